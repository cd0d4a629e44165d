"""``tippedisk simulate``: one run of any registered model -> a netCDF dataset."""

from __future__ import annotations

import dataclasses

from .. import defaults
from .common import add_output, finite_float, positive_int, writable
from .registry import command


def _arguments(p) -> None:
    p.add_argument("--model", default="ode-euler",
                   help="model name, e.g. ode-euler (ode1), ode-quaternion (ode2), Moreau Models 1-10: m1 ... m10")
    p.add_argument("--t-end", type=finite_float, default=5.0, help="end time [s] (default 5)")
    add_output(p)
    p.add_argument("--dt-output", type=finite_float, help="output sampling of ODE models [s] (default 1e-3)")
    p.add_argument("--tol", type=finite_float, help=f"tolerance: heyoka {defaults.TAYLOR_TOL:g} (ODE), prox stopping "
                                                    f"{defaults.MOREAU_TOL:g} (Moreau)")
    p.add_argument("--fall-angle", type=finite_float,
                   help=f"tilt above the table [rad] that ends a run (default {defaults.FALL_ANGLE:g}; quaternion "
                        "Moreau models: 0, no fall check)")
    mor = p.add_argument_group("Moreau time stepping (models m1 ... m10; Sect. 4, 6 defaults)")
    mor.add_argument("--dt", type=finite_float, help=f"time step [s] (default {defaults.MOREAU_DT:g})")
    mor.add_argument("--store-every", type=positive_int, help="store every n-th step (default: 1 ms sampling)")
    mor.add_argument("--max-iter", type=positive_int,
                     help=f"prox iteration limit per step (default {defaults.MOREAU_MAX_ITER})")
    mor.add_argument("--normalize-quaternion", action="store_true", help="normalise p after each step")
    mor.add_argument("--progress", action="store_true", default=None, help="always show a progress bar")
    init = p.add_argument_group("initial state (Table 3 defaults)")
    for name, unit, default in (("alpha", "rad", 0.0), ("beta", "rad", "pi/2"), ("gamma0", "rad", "-pi/2 + 0.1"),
                                ("alpha-dot", "rad/s", 40.0), ("beta-dot", "rad/s", 0.0),
                                ("gamma-dot", "rad/s", "-alpha_dot cos(beta)")):
        init.add_argument(f"--{name}", type=finite_float, help=f"[{unit}] (default {default})")
    phys = p.add_argument_group("parameters (Tables 1-2, Sect. 6 defaults)")
    for name, help_text in (("mu", "friction coefficient (0.3)"), ("eps", "smoothing of (2.29) [m/s] (0.1)"),
                            ("radius", "disk radius r [m] (0.045)"), ("e", "eccentricity [m] (2.5e-3)"),
                            ("mass", "mass [kg] (0.435)"), ("gravity", "[m/s^2] (9.81)")):
        phys.add_argument(f"--{name}", type=finite_float, help=help_text)


@command("simulate", "simulate the tippedisk and write a netCDF dataset", _arguments)
def simulate(args) -> int:
    from .. import results
    from ..parameters import Disk, Friction, InitialState, Setup
    from ..solvers import resolve
    from ..solvers import simulate as run_model

    info = resolve(args.model)
    disk_kw = {k: v for k, v in (("r", args.radius), ("e", args.e), ("m", args.mass)) if v is not None}
    fric_kw = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    init_kw = {k: v for k, v in (("alpha", args.alpha), ("beta", args.beta), ("gamma", args.gamma0),
                                 ("alpha_dot", args.alpha_dot), ("beta_dot", args.beta_dot),
                                 ("gamma_dot", args.gamma_dot)) if v is not None}
    setup = Setup(disk=dataclasses.replace(Disk(), **disk_kw), friction=dataclasses.replace(Friction(), **fric_kw),
                  **({"gravity": args.gravity} if args.gravity is not None else {}))
    options = {k: v for k, v in (("dt_output", args.dt_output), ("tol", args.tol),
                                 ("fall_angle", args.fall_angle), ("dt", args.dt), ("store_every", args.store_every),
                                 ("max_iter", args.max_iter), ("progress", args.progress),
                                 ("normalize_quaternion", args.normalize_quaternion or None)) if v is not None}
    output = writable(args.output)
    if "checkpoint" in info.options:  # a long run killed midway resumes when the command is repeated
        options["checkpoint"] = str(output) + ".checkpoint.npz"
    ds = run_model(info.name, args.t_end, setup=setup, initial=InitialState(**init_kw), **options)
    results.save(ds, output)
    print(f"{output}: {ds.attrs['model']} {ds.attrs['status']}: {ds.attrs['message']}")
    return 1 if ds.attrs["status"] in ("nonfinite", "not_converged") else 0

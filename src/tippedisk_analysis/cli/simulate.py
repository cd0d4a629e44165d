"""``tippedisk simulate``: one run of any registered model -> a netCDF dataset."""

from __future__ import annotations

import argparse

import dataclasses

from .. import defaults
from ..files import remove_stale_parts, show
from .common import add_disk, add_output, disk_from_args, finite_float, output_path, positive_int, tolerance
from .registry import command

INITIAL = (  # option, InitialState field, help
    ("alpha", "alpha", "Euler angle alpha(0), precession [rad] (default 0)"),
    ("beta", "beta", "Euler angle beta(0), inclination [rad] (default pi/2: upright)"),
    ("gamma0", "gamma", "Euler angle gamma(0), rotation about the normal [rad] (default -pi/2 + 0.1)"),
    ("alpha-dot", "alpha_dot", "rate alpha_dot(0) = spin Omega [rad/s] (default 40)"),
    ("beta-dot", "beta_dot", "rate beta_dot(0) [rad/s] (default 0)"),
    ("gamma-dot", "gamma_dot", "rate gamma_dot(0) [rad/s] (default -alpha_dot cos(beta): no spin about the normal)"),
)

NUMERICAL_FAILURES = ("nonfinite", "not_converged", "zeno", "failed")
"""Statuses of a run that the numerics ended (exit 1); fell and lift_off are physical endings (exit 0)."""


def _arguments(p) -> None:
    p.add_argument("--model", default="ode-euler",
                   help="model name, e.g. ode-euler (ode1), ode-quaternion (ode2), Moreau Models 1-10: m1 ... m10, "
                        "the event-driven set-valued Coulomb model hybrid-euler (h1)")
    p.add_argument("--t-end", type=finite_float, default=5.0, help="end time [s] (default 5)")
    add_output(p)
    p.add_argument("--dt-output", type=finite_float, help="output sampling of ODE models [s] (default 1e-3)")
    p.add_argument("--tol", type=tolerance, help=f"tolerance: heyoka {defaults.TAYLOR_TOL:g} (ODE), prox stopping "
                                                    f"{defaults.MOREAU_TOL:g} (Moreau)")
    p.add_argument("--fall-angle", type=finite_float,
                   help=f"tilt above the table [rad] that ends a run (default {defaults.FALL_ANGLE:g}; quaternion "
                        "Moreau models: 0, no fall check)")
    mor = p.add_argument_group("Moreau time stepping (models m1 ... m10; Sect. 4, 6 defaults)")
    mor.add_argument("--dt", type=finite_float, help=f"time step [s] (default {defaults.MOREAU_DT:g})")
    mor.add_argument("--store-every", type=positive_int, help="store every n-th step (default: 1 ms sampling)")
    mor.add_argument("--max-iter", type=positive_int,
                     help=f"prox iteration limit per step (default {defaults.MOREAU_MAX_ITER})")
    mor.add_argument("--normalize-quaternion", action=argparse.BooleanOptionalAction, default=None,
                     help="normalise p after each step (quaternion models m2, m4, ..., m10; default on, as Sect. 3.2 "
                          "prescribes; --no-normalize-quaternion for the drift study)")
    mor.add_argument("--progress", action="store_true", default=None, help="always show a progress bar")
    add_start_and_physics(p, "initial state (Table 3 defaults; z and the velocity of G close the contact at C1 "
                             "without slip)", "friction and gravity (Sect. 6 defaults)")


def add_start_and_physics(p, initial_title: str, physics_title: str) -> None:
    """The initial-state options (INITIAL), friction and gravity, and the disk's options, in groups of these titles."""
    init = p.add_argument_group(initial_title)
    for option, _, help_text in INITIAL:
        init.add_argument(f"--{option}", type=finite_float, help=help_text)
    phys = p.add_argument_group(physics_title)
    phys.add_argument("--mu", type=finite_float, help="friction coefficient [-] (0.3)")
    phys.add_argument("--eps", type=finite_float, help="smoothing of (2.29) [m/s] (0.1)")
    phys.add_argument("--gravity", type=finite_float, help="gravitational acceleration [m/s^2] (9.81)")
    add_disk(p)


def _interrupted(checkpoint: str | None) -> str:
    if checkpoint is None:
        return "interrupted; nothing stored (ODE runs keep no checkpoint: rerun to start again)"
    from ..solvers.moreau.checkpoint import stored_progress

    stored = stored_progress(checkpoint)
    if stored is None:
        return (f"interrupted; nothing stored yet (a checkpoint is written every {defaults.CHECKPOINT_SECONDS:g} s "
                "of work): rerun to start again")
    return (f"interrupted; checkpoint at t = {stored[0]:.6g} of {stored[1]:g} s stored in '{show(checkpoint)}'; "
            "rerun the same command to resume")


@command("simulate", "simulate the tippedisk and write a netCDF dataset", _arguments)
def simulate(args) -> int:
    from .. import results
    from ..errors import Interrupted
    from ..parameters import Friction, InitialState, Setup
    from ..solvers import resolve
    from ..solvers import simulate as run_model
    from ..solvers.moreau.checkpoint import CheckpointError

    info = resolve(args.model)
    fric_kw = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    init_kw = {field: getattr(args, option.replace("-", "_")) for option, field, _ in INITIAL
               if getattr(args, option.replace("-", "_")) is not None}
    setup = Setup(disk=disk_from_args(args), friction=dataclasses.replace(Friction(), **fric_kw),
                  **({"gravity": args.gravity} if args.gravity is not None else {}))
    options = {k: v for k, v in (("dt_output", args.dt_output), ("tol", args.tol),
                                 ("fall_angle", args.fall_angle), ("dt", args.dt), ("store_every", args.store_every),
                                 ("max_iter", args.max_iter), ("progress", args.progress),
                                 ("normalize_quaternion", args.normalize_quaternion)) if v is not None}
    initial = InitialState(**init_kw)
    output = output_path(args)
    checkpoint = None
    if "checkpoint" in info.options:  # a long run killed midway resumes when the command is repeated
        checkpoint = options["checkpoint"] = str(output) + ".checkpoint.npz"
        remove_stale_parts(checkpoint)  # temporary checkpoint files of a run killed with kill -9
    try:
        try:
            ds = run_model(info.name, args.t_end, setup=setup, initial=initial, **options)
        except CheckpointError:
            if not args.overwrite:
                raise
            from pathlib import Path

            Path(checkpoint).unlink(missing_ok=True)  # --overwrite: discard the other run's or a damaged checkpoint
            ds = run_model(info.name, args.t_end, setup=setup, initial=initial, **options)
    except KeyboardInterrupt:
        raise Interrupted(_interrupted(checkpoint)) from None
    results.save(ds, output)
    print(f"{show(output)}: {ds.attrs['model']} {ds.attrs['status']}: {ds.attrs['message']}")
    return 1 if ds.attrs["status"] in NUMERICAL_FAILURES else 0

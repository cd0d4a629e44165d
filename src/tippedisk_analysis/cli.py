"""Command line: ``tippedisk simulate | plot | study | stability-map | poincare | outcome-map | bifurcation``.

Thin: parse, call the library, print one line.

Bad input (a TippediskError) prints one line on stderr and exits with status 2;
nothing is written then. A run that ended with a numerical failure exits with 1.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .errors import ParameterError, TippediskError
from .ranges import parse_range, range_values


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit status 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _add_simulate(sub) -> None:
    p = sub.add_parser("simulate", help="simulate the tippedisk and write a netCDF dataset")
    p.add_argument("--model", default="ode-euler",
                   help="model name, e.g. ode-euler (ode1), ode-quaternion (ode2), Moreau Models 1-10: m1 ... m10")
    p.add_argument("--t-end", type=_finite_float, default=5.0, help="end time [s] (default 5)")
    p.add_argument("--output", "-o", required=True, help="netCDF file to write")
    p.add_argument("--dt-output", type=_finite_float, help="output sampling [s] (default 1e-3)")
    p.add_argument("--tol", type=_finite_float, help="tolerance: heyoka 1e-14 (ODE), prox stopping 1e-8 (Moreau)")
    p.add_argument("--fall-angle", type=_finite_float, help="tilt above the table [rad] that ends a run (default 0.1)")
    mor = p.add_argument_group("Moreau time stepping (models m1 ... m10; Sect. 4, 6 defaults)")
    mor.add_argument("--dt", type=_finite_float, help="time step [s] (default 1e-5)")
    mor.add_argument("--store-every", type=int, help="store every n-th step (default: 1 ms sampling)")
    mor.add_argument("--max-iter", type=int, help="prox iteration limit per step (default 1000)")
    mor.add_argument("--normalize-quaternion", action="store_true", help="normalise p after each step")
    mor.add_argument("--progress", action="store_true", default=None, help="always show a progress bar")
    init = p.add_argument_group("initial state (Table 3 defaults)")
    for name, default in (("alpha", 0.0), ("beta", "pi/2"), ("gamma0", "-pi/2 + 0.1"), ("alpha-dot", 40.0),
                          ("beta-dot", 0.0), ("gamma-dot", "-alpha_dot cos(beta)")):
        init.add_argument(f"--{name}", type=_finite_float, help=f"[rad or rad/s] (default {default})")
    phys = p.add_argument_group("parameters (Tables 1-2, Sect. 6 defaults)")
    for name, help_text in (("mu", "friction coefficient (0.3)"), ("eps", "smoothing of (2.29) [m/s] (0.1)"),
                            ("radius", "disk radius r [m] (0.045)"), ("e", "eccentricity [m] (2.5e-3)"),
                            ("mass", "mass [kg] (0.435)"), ("gravity", "[m/s^2] (9.81)")):
        phys.add_argument(f"--{name}", type=_finite_float, help=help_text)


def _simulate(args) -> int:
    import dataclasses

    from . import results
    from .parameters import Disk, Friction, InitialState, Setup
    from .solvers import resolve, simulate

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
    output = _writable(args.output)
    if "checkpoint" in info.options:  # a long run killed midway resumes when the command is repeated
        options["checkpoint"] = str(output) + ".checkpoint.npz"
    ds = simulate(info.name, args.t_end, setup=setup, initial=InitialState(**init_kw), **options)
    results.save(ds, output)
    print(f"{output}: {ds.attrs['model']} {ds.attrs['status']}: {ds.attrs['message']}")
    return 1 if ds.attrs["status"] in ("nonfinite", "not_converged") else 0


def _add_plot(sub) -> None:
    p = sub.add_parser("plot", help="draw a stored dataset as a PNG figure")
    p.add_argument("dataset", help="netCDF file written by tippedisk")
    p.add_argument("--output", "-o", help="PNG file (default: the dataset name with .png)")


def _plot(args) -> int:
    from . import plotting, results

    ds = results.load(args.dataset)
    output = _writable(args.output or str(Path(args.dataset).with_suffix(".png")))
    formats = plotting.file_formats()
    if output.suffix.lower().lstrip(".") not in formats:
        raise ParameterError(f"cannot draw to {output.suffix or 'a file without suffix'!r}; give --output with one of "
                             f"{', '.join('.' + f for f in sorted(formats))}")
    plotting.plot_dataset(ds, output)
    print(f"{output}: {ds.attrs['kind']} figure")
    return 0


def _writable(path: str) -> Path:
    path = Path(path)
    if not path.parent.is_dir():
        raise ParameterError(f"directory {str(path.parent)!r} does not exist; create it or choose another --output")
    return path


def _add_study(sub) -> None:
    p = sub.add_parser("study", help="run a study script from studies/ (dataset + figure)")
    p.add_argument("name", nargs="?", help="study name (see --list)")
    p.add_argument("--list", action="store_true", help="print the study names, one per line")
    p.add_argument("--output-dir", default="output", help="folder for the dataset and figure (default output/)")


def _study(args) -> int:
    from . import studies

    if args.list:
        print("\n".join(studies.names()))
        return 0
    if not args.name:
        raise ParameterError("give a study name or --list")
    studies.run(args.name, args.output_dir)
    return 0


def _add_stability_map(sub) -> None:
    p = sub.add_parser("stability-map", help="eigenvalue stability of the spinning solutions over Omega and eps")
    p.add_argument("--omega", required=True, help="spin rates START:STOP:N [rad/s] (N values, ends included; "
                   "write --omega=-50:50:101 for a negative START)")
    p.add_argument("--eps", required=True, help="smoothing eps of (2.29) START:STOP:N [m/s]")
    p.add_argument("--mu", help="friction coefficient START:STOP:N or one value (default 0.3, not a dimension)")
    p.add_argument("--e", help="eccentricity START:STOP:N or one value [m] (default 2.5e-3, not a dimension)")
    p.add_argument("--output", "-o", required=True, help="netCDF file to write")


def _stability_map(args) -> int:
    from . import results
    from .analysis import maps

    ranges = {name: range_values(getattr(args, name), name) if getattr(args, name) is not None else None
              for name in ("omega", "eps", "mu", "e")}
    output = _writable(args.output)
    ds = maps.stability_map(ranges["omega"], ranges["eps"], mu=ranges["mu"], e=ranges["e"])
    results.save(ds, output)
    print(f"{output}: stability map {ds.attrs['message']}")
    return 0


COMMANDS = {"simulate": (_add_simulate, _simulate), "plot": (_add_plot, _plot), "study": (_add_study, _study),
            "stability-map": (_add_stability_map, _stability_map)}


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="tippedisk", description="Simulate and analyse the tippedisk (Sailer et al. 2020).")
    from . import __version__

    parser.add_argument("--version", action="version", version=f"tippedisk_analysis {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add, _ in COMMANDS.values():
        add(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return COMMANDS[args.command][1](args)
    except TippediskError as exc:
        print(f"tippedisk {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"tippedisk {args.command}: error: not enough memory for this request; use fewer grid points "
              "or a shorter run", file=sys.stderr)
        return 2


# --- trajectory analysis: Poincaré sections, outcome maps, bifurcation diagrams (issue 5) ---


def _range(name: str):
    """argparse type for ``--name START:STOP:N``."""

    def parse(text: str):
        try:
            return parse_range(text, name)
        except ParameterError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = f"--{name} range"
    return parse


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive integer")
    return value


def _add_initial_and_friction(p) -> None:
    p.add_argument("--omega", type=_finite_float, help="initial spin Omega = alpha_dot(0) [rad/s] (Table 3: 40)")
    p.add_argument("--dgamma0", type=_finite_float, help="gamma(0) = -pi/2 + dgamma0 [rad] (Table 3: 0.1)")
    p.add_argument("--mu", type=_finite_float, help="friction coefficient (0.3)")
    p.add_argument("--eps", type=_finite_float, help="smoothing of (2.29) [m/s] (0.1)")
    p.add_argument("--model", default="ode-euler", help="ode-euler (ode1) or ode-quaternion (ode2)")
    p.add_argument("--tol", type=_finite_float, default=1e-14, help="integrator tolerance (default 1e-14)")
    p.add_argument("--t-end", type=_finite_float, default=10.0, help="end time [s] (default 10)")
    p.add_argument("--t-transient", type=_finite_float, default=0.0, help="skip crossings before this time [s]")
    p.add_argument("--max-crossings", type=_positive_int, help="stop after this many crossings")
    p.add_argument("--section", default="beta_dot=0",
                   help="NAME=LEVEL, e.g. beta_dot=0 (default), gamma=pi/2, 'alpha mod 2pi=0'")
    p.add_argument("--direction", default="positive", choices=("positive", "negative", "any"),
                   help="crossing direction of NAME (default positive)")
    p.add_argument("--output", "-o", required=True, help="netCDF file to write")


def _setup_initial(args):
    import dataclasses

    from .parameters import Friction, InitialState, Setup

    fric = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    init = {}
    if getattr(args, "omega", None) is not None:
        init["alpha_dot"] = args.omega
    if args.dgamma0 is not None:
        init["gamma"] = -0.5 * math.pi + args.dgamma0
    return Setup(friction=dataclasses.replace(Friction(), **fric)), InitialState(**init)


def _add_poincare(sub) -> None:
    p = sub.add_parser("poincare", help="Poincaré section of one trajectory (heyoka events) -> netCDF")
    _add_initial_and_friction(p)


def _poincare(args) -> int:
    from . import results
    from .analysis.poincare import poincare_section

    setup, initial = _setup_initial(args)
    output = _writable(args.output)
    ds = poincare_section(args.section, direction=args.direction, model=args.model, setup=setup, initial=initial,
                          t_transient=args.t_transient, t_end=args.t_end, max_crossings=args.max_crossings,
                          tol=args.tol)
    results.save(ds, output)
    print(f"{output}: section {ds.attrs['section']} ({ds.attrs['direction']}): {ds.attrs['message']}")
    return 1 if ds.attrs["status"] == "nonfinite" else 0


def _add_outcome_map(sub) -> None:
    p = sub.add_parser("outcome-map", help="classify runs over a grid of (Omega, eps, ...) -> netCDF")
    p.add_argument("--omega", type=_range("omega"), required=True, help="START:STOP:N initial spin Omega [rad/s] "
                   "(N values, ends included; write --omega=-50:-10:5 for a negative START)")
    p.add_argument("--eps", type=_range("eps"), required=True, help="START:STOP:N smoothing velocity eps [m/s]")
    p.add_argument("--mu", type=_range("mu"), help="START:STOP:N friction coefficient (default 0.3)")
    p.add_argument("--e", type=_range("e"), help="START:STOP:N eccentricity [m] (default 2.5e-3)")
    p.add_argument("--dgamma0", type=_range("dgamma0"), help="START:STOP:N gamma(0) + pi/2 [rad] (default 0.1)")
    p.add_argument("--t-end", type=_finite_float, default=5.0, help="length of each run [s] (default 5)")
    p.add_argument("--window", type=_finite_float, help="classification window at the end [s] (default t_end/5)")
    p.add_argument("--tol", type=_finite_float, default=1e-10, help="integrator tolerance (default 1e-10)")
    p.add_argument("--fall-angle", type=_finite_float, default=0.1, help="tilt that ends a run [rad] (0.1)")
    p.add_argument("--chunk-size", type=_positive_int, default=128, help="grid points per chunk (default 128)")
    p.add_argument("--batch-size", type=_positive_int, default=4, help="SIMD lanes per batch: 1, 2, 4, 8, 16 (4)")
    p.add_argument("--threads", type=_positive_int, help="threads without --scheduler (default: cores)")
    p.add_argument("--scheduler", help="dask.distributed scheduler address, or local:N for a local cluster")
    p.add_argument("--output", "-o", required=True, help="netCDF file (chunks go to OUTPUT.chunks/)")


def _outcome_map(args) -> int:
    from .analysis.outcome_map import outcome_map

    ranges = {k: getattr(args, k) for k in ("omega", "eps", "mu", "e", "dgamma0") if getattr(args, k) is not None}
    output = _writable(args.output)
    ds = outcome_map(ranges, output=output, scheduler=args.scheduler, threads=args.threads, t_end=args.t_end,
                     window=args.window, tol=args.tol, fall_angle=args.fall_angle, chunk_size=args.chunk_size,
                     batch_size=args.batch_size)
    print(f"{output}: {ds.attrs['message']}")
    return 0


def _add_bifurcation(sub) -> None:
    p = sub.add_parser("bifurcation", help="brute-force bifurcation diagram: a quantity at crossings vs Omega")
    p.add_argument("--omega", type=_range("omega"), required=True, help="START:STOP:N initial spin Omega [rad/s]")
    p.add_argument("--quantity", default="gamma", help="quantity recorded at the crossings (default gamma)")
    p.add_argument("--dgamma0", type=_finite_float, help="gamma(0) = -pi/2 + dgamma0 [rad] (Table 3: 0.1)")
    p.add_argument("--mu", type=_finite_float, help="friction coefficient (0.3)")
    p.add_argument("--eps", type=_finite_float, help="smoothing of (2.29) [m/s] (0.1)")
    p.add_argument("--tol", type=_finite_float, default=1e-12, help="integrator tolerance (default 1e-12)")
    p.add_argument("--t-end", type=_finite_float, default=10.0, help="end time of each run [s] (default 10)")
    p.add_argument("--t-transient", type=_finite_float, default=5.0, help="transient skipped [s] (default 5)")
    p.add_argument("--max-crossings", type=_positive_int, default=50, help="crossings per Omega (default 50)")
    p.add_argument("--section", default="beta_dot=0", help="NAME=LEVEL (default beta_dot=0)")
    p.add_argument("--direction", default="positive", choices=("positive", "negative", "any"))
    p.add_argument("--output", "-o", required=True, help="netCDF file to write")


def _bifurcation(args) -> int:
    from . import results
    from .analysis.bifurcation import bifurcation_diagram

    setup, initial = _setup_initial(args)
    output = _writable(args.output)
    ds = bifurcation_diagram(args.omega, quantity=args.quantity, section=args.section, direction=args.direction,
                             setup=setup, initial=initial, t_transient=args.t_transient, t_end=args.t_end,
                             max_crossings=args.max_crossings, tol=args.tol)
    results.save(ds, output)
    print(f"{output}: {ds.attrs['message']}")
    return 0


# Trajectory analysis (issue 5): registered here, after the core commands.
COMMANDS.update({"poincare": (_add_poincare, _poincare), "outcome-map": (_add_outcome_map, _outcome_map),
                 "bifurcation": (_add_bifurcation, _bifurcation)})


if __name__ == "__main__":
    sys.exit(main())

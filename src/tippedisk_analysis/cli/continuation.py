"""``tippedisk continue``: branches of spinning solutions in one parameter, and curves of their Hopf and
zero-eigenvalue points in two parameters."""

from __future__ import annotations

from ..errors import ParameterError
from ..files import show
from .common import add_disk, add_output, disk_from_args, disk_options_given, finite_float, output_path, positive_int
from .registry import command

PARAMETER_HELP = "omega (spin rate), eps, mu, e (A, B, C about G fixed), inertia (scale of A, B, C)"


def _arguments(p) -> None:
    one = p.add_argument_group("a branch in one parameter")
    one.add_argument("--branch", default="inverted", choices=("inverted", "noninverted"),
                     help="family of stationary solutions (Fig. 6; default inverted)")
    one.add_argument("--parameter", default="omega", help=f"continuation parameter: {PARAMETER_HELP} (default omega)")
    one.add_argument("--from", dest="start", type=finite_float,
                     help="start value (omega: required; other parameters: default the Table 1-3 value)")
    one.add_argument("--to", dest="stop", type=finite_float, help="end value of the parameter")
    two = p.add_argument_group("from a point of a continuation dataset")
    two.add_argument("--from-point", help="FILE:LABEL, a special point of a continuation dataset, e.g. c.nc:HOPF1; "
                                          "with --parameters A,B: the curve of that Hopf or zero-eigenvalue point "
                                          "in two parameters; with --parameter P --to X: a branch in P through it")
    two.add_argument("--parameters", help="two parameters of a curve, e.g. omega,eps")
    two.add_argument("--bounds", action="append", default=[], metavar="NAME=LOW:HIGH",
                     help="box the curve stays in (repeatable), e.g. --bounds eps=0.1:0.4")
    fixed = p.add_argument_group("fixed parameters (Tables 1-3, Sect. 6 defaults)")
    fixed.add_argument("--omega", type=finite_float, help="spin rate [rad/s] when omega is not continued "
                                                          "(not with --from-point: the point fixes it)")
    fixed.add_argument("--eps", type=finite_float, help="smoothing of (2.29) [m/s] (0.1)")
    fixed.add_argument("--mu", type=finite_float, help="friction coefficient (0.3)")
    fixed.add_argument("--e", type=finite_float, help="eccentricity [m] (default: the disk's, Table 2: 2.5e-3; A, B, "
                                                      "C about G held fixed)")
    step = p.add_argument_group("step control (scaled arclength)")
    step.add_argument("--ds-max", type=finite_float, help="largest step (default 0.2 in omega, else 0.05)")
    step.add_argument("--max-points", type=positive_int, default=500, help="points per direction (default 500)")
    add_output(p)
    add_disk(p, e_option=False)


def _bounds(items: list[str]) -> dict:
    out = {}
    for item in items:
        name, _, span = item.partition("=")
        low, _, high = span.partition(":")
        try:
            out[name.strip()] = (float(low), float(high))
        except ValueError:
            raise ParameterError(f"--bounds {item!r} is not NAME=LOW:HIGH; give e.g. --bounds eps=0.1:0.4") from None
        if not out[name.strip()][0] < out[name.strip()][1]:
            raise ParameterError(f"--bounds {item!r}: give LOW < HIGH")
    return out


@command("continue", "continuation of the spinning solutions: branches, Hopf and zero-eigenvalue curves", _arguments)
def continue_(args) -> int:
    import dataclasses

    from .. import results
    from ..analysis import spin_continuation
    from ..dynamics import continuation
    from ..parameters import Friction, Setup

    output = output_path(args)
    friction = {k: v for k, v in (("eps", args.eps), ("mu", args.mu)) if v is not None}
    options = {"max_points": args.max_points}
    if args.ds_max is not None and not args.ds_max > 0:
        raise ParameterError(f"--ds-max {args.ds_max:g}: give a positive step, e.g. --ds-max 0.05")
    if args.from_point:
        path, _, label = args.from_point.rpartition(":")
        if not path or not label:
            raise ParameterError(f"--from-point {args.from_point!r} is not FILE:LABEL; give e.g. c.nc:HOPF1")
        given = [f"--{name.replace('_', '-')}" for name in ("eps", "mu", "omega", "start")
                 if getattr(args, name) is not None] + (["--branch"] if args.branch != "inverted" else []) + \
            disk_options_given(args)
        if given:
            raise ParameterError(f"{', '.join(given).replace('--start', '--from')} with --from-point: the point's "
                                 "dataset fixes the branch and the parameters; drop them")
        if args.parameters is not None and args.stop is not None:
            raise ParameterError("--to with --parameters: a curve is bounded by --bounds NAME=LOW:HIGH; give "
                                 "--parameter P --to X for a branch through the point instead")
        source = results.load(path)
        if args.parameters is None and args.stop is not None:  # a branch in --parameter through the point
            options["ds_max"] = args.ds_max or (0.2 if args.parameter == "omega" else 0.05)
            ds = spin_continuation.continue_from_point(
                source, label, args.parameter, args.stop,
                options=continuation.Options(ds=min(0.02, options["ds_max"]), **options))
        else:
            parameters = [s.strip() for s in (args.parameters or "omega,eps").split(",")]
            options["ds_max"] = args.ds_max or 0.05
            ds = spin_continuation.continue_curve(source, label, parameters, bounds=_bounds(args.bounds),
                                                  options=continuation.Options(ds=min(0.02, options["ds_max"]),
                                                                               **options))
    else:
        if args.parameters or args.bounds:
            raise ParameterError("--parameters and --bounds belong to --from-point (curves); for a branch give "
                                 "--parameter, --from and --to")
        if args.stop is None:
            raise ParameterError("give --to (the end value of the continuation parameter)")
        setup = Setup(disk=disk_from_args(args), friction=dataclasses.replace(Friction(), **friction))
        options["ds_max"] = args.ds_max or (0.2 if args.parameter == "omega" else 0.05)
        ds = spin_continuation.continue_branch(args.branch, args.parameter, args.start, args.stop, setup=setup,
                                               omega=args.omega,
                                               options=continuation.Options(ds=min(0.02, options["ds_max"]),
                                                                            **options))
    results.save(ds, output)
    print(f"{show(output)}: {ds.attrs['message']}")
    return 0 if ds.attrs["status"] in continuation.RESULTS else 1

"""``tippedisk basins`` and ``tippedisk basin-fractions``: attractors found by recurrences (analysis/basins.py).

* ``basins``: basins of attraction over one or two initial values (ranges START:STOP:N) at fixed
  parameters, e.g. ``--omega 40 --dgamma0 -3.1:3.1:256 --beta0 1.2:1.9:256``;
* ``basin-fractions``: basin fractions of sampled initial conditions (ranges LOW:HIGH) continued over
  an initial value or a parameter, e.g. ``--over omega=10:80:36 --dgamma0 -3.1:3.1 --beta0 1.2:1.9``.
Both are resumable (chunks in OUTPUT.chunks/) and run on threads or a dask cluster (--scheduler).
"""

from __future__ import annotations

import re

from .. import defaults
from ..errors import ParameterError
from ..files import show
from ..ranges import parse_range
from .common import add_disk, add_output, disk_from_args, finite_float, output_path, positive_int, scheduler_type, \
    tolerance, undecided_hint
from .registry import command

INITIAL_HELP = {"omega": "initial spin Omega [rad/s] (Table 3: 40)", "beta0": "initial beta [rad] (pi/2)",
                "dgamma0": "gamma(0) + pi/2 [rad] (0.1)", "beta_dot0": "initial beta_dot [rad/s] (0)",
                "gamma_dot0": "initial gamma_dot [rad/s] (-Omega cos beta0)"}


def _common(p) -> None:
    p.add_argument("--eps", type=finite_float, help="smoothing of (2.29) [m/s] (0.1)")
    p.add_argument("--mu", type=finite_float, help="friction coefficient (0.3)")
    p.add_argument("--e", type=finite_float, help="eccentricity [m] (default: the disk's, Table 2: 2.5e-3). Held "
                   "fixed: A, B, C about G (--disk table2 / given), or the hole geometry but its offset b "
                   "(--disk geometry)")
    p.add_argument("--t-end", type=finite_float, default=60.0, help="maximum horizon of each run [s] (default 60)")
    p.add_argument("--dt", type=finite_float, help="sampling interval of the recurrence grid [s] (default 0.05)")
    p.add_argument("--tol", type=tolerance, default=defaults.MAP_TOL,
                   help=f"integrator tolerance (default {defaults.MAP_TOL:g})")
    p.add_argument("--fall-angle", type=finite_float, default=defaults.FALL_ANGLE,
                   help=f"tilt that ends a run [rad] (default {defaults.FALL_ANGLE:g})")
    p.add_argument("--chunk-size", type=positive_int, help="runs per chunk (default 256)")
    p.add_argument("--batch-size", type=positive_int, default=defaults.BATCH_SIZE,
                   help=f"SIMD lanes per batch: 1, 2, 4, 8, 16 (default {defaults.BATCH_SIZE})")
    p.add_argument("--threads", type=positive_int, help="threads without --scheduler (default: cores)")
    p.add_argument("--scheduler", type=scheduler_type,
                   help="dask.distributed scheduler address (tcp://host:8786), or local:N for N local processes")
    add_output(p, "netCDF file (chunks go to OUTPUT.chunks/; the same command resumes them)")
    add_disk(p, e_option=False)


def _options(args, swept: str | None = None, first: float | None = None) -> dict:
    """Library options of both commands; ``swept``: the parameter basin-fractions continues over (its first
    value ``first`` completes a --disk given)."""
    from ..parameters import Setup, to_dict

    e_swept = swept == "e"
    disk = disk_from_args(args, sweep_e=first if e_swept else None, e_swept=e_swept)
    opts = {"t_end": args.t_end, "tol": args.tol, "fall_angle": args.fall_angle, "batch_size": args.batch_size,
            "parameters": {k: getattr(args, k) for k in ("eps", "mu", "e") if getattr(args, k) is not None},
            "setup": to_dict(Setup(disk=disk))}
    if args.chunk_size is not None:
        opts["chunk_size"] = args.chunk_size
    if args.dt is not None:
        opts["recurrence"] = {"dt": args.dt}
    return opts


def _negative_ranges(p) -> None:
    """Let values such as -3.1:3.1:256 follow an option (argparse takes only plain negative numbers for values)."""
    p._negative_number_matcher = re.compile(r"^-\d*\.?\d+([eE][-+]?\d+)?(:.*)?$")


def _basins_arguments(p) -> None:
    _negative_ranges(p)
    for name, text in INITIAL_HELP.items():
        p.add_argument(f"--{name}", help=f"{text}: one value or START:STOP:N (one or two ranges)")
    _common(p)


@command("basins", "basins of attraction over one or two initial values (recurrences) -> netCDF", _basins_arguments)
def basins(args) -> int:
    from ..analysis import basins as bs

    axes, fixed = {}, {}
    for name in bs.INITIAL:
        text = getattr(args, name)
        if text is None:
            continue
        start, stop, n = parse_range(text, name)
        if n == 1:
            fixed[name] = start
        else:
            axes[name] = (start, stop, n)
    output = output_path(args)
    ds = bs.basins(axes, initial=fixed, output=output, overwrite=args.overwrite, scheduler=args.scheduler,
                   threads=args.threads, **_options(args))
    print(f"{show(output)}: {ds.attrs['message']}{undecided_hint(ds, args.t_end)}")
    return 1 if ds.attrs["status"] != "completed" else 0


def _sampled(text: str, name: str) -> tuple[float, float] | float:
    parts = str(text).split(":")
    try:
        values = [float(v) for v in parts]
    except ValueError:
        raise ParameterError(f"--{name} {text!r} is not a number or LOW:HIGH") from None
    if len(values) == 1:
        return values[0]
    if len(values) != 2 or not values[0] <= values[1]:
        raise ParameterError(f"--{name} {text!r}: give one value or LOW:HIGH with LOW <= HIGH (sampled uniformly)")
    return values[0], values[1]


def _fractions_arguments(p) -> None:
    _negative_ranges(p)
    p.add_argument("--over", required=True, help="NAME=START:STOP:N, the continued initial value or parameter: "
                                                 "omega, beta0, ..., eps, mu, e (e.g. omega=10:80:36)")
    p.add_argument("--samples", type=positive_int, default=200, help="initial conditions per value (default 200)")
    p.add_argument("--seed", type=int, default=0, help="seed of the uniform sampling (default 0)")
    for name, text in INITIAL_HELP.items():
        p.add_argument(f"--{name}", help=f"{text}: one value, or LOW:HIGH sampled uniformly")
    _common(p)


@command("basin-fractions", "basin fractions of sampled initial conditions continued over Omega, eps, ... -> netCDF",
         _fractions_arguments)
def basin_fractions(args) -> int:
    from ..analysis import basins as bs

    name, sep, text = str(args.over).partition("=")
    if not sep:
        raise ParameterError(f"--over {args.over!r}: give NAME=START:STOP:N, e.g. omega=10:80:36")
    values = parse_range(text, name)
    ranges, fixed = {}, {}
    for n in bs.INITIAL:
        if getattr(args, n) is None:
            continue
        v = _sampled(getattr(args, n), n)
        (ranges if isinstance(v, tuple) else fixed)[n] = v
    if not ranges:
        raise ParameterError("give at least one sampled range LOW:HIGH, e.g. --dgamma0 -3.1:3.1 --beta0 1.2:1.9")
    opts = _options(args, swept=name, first=values[0])
    output = output_path(args)
    ds = bs.basin_fractions(name, values, ranges, samples=args.samples, seed=args.seed, initial=fixed, output=output,
                            overwrite=args.overwrite, scheduler=args.scheduler, threads=args.threads, **opts)
    print(f"{show(output)}: {ds.attrs['message']}{undecided_hint(ds, args.t_end)}")
    return 1 if ds.attrs["status"] != "completed" else 0

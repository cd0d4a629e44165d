"""``tippedisk outcome-map``: classify runs over a grid of (Omega, eps[, mu, e, dgamma0]); resumable.

By default each run is assigned to the attractor it reaches (``--classify attractors``, analysis/basins.py);
``--classify rules`` keeps the rule-based classification of fixed-length runs (analysis/outcome_map.py)."""

from __future__ import annotations

from .. import defaults
from ..files import show
from .common import add_disk, add_output, disk_from_args, finite_float, output_path, positive_int, range_type, \
    scheduler_type, tolerance, undecided_hint
from .registry import command


def _arguments(p) -> None:
    p.add_argument("--omega", type=range_type("omega"), required=True, help="START:STOP:N initial spin Omega "
                   "[rad/s] (N values, ends included; write --omega=-50:-10:5 for a negative START)")
    p.add_argument("--eps", type=range_type("eps"), required=True, help="START:STOP:N smoothing velocity eps [m/s]")
    p.add_argument("--mu", type=range_type("mu"), help="START:STOP:N friction coefficient [-] (default 0.3)")
    p.add_argument("--e", type=range_type("e"), help="START:STOP:N eccentricity [m] (default: the disk's). Held "
                   "fixed: A, B, C about G (--disk table2 / given), or the hole geometry but its offset b, with "
                   "m, A, B, C recomputed (--disk geometry)")
    p.add_argument("--dgamma0", type=range_type("dgamma0"), help="START:STOP:N gamma(0) + pi/2 [rad] (default 0.1)")
    p.add_argument("--classify", choices=("attractors", "rules"), default="attractors",
                   help="attractors (default): assign each run to the attractor it reaches, found by recurrences, "
                        "with t_end as the maximum horizon; rules: classify by the end window of fixed-length runs")
    p.add_argument("--t-end", type=finite_float, help="length of each run [s] (default 5; attractors: the maximum "
                                                      "horizon, default 60)")
    p.add_argument("--window", type=finite_float, help="rules: classification window at the end [s] "
                   f"(default {defaults.OUTCOME_WINDOW_FRACTION:g} t_end)")
    p.add_argument("--dt", type=finite_float, help="attractors: sampling interval of the recurrence grid [s] "
                                                   "(default 0.05)")
    p.add_argument("--tol", type=tolerance, default=defaults.MAP_TOL,
                   help=f"integrator tolerance (default {defaults.MAP_TOL:g})")
    p.add_argument("--fall-angle", type=finite_float, default=defaults.FALL_ANGLE,
                   help=f"tilt that ends a run [rad] (default {defaults.FALL_ANGLE:g})")
    p.add_argument("--chunk-size", type=positive_int, default=defaults.CHUNK_SIZE,
                   help=f"grid points per chunk (default {defaults.CHUNK_SIZE})")
    p.add_argument("--batch-size", type=positive_int, default=defaults.BATCH_SIZE,
                   help=f"SIMD lanes per batch: 1, 2, 4, 8, 16 (default {defaults.BATCH_SIZE})")
    p.add_argument("--threads", type=positive_int, help="threads without --scheduler (default: cores)")
    p.add_argument("--scheduler", type=scheduler_type,
                   help="dask.distributed scheduler address (tcp://host:8786), or local:N for N local processes")
    add_output(p, "netCDF file (finished chunks go to OUTPUT.chunks/; the same command resumes them)")
    add_disk(p, e_option=False)


@command("outcome-map", "classify runs over a grid of (Omega, eps, ...) -> netCDF", _arguments)
def outcome_map(args) -> int:
    from ..analysis.outcome_map import outcome_map as run_map
    from ..parameters import Setup

    ranges = {k: getattr(args, k) for k in ("omega", "eps", "mu", "e", "dgamma0") if getattr(args, k) is not None}
    setup = Setup(disk=disk_from_args(args, sweep_e=args.e[0] if args.e else None, e_swept=True))
    output = output_path(args)
    attractors = {}
    if args.classify == "attractors":
        attractors = {"classify": "attractors", "recurrence": {"dt": args.dt} if args.dt is not None else None}
    t_end = args.t_end if args.t_end is not None else (60.0 if args.classify == "attractors" else 5.0)
    ds = run_map(ranges, output=output, scheduler=args.scheduler, threads=args.threads, t_end=t_end,
                 window=args.window, tol=args.tol, fall_angle=args.fall_angle, chunk_size=args.chunk_size,
                 batch_size=args.batch_size, setup=setup, overwrite=args.overwrite, **attractors)
    print(f"{show(output)}: {ds.attrs['message']}{undecided_hint(ds, t_end)}")
    return 0

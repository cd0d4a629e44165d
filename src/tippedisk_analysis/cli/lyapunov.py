"""``tippedisk lyapunov``: Lyapunov exponents of the reduced tippedisk (one run: the spectrum with its
convergence history and error bars; ranges START:STOP:N of --omega and --eps: a resumable map of the largest
exponent), or of a textbook system (--system lorenz).

Exit status of a run: 0 when it is ``completed`` or ``not_converged`` (a finite-time spectrum with error bars
too wide yet: written, and the message names the t_end that settles it); 1 when it fell, lifted off, failed or
its sum missed the mean divergence (``not_verified``)."""

from __future__ import annotations

from .. import defaults
from ..errors import ParameterError
from ..files import show
from .common import add_disk, add_output, disk_from_args, disk_options_given, finite_float, output_path, \
    positive_int, range_type, scheduler_type, tolerance
from .registry import command

RESULTS = ("completed", "not_converged")  # a spectrum with its error bars (exit 0)


def _arguments(p) -> None:
    p.add_argument("--omega", type=range_type("omega"), help="initial spin Omega [rad/s]: one value (a run) or "
                   "START:STOP:N (a map); Table 3 start otherwise (default 40)")
    p.add_argument("--eps", type=range_type("eps"), help="smoothing eps [m/s]: one value or START:STOP:N (default 0.1)")
    p.add_argument("--mu", type=finite_float, help="friction coefficient (default 0.3)")
    p.add_argument("--dgamma0", type=finite_float, default=0.1, help="gamma(0) + pi/2 [rad] (default 0.1)")
    p.add_argument("--t-end", type=finite_float, help="end of each run [s], transient included (default 20; "
                   "--system: 1000)")
    p.add_argument("--dt", type=finite_float, help="re-orthonormalisation interval (default 0.1 s for a run, "
                                                   "0.5 s for a map, 1 for --system)")
    p.add_argument("--transient", type=finite_float, default=0.0, help="not accumulated at the start (default 0)")
    p.add_argument("--n-exponents", type=positive_int, help="exponents of a run (default all 7)")
    p.add_argument("--system", help="a textbook system instead of the tippedisk: lorenz")
    p.add_argument("--tol", type=tolerance, help=f"integrator tolerance (default 1e-12; maps {defaults.MAP_TOL:g})")
    p.add_argument("--chunk-size", type=positive_int, default=128, help="map points per stored chunk (default 128)")
    p.add_argument("--batch-size", type=positive_int, default=defaults.BATCH_SIZE, help="SIMD lanes (default 4)")
    p.add_argument("--threads", type=positive_int, help="threads without --scheduler (default: cores)")
    p.add_argument("--scheduler", type=scheduler_type,
                   help="dask.distributed scheduler address (tcp://host:8786), or local:N for N local processes")
    add_output(p, "netCDF file (a map's finished chunks go to OUTPUT.chunks/; the same command resumes them)")
    add_disk(p)


@command("lyapunov", "Lyapunov exponents: a run's spectrum, or a map of the largest over (Omega, eps)", _arguments)
def lyapunov(args) -> int:
    import dataclasses

    from .. import results
    from ..analysis import lyapunov as ly
    from ..parameters import Friction, InitialState, Setup, to_dict

    output = output_path(args)
    if args.system:
        if args.system != "lorenz":
            raise ParameterError(f"--system {args.system!r}: the Lyapunov command knows lorenz")
        tippedisk_only = (["--omega"] if args.omega else []) + (["--eps"] if args.eps else []) + \
            (["--mu"] if args.mu is not None else []) + disk_options_given(args)
        if tippedisk_only:
            raise ParameterError(f"{', '.join(tippedisk_only)} belong(s) to the tippedisk, not to --system; drop them")
        ds = ly.textbook_spectrum("lorenz", [1.0, 1.0, 1.0], t_end=args.t_end or 1000.0, dt=args.dt or 1.0,
                                  transient=args.transient or 10.0, tol=args.tol or ly.TOL)
        results.save(ds, output)
        print(f"{show(output)}: {ds.attrs['message']}")
        return 0 if ds.attrs["status"] in RESULTS else 1
    omega = args.omega or (40.0, 40.0, 1)
    eps = args.eps or (Friction().eps, Friction().eps, 1)
    friction = dataclasses.replace(Friction(), **({"mu": args.mu} if args.mu is not None else {}))
    disk = disk_from_args(args)
    if omega[2] > 1 or eps[2] > 1:
        if args.n_exponents not in (None, 1) or args.transient:
            raise ParameterError("maps compute the largest exponent from t = 0: drop --n-exponents / --transient")
        ds = ly.lyapunov_map(omega, eps, output=output, overwrite=args.overwrite, scheduler=args.scheduler,
                             threads=args.threads, t_end=args.t_end or 20.0, dt=args.dt or 0.5, dgamma0=args.dgamma0,
                             tol=args.tol or defaults.MAP_TOL, chunk_size=args.chunk_size, batch_size=args.batch_size,
                             setup=to_dict(Setup(disk=disk, friction=friction)))
        print(f"{show(output)}: {ds.attrs['message']}")
        return 0 if ds.attrs["status"] == "completed" else 1
    if args.scheduler or args.threads:
        raise ParameterError("--scheduler and --threads belong to maps (ranges START:STOP:N of --omega or --eps)")
    setup = Setup(disk=disk, friction=dataclasses.replace(friction, eps=eps[0]))
    initial = InitialState(alpha_dot=omega[0], gamma=-1.5707963267948966 + args.dgamma0)
    ds = ly.tippedisk_spectrum(setup, initial, t_end=args.t_end or 20.0, dt=args.dt or ly.DT,
                               transient=args.transient, n_exponents=args.n_exponents, tol=args.tol or ly.TOL)
    results.save(ds, output)
    print(f"{show(output)}: {ds.attrs['message']}")
    return 0 if ds.attrs["status"] in RESULTS else 1

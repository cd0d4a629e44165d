"""``tippedisk bifurcation``: brute-force bifurcation diagram, a quantity at Poincaré crossings vs Omega."""

from __future__ import annotations

from .. import defaults
from ..files import show
from .common import add_disk, add_initial_and_friction, add_output, output_path, positive_int, \
    range_type, scheduler_type, setup_and_initial, tolerance
from .poincare import add_section
from .registry import command


def _arguments(p) -> None:
    from ..models.variables import quantities

    p.add_argument("--omega", type=range_type("omega"), required=True,
                   help="START:STOP:N initial spin Omega [rad/s] (one run from Table 3 per value)")
    p.add_argument("--quantity", default="gamma", choices=quantities(), metavar="QUANTITY",
                   help="quantity recorded at the crossings (default gamma; angles wrapped into (-pi, pi]); one of "
                        + ", ".join(quantities()))
    add_initial_and_friction(p, omega=False)
    p.add_argument("--tol", type=tolerance, default=defaults.BIFURCATION_TOL,
                   help=f"integrator tolerance (default {defaults.BIFURCATION_TOL:g})")
    add_section(p, t_end=10.0, t_transient=5.0, max_crossings=50)
    p.add_argument("--threads", type=positive_int, help="threads without --scheduler (default: cores)")
    p.add_argument("--scheduler", type=scheduler_type,
                   help="dask.distributed scheduler address (tcp://host:8786), or local:N for N local processes")
    add_output(p, "netCDF file (finished chunks of Omega values go to OUTPUT.chunks/; the same command resumes)")
    add_disk(p)


@command("bifurcation", "brute-force bifurcation diagram: a quantity at crossings vs Omega", _arguments)
def bifurcation(args) -> int:
    from ..analysis.bifurcation import bifurcation_diagram

    setup, initial = setup_and_initial(args, omega=False)
    output = output_path(args)
    ds = bifurcation_diagram(args.omega, quantity=args.quantity, section=args.section, direction=args.direction,
                             setup=setup, initial=initial, t_transient=args.t_transient, t_end=args.t_end,
                             max_crossings=args.max_crossings, tol=args.tol, threads=args.threads,
                             scheduler=args.scheduler, output=output, overwrite=args.overwrite)
    print(f"{show(output)}: {ds.attrs['message']}")
    return 0

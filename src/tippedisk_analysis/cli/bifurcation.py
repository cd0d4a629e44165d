"""``tippedisk bifurcation``: brute-force bifurcation diagram, a quantity at Poincaré crossings vs Omega."""

from __future__ import annotations

from .. import defaults
from .common import add_initial_and_friction, add_output, finite_float, range_type, setup_and_initial, writable
from .poincare import add_section
from .registry import command


def _arguments(p) -> None:
    from ..analysis.poincare import quantities

    p.add_argument("--omega", type=range_type("omega"), required=True,
                   help="START:STOP:N initial spin Omega [rad/s]")
    p.add_argument("--quantity", default="gamma", choices=quantities(), metavar="QUANTITY",
                   help="quantity recorded at the crossings (default gamma); one of " + ", ".join(quantities()))
    add_initial_and_friction(p, omega=False)
    p.add_argument("--tol", type=finite_float, default=defaults.BIFURCATION_TOL,
                   help=f"integrator tolerance (default {defaults.BIFURCATION_TOL:g})")
    add_section(p, t_end=10.0, t_transient=5.0, max_crossings=50)
    add_output(p)


@command("bifurcation", "brute-force bifurcation diagram: a quantity at crossings vs Omega", _arguments)
def bifurcation(args) -> int:
    from .. import results
    from ..analysis.bifurcation import bifurcation_diagram

    setup, initial = setup_and_initial(args)
    output = writable(args.output)
    ds = bifurcation_diagram(args.omega, quantity=args.quantity, section=args.section, direction=args.direction,
                             setup=setup, initial=initial, t_transient=args.t_transient, t_end=args.t_end,
                             max_crossings=args.max_crossings, tol=args.tol)
    results.save(ds, output)
    print(f"{output}: {ds.attrs['message']}")
    return 0

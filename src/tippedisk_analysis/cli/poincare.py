"""``tippedisk poincare``: Poincaré section of one trajectory (heyoka events)."""

from __future__ import annotations

from .. import defaults
from .common import add_initial_and_friction, add_output, finite_float, positive_int, setup_and_initial, writable
from .registry import command

DIRECTIONS = ("positive", "negative", "any")


def add_section(p, t_end: float, t_transient: float, max_crossings: int | None) -> None:
    p.add_argument("--t-end", type=finite_float, default=t_end, help=f"end time [s] (default {t_end:g})")
    p.add_argument("--t-transient", type=finite_float, default=t_transient,
                   help=f"skip crossings before this time [s] (default {t_transient:g})")
    p.add_argument("--max-crossings", type=positive_int, default=max_crossings,
                   help="stop after this many crossings" + (f" (default {max_crossings})" if max_crossings else ""))
    p.add_argument("--section", default="beta_dot=0",
                   help="NAME=LEVEL, e.g. beta_dot=0 (default), gamma=pi/2, 'alpha mod 2pi=0'")
    p.add_argument("--direction", default="positive", choices=DIRECTIONS,
                   help="count crossings where NAME increases (positive, default), decreases (negative) or both")


def _arguments(p) -> None:
    add_initial_and_friction(p)
    p.add_argument("--model", default="ode-euler", help="ode-euler (ode1) or ode-quaternion (ode2)")
    p.add_argument("--tol", type=finite_float, default=defaults.TAYLOR_TOL,
                   help=f"integrator tolerance (default {defaults.TAYLOR_TOL:g})")
    add_section(p, t_end=10.0, t_transient=0.0, max_crossings=None)
    add_output(p)


@command("poincare", "Poincaré section of one trajectory (heyoka events) -> netCDF", _arguments)
def poincare(args) -> int:
    from .. import results
    from ..analysis.poincare import poincare_section

    setup, initial = setup_and_initial(args)
    output = writable(args.output)
    ds = poincare_section(args.section, direction=args.direction, model=args.model, setup=setup, initial=initial,
                          t_transient=args.t_transient, t_end=args.t_end, max_crossings=args.max_crossings,
                          tol=args.tol)
    results.save(ds, output)
    print(f"{output}: section {ds.attrs['section']} ({ds.attrs['direction']}): {ds.attrs['message']}")
    return 1 if ds.attrs["status"] == "nonfinite" else 0

"""``tippedisk poincare``: Poincaré section of one trajectory (heyoka events)."""

from __future__ import annotations

from .. import defaults
from ..files import show
from ..resources import check_memory
from .common import add_disk, add_initial_and_friction, add_output, finite_float, output_path, positive_int, \
    setup_and_initial, tolerance
from .registry import command

DIRECTIONS = ("positive", "negative", "any")
CROSSINGS_PER_SECOND = 100.0  # generous: beta_dot = 0 is crossed ~25 times per second at Omega = 40 rad/s
BYTES_PER_CROSSING = 600.0  # ~30 state and output doubles per crossing, with copies


def add_section(p, t_end: float, t_transient: float, max_crossings: int | None) -> None:
    p.add_argument("--t-end", type=finite_float, default=t_end, help=f"end time [s] (default {t_end:g})")
    p.add_argument("--t-transient", type=finite_float, default=t_transient,
                   help=f"skip crossings before this time [s] (default {t_transient:g})")
    p.add_argument("--max-crossings", type=positive_int, default=max_crossings,
                   help="stop after this many crossings" + (f" (default {max_crossings})" if max_crossings else ""))
    p.add_argument("--section", default="beta_dot=0",
                   help="NAME=LEVEL, e.g. beta_dot=0 (default), gamma=pi/2, 'alpha mod 2pi=0'")
    p.add_argument("--direction", default="positive", choices=DIRECTIONS,
                   help="which crossings of the section count: positive (default) where NAME increases through "
                        "LEVEL, negative where it decreases, any for both")


def _arguments(p) -> None:
    add_initial_and_friction(p)
    p.add_argument("--model", default="ode-euler", help="ode-euler (ode1), ode-quaternion (ode2) or hybrid-euler (h1: set-valued "
                   "Coulomb, rolling and sliding)")
    p.add_argument("--tol", type=tolerance, default=defaults.TAYLOR_TOL,
                   help=f"integrator tolerance (default {defaults.TAYLOR_TOL:g})")
    add_section(p, t_end=10.0, t_transient=0.0, max_crossings=None)
    add_output(p)
    add_disk(p)


@command("poincare", "Poincaré section of one trajectory (heyoka events) -> netCDF", _arguments)
def poincare(args) -> int:
    from .. import results
    from ..analysis.poincare import poincare_section
    from ..errors import Interrupted

    setup, initial = setup_and_initial(args)
    crossings = min(args.max_crossings or float("inf"), CROSSINGS_PER_SECOND * args.t_end)
    check_memory(crossings * BYTES_PER_CROSSING, f"a Poincaré section of up to {crossings:,.0f} crossings",
                 "give --max-crossings or a shorter --t-end")
    output = output_path(args)
    try:
        ds = poincare_section(args.section, direction=args.direction, model=args.model, setup=setup,
                              initial=initial, t_transient=args.t_transient, t_end=args.t_end,
                              max_crossings=args.max_crossings, tol=args.tol)
    except KeyboardInterrupt:
        raise Interrupted("interrupted; nothing stored (one trajectory, no checkpoint: rerun to start again)") from None
    results.save(ds, output)
    print(f"{show(output)}: section {ds.attrs['section']} ({ds.attrs['direction']}): {ds.attrs['message']}")
    return 1 if ds.attrs["status"] == "nonfinite" else 0

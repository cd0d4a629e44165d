"""``tippedisk stability-map``: eigenvalue stability of the spinning solutions over (Omega, eps[, mu, e])."""

from __future__ import annotations

from ..ranges import range_values
from .common import add_output, writable
from .registry import command


def _arguments(p) -> None:
    p.add_argument("--omega", required=True, help="spin rates START:STOP:N [rad/s] (N values, ends included; "
                   "write --omega=-50:50:101 for a negative START)")
    p.add_argument("--eps", required=True, help="smoothing eps of (2.29) START:STOP:N [m/s]")
    p.add_argument("--mu", help="friction coefficient START:STOP:N or one value (default 0.3, not a dimension)")
    p.add_argument("--e", help="eccentricity START:STOP:N or one value [m] (default 2.5e-3, not a dimension; "
                               "A, B, C about G held fixed)")
    add_output(p)


@command("stability-map", "eigenvalue stability of the spinning solutions over Omega and eps", _arguments)
def stability_map(args) -> int:
    from .. import results
    from ..analysis import maps

    ranges = {name: range_values(getattr(args, name), name) if getattr(args, name) is not None else None
              for name in ("omega", "eps", "mu", "e")}
    output = writable(args.output)
    ds = maps.stability_map(ranges["omega"], ranges["eps"], mu=ranges["mu"], e=ranges["e"])
    results.save(ds, output)
    print(f"{output}: stability map {ds.attrs['message']}")
    return 0

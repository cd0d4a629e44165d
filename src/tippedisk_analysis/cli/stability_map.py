"""``tippedisk stability-map``: eigenvalue stability of the spinning solutions over (Omega, eps[, mu, e])."""

from __future__ import annotations

from ..files import show
from ..ranges import range_values
from .common import add_disk, add_output, disk_from_args, output_path
from .registry import command


def _arguments(p) -> None:
    p.add_argument("--omega", required=True, help="spin rates START:STOP:N [rad/s] (N values, ends included; "
                   "write --omega=-50:50:101 for a negative START)")
    p.add_argument("--eps", required=True, help="smoothing eps of (2.29) START:STOP:N [m/s]")
    p.add_argument("--mu", help="friction coefficient START:STOP:N or one value [-] (default 0.3, not a dimension)")
    p.add_argument("--e", help="eccentricity START:STOP:N or one value [m] (default: the disk's; not a dimension "
                               "for one value). Held fixed: A, B, C about G (--disk table2 / given), or the hole "
                               "geometry but its offset b, with m, A, B, C recomputed (--disk geometry)")
    add_output(p)
    add_disk(p, e_option=False)


@command("stability-map", "eigenvalue stability of the spinning solutions over Omega and eps", _arguments)
def stability_map(args) -> int:
    from .. import results
    from ..analysis import maps
    from ..parameters import Setup

    ranges = {name: range_values(getattr(args, name), name) if getattr(args, name) is not None else None
              for name in ("omega", "eps", "mu", "e")}
    e = ranges["e"]
    setup = Setup(disk=disk_from_args(args, sweep_e=None if e is None else float(e[0]), e_swept=True))
    output = output_path(args)
    ds = maps.stability_map(ranges["omega"], ranges["eps"], mu=ranges["mu"], e=e, setup=setup)
    results.save(ds, output)
    print(f"{show(output)}: stability map {ds.attrs['message']}")
    return 0

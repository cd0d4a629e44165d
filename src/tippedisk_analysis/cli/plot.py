"""``tippedisk plot``: draw any dataset of ours with the figure of its kind."""

from __future__ import annotations

from pathlib import Path

from ..errors import ParameterError
from ..files import show
from .common import output_path
from .registry import command


def _arguments(p) -> None:
    p.add_argument("dataset", help="netCDF file written by tippedisk")
    p.add_argument("--output", "-o", help="figure file, format from the suffix (default: the dataset name with .png)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing figure (refused without it)")
    p.add_argument("--observable", help="continuation branches: the variable drawn against the parameter "
                                        "(default max_real_eig; e.g. lambda_N, omega_x)")
    p.add_argument("--over", metavar="MAP.nc", help="continuation curves: draw them over this stability map")


@command("plot", "draw a stored dataset as a figure (PNG, PDF, SVG, ...)", _arguments)
def plot(args) -> int:
    from .. import results

    ds = results.load(args.dataset)
    output = output_path(args, str(args.output or Path(args.dataset).with_suffix(".png")), netcdf=False)
    results.require_samples(ds, "draw")  # checks before matplotlib loads
    from .. import plotting

    formats = plotting.file_formats()
    if output.suffix.lower().lstrip(".") not in formats:
        raise ParameterError(f"cannot draw to {output.suffix or 'a file without suffix'!r}; give --output with one of "
                             f"{', '.join('.' + f for f in sorted(formats))}")
    options = {}
    if args.observable is not None:
        options["observable"] = args.observable
    if args.over is not None:
        background = results.load(args.over)
        if background.attrs.get("kind") != "stability_map":
            raise ParameterError(f"--over {args.over!r} is a {background.attrs.get('kind')} dataset; give a stability "
                                 "map (tippedisk stability-map)")
        options["background"] = background
    plotting.plot_dataset(ds, output, **options)
    print(f"{show(output)}: {ds.attrs['kind']} figure")
    return 0

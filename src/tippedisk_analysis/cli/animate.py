"""``tippedisk animate``: a 3D animation of a stored simulation (GIF with Pillow, MP4 and more with ffmpeg)."""

from __future__ import annotations

import argparse

from ..files import show
from .common import finite_float, output_path
from .registry import command

PANELS = "gamma,z_S,E_tot"
SUFFIXES = (".gif", ".mp4", ".mkv", ".mov", ".webm", ".avi")


def size_type(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not WIDTHxHEIGHT in pixels, e.g. 960x540") from None
    return width, height


def _arguments(p) -> None:
    p.add_argument("dataset", help="netCDF file written by tippedisk simulate (any model, Euler or quaternion)")
    p.add_argument("--output", "-o", required=True,
                   help="animation file: .gif (Pillow, or ffmpeg when installed) or .mp4/.mkv/.webm (ffmpeg)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing file (refused without it)")
    p.add_argument("--speed", type=finite_float, default=0.1,
                   help="simulated seconds per second of video (default 0.1: ten times slower than life)")
    p.add_argument("--fps", type=finite_float, default=30.0, help="frames per second of the video (default 30)")
    p.add_argument("--size", type=size_type, default=(960, 540), help="WIDTHxHEIGHT in pixels (default 960x540)")
    p.add_argument("--t-start", type=finite_float, help="first simulated time shown [s] (default: the run's start)")
    p.add_argument("--t-end", type=finite_float, help="last simulated time shown [s] (default: the run's end)")
    p.add_argument("--panels", default=PANELS,
                   help=f"comma-separated time series beside the disk with a moving cursor (default {PANELS}); "
                        "'none' for the 3D view alone")


@command("animate", "3D animation of a stored simulation (disk, G, S, contact track) -> GIF or MP4", _arguments)
def animate(args) -> int:
    from .. import results
    from ..errors import Interrupted, ParameterError

    ds = results.load(args.dataset)
    output = output_path(args, netcdf=False)
    results.require_samples(ds, "animate")  # checks before matplotlib loads
    if output.suffix.lower() not in SUFFIXES:
        raise ParameterError(f"cannot write an animation to {output.suffix or 'a file without suffix'!r}; give "
                             f"--output with one of {', '.join(SUFFIXES)} (.gif with Pillow, the others with ffmpeg)")
    from ..plotting.animation import animate as write_animation

    panels = () if args.panels.strip().lower() in ("", "none") else tuple(p.strip() for p in args.panels.split(","))
    try:
        path, n = write_animation(ds, output, speed=args.speed, fps=args.fps, size=args.size, panels=panels,
                                  t_start=args.t_start, t_stop=args.t_end)
    except KeyboardInterrupt:
        raise Interrupted("interrupted; nothing stored (the animation is written in one go: rerun to start again)") \
            from None
    print(f"{show(path)}: {n} frames at {args.fps:g} fps, {args.size[0]}x{args.size[1]} pixels")
    return 0

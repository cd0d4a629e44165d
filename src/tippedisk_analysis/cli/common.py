"""Argument types and checks shared by the commands: one line naming the fix for every bad value."""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

from .. import files
from ..errors import ParameterError
from ..ranges import parse_range

DISK_SOURCES = ("table2", "geometry", "given")


def finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


MIN_TOL = 1e-16  # below double precision's round-off a tolerance means nothing (and heyoka's order explodes)


def tolerance(text: str) -> float:
    """An integrator or solver tolerance in [MIN_TOL, 1)."""
    value = finite_float(text)
    if not MIN_TOL <= value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a tolerance in [{MIN_TOL:g}, 1) (double precision "
                                         "resolves no less); give e.g. 1e-13")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive integer")
    return value


def range_type(name: str):
    """argparse type for ``--name START:STOP:N``."""

    def parse(text: str):
        try:
            return parse_range(text, name)
        except ParameterError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = f"--{name} range"
    return parse


def scheduler_type(text: str) -> str:
    """argparse type for ``--scheduler``: a dask address or local:N with N >= 1."""
    from ..dynamics.schedulers import parse_scheduler

    try:
        parse_scheduler(text)
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(exc.cli_message()) from None
    return text


def add_output(p: argparse.ArgumentParser, what: str = "netCDF file to write", required: bool = True) -> None:
    p.add_argument("--output", "-o", required=required, help=what)
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing output (and discard chunks or a checkpoint of another configuration); "
                        "without it an existing output is refused")


def output_path(args, path: str | None = None, netcdf: bool = True) -> Path:
    """The output path, checked before any work starts (exists without --overwrite, directory, device, ...)."""
    return files.check_output(path if path is not None else args.output, overwrite=args.overwrite, netcdf=netcdf)


def add_initial_and_friction(p: argparse.ArgumentParser, omega: bool = True) -> None:
    """Options of one trajectory of ODE Model 1 from the Table 3 start (Poincaré sections, bifurcation diagrams)."""
    if omega:
        p.add_argument("--omega", type=finite_float, help="initial spin Omega = alpha_dot(0) [rad/s] (Table 3: 40)")
    p.add_argument("--dgamma0", type=finite_float, help="gamma(0) = -pi/2 + dgamma0 [rad] (Table 3: 0.1)")
    p.add_argument("--mu", type=finite_float, help="friction coefficient [-] (0.3)")
    p.add_argument("--eps", type=finite_float, help="smoothing of (2.29) [m/s] (0.1)")


def add_disk(p: argparse.ArgumentParser, e_option: bool = True) -> None:
    """The disk: Table 2 (default), the drilled-disk geometry of Sect. 5, or m, e, r, A, B, C given."""
    g = p.add_argument_group(
        "disk (Sect. 2, 5; Tables 1-2)",
        "--disk table2 (default): Table 2; --mass scales A, B, C with m (same shape, other density), --e and "
        "--radius keep A, B, C about G. --disk geometry: the drilled steel disk of Sect. 5 from --rho, --radius, "
        "--hole-radius, --hole-offset, --thickness (m, e, A, B, C follow; an e sweep moves the hole). "
        "--disk given: all of --mass, --e, --radius, --A, --B, --C.")
    g.add_argument("--disk", choices=DISK_SOURCES, default="table2", help="how the disk is given (default table2)")
    g.add_argument("--mass", type=finite_float, help="mass m [kg] (Table 2: 0.435)")
    if e_option:
        g.add_argument("--e", type=finite_float, help="eccentricity e = |GS| [m] (Table 2: 2.5e-3)")
    g.add_argument("--radius", type=finite_float, help="rim radius r [m] (0.045)")
    for name, value in (("A", "0.249e-3"), ("B", "0.227e-3"), ("C", "0.468e-3")):
        g.add_argument(f"--{name}", type=finite_float, help=f"principal inertia {name} about G [kg m^2] "
                                                            f"(Table 2: {value}; with --disk given)")
    g.add_argument("--rho", type=finite_float, help="density [kg/m^3] (--disk geometry; Table 1: 7700)")
    g.add_argument("--hole-radius", type=finite_float, help="hole radius a [m] (--disk geometry; 0.015)")
    g.add_argument("--hole-offset", type=finite_float, help="distance b of the hole centre from G [m] "
                                                            "(--disk geometry; 0.02)")
    g.add_argument("--thickness", type=finite_float, help="thickness h [m] (--disk geometry; 0.01)")


DISK_OPTIONS = {"m": "--mass", "e": "--e", "r": "--radius", "A": "--A", "B": "--B", "C": "--C", "rho": "--rho",
                "a": "--hole-radius", "b": "--hole-offset", "h": "--thickness"}
"""Disk field -> option of :func:`add_disk` (``--e`` is a command's own option where it is swept or fixed)."""
_DISK_ATTRS = {"m": "mass", "e": "e", "r": "radius", "A": "A", "B": "B", "C": "C", "rho": "rho", "a": "hole_radius",
               "b": "hole_offset", "h": "thickness"}


def disk_options_given(args) -> list[str]:
    """The disk options given on the command line (``--disk`` other than table2 included), for commands that
    refuse them where a dataset already fixes the disk."""
    given = [DISK_OPTIONS[k] for k, attr in _DISK_ATTRS.items() if getattr(args, attr, None) is not None]
    return (["--disk"] if getattr(args, "disk", "table2") != "table2" else []) + given


def disk_from_args(args, *, sweep_e: float | None = None, e_swept: bool = False):
    """The Disk the options describe; ParameterError (one line) for options that do not belong to --disk.

    Map commands sweep ``--e`` (``e_swept``): there the disk's own e is the first swept value
    ``sweep_e`` for ``--disk given`` (needed to check the disk), and the sweep moves the hole of
    ``--disk geometry`` or keeps A, B, C about G otherwise (Disk.with_eccentricity).
    """
    from ..parameters import Disk

    given = {name: getattr(args, attr, None) for name, attr in _DISK_ATTRS.items()}
    if e_swept:
        given["e"] = sweep_e if getattr(args, "disk", "table2") == "given" else None
    option = DISK_OPTIONS
    present = {k for k, v in given.items() if v is not None}
    source = getattr(args, "disk", "table2")

    def refuse(names, why):
        names = sorted(names, key=list(option).index)
        if names:
            raise ParameterError(f"{', '.join(option[n] for n in names)} {why}")

    if source == "geometry":
        refuse(present & {"m", "A", "B", "C"}, "cannot be given with --disk geometry: m, A, B, C follow from "
                                              "the geometry; change --rho, --hole-radius, --hole-offset, --thickness")
        refuse(present & {"e"}, "cannot be given with --disk geometry: e = b a^2/(r^2 - a^2) follows from it; "
                                "change --hole-offset")
        geo = {k: given[k] for k in ("rho", "r", "a", "b", "h") if given[k] is not None}
        return Disk.from_geometry(**geo)
    refuse(present & {"rho", "a", "b", "h"}, "belong(s) to the drilled-disk geometry; add --disk geometry")
    if source == "given":
        missing = {"m", "e", "r", "A", "B", "C"} - present
        refuse(missing, "missing: --disk given needs all of --mass, --e, --radius, --A, --B, --C")
        return Disk(**{k: given[k] for k in ("m", "e", "r", "A", "B", "C")})
    refuse(present & {"A", "B", "C"}, "need(s) --disk given (with all of --mass, --e, --radius, --A, --B, --C)")
    shape = {k: given[k] for k in ("r", "e") if k in present}  # together: a new r is checked against the new e
    disk = dataclasses.replace(Disk(), **shape)  # Table 2's A, B, C about G kept (Disk.with_eccentricity)
    if "m" in present:
        disk = disk.with_mass(given["m"])
    return disk


def setup_and_initial(args, omega: bool = True):
    """Setup and InitialState from ``add_initial_and_friction`` and ``add_disk`` options
    (``omega``: ``--omega`` is the initial spin; False where it is a range, as in bifurcation)."""
    from ..parameters import Friction, InitialState, Setup

    fric = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    init = {}
    if omega and getattr(args, "omega", None) is not None:
        init["alpha_dot"] = args.omega
    if args.dgamma0 is not None:
        init["gamma"] = -0.5 * math.pi + args.dgamma0
    return Setup(disk=disk_from_args(args), friction=dataclasses.replace(Friction(), **fric)), InitialState(**init)


def undecided_hint(ds, t_end: float) -> str:
    """What to do about runs classified ``undecided`` by attractors (appended to the command's one line):
    they had not reached an attractor when the horizon ended."""
    outcome = ds.get("outcome")
    by_attractors = ds.attrs.get("kind") in ("basins", "basin_fractions") or ds.attrs.get("classify") == "attractors"
    if not by_attractors or outcome is None or "undecided" not in str(outcome.attrs.get("flag_meanings", "")).split():
        return ""
    flags = dict(zip(str(outcome.attrs["flag_meanings"]).split(), list(outcome.attrs["flag_values"])))
    n = int((outcome.values == flags["undecided"]).sum())
    if not n:
        return ""
    return (f"; {n} of {outcome.size} runs undecided: the horizon --t-end {t_end:g} s ended before they reached an "
            "attractor (the tippedisk's transients last tens of seconds); give a longer --t-end, e.g. 60"
            + (", or --classify rules" if ds.attrs.get("kind") == "outcome_map" else ""))

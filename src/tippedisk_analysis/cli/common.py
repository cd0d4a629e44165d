"""Argument types and checks shared by the commands: one line naming the fix for every bad value."""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

from ..errors import ParameterError
from ..ranges import parse_range


def finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
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


def writable(path: str) -> Path:
    """The output path, checked before any work starts."""
    path = Path(path)
    if not path.parent.is_dir():
        raise ParameterError(f"directory {str(path.parent)!r} does not exist; create it or choose another --output")
    return path


def add_output(p: argparse.ArgumentParser, what: str = "netCDF file to write") -> None:
    p.add_argument("--output", "-o", required=True, help=what)


def add_initial_and_friction(p: argparse.ArgumentParser, omega: bool = True) -> None:
    """Options of one trajectory of ODE Model 1 from the Table 3 start (Poincaré sections, bifurcation diagrams)."""
    if omega:
        p.add_argument("--omega", type=finite_float, help="initial spin Omega = alpha_dot(0) [rad/s] (Table 3: 40)")
    p.add_argument("--dgamma0", type=finite_float, help="gamma(0) = -pi/2 + dgamma0 [rad] (Table 3: 0.1)")
    p.add_argument("--mu", type=finite_float, help="friction coefficient (0.3)")
    p.add_argument("--eps", type=finite_float, help="smoothing of (2.29) [m/s] (0.1)")


def setup_and_initial(args):
    """Setup and InitialState from ``add_initial_and_friction`` options."""
    from ..parameters import Friction, InitialState, Setup

    fric = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    init = {}
    if getattr(args, "omega", None) is not None:
        init["alpha_dot"] = args.omega
    if args.dgamma0 is not None:
        init["gamma"] = -0.5 * math.pi + args.dgamma0
    return Setup(friction=dataclasses.replace(Friction(), **fric)), InitialState(**init)

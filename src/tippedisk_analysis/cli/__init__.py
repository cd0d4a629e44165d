"""Command line: ``tippedisk COMMAND``, one module per command, registered with :func:`.registry.command`.

Thin: parse, call the library, print one line. Bad input (a TippediskError) prints one line
on stderr and exits with status 2; nothing is written then. A run that ended with a
numerical failure exits with 1.
"""

from __future__ import annotations

import argparse
import sys

from ..errors import TippediskError
from ..version import __version__
from . import (bifurcation, continuation, outcome_map, plot, poincare, simulate, stability_map,  # noqa: F401
               study)  # registration
from . import periodic_orbits  # noqa: F401  (registration)
from . import lyapunov  # noqa: F401  (registration)
from .registry import COMMANDS


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit status 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="tippedisk", description="Simulate and analyse the tippedisk (Sailer et al. 2020).")
    parser.add_argument("--version", action="version", version=f"tippedisk_analysis {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for cmd in COMMANDS.values():
        cmd.add_arguments(sub.add_parser(cmd.name, help=cmd.help, description=cmd.help))
    return parser


def main(argv: list[str] | None = None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a usage error (one line on stderr, status 2)
        return int(exc.code or 0)
    try:
        return COMMANDS[args.command].run(args)
    except TippediskError as exc:
        print(f"tippedisk {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"tippedisk {args.command}: error: not enough memory for this request; use fewer grid points "
              "or a shorter run", file=sys.stderr)
        return 2


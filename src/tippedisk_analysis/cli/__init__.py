"""Command line: ``tippedisk COMMAND``, one module per command, registered with :func:`.registry.command`.

Thin: parse, call the library, print one line. The promises every command keeps:

* bad input, an output that cannot be written, or a request that cannot fit in memory: one line
  on stderr naming the fix, exit status 2, checked before any computation, nothing written;
* an existing output is replaced only with ``--overwrite`` (two runs started together on one
  output both finish; the last one's rename wins, nothing is half-written);
* Ctrl-C: one line saying what was kept (chunks, a checkpoint) and how to resume, exit status 130;
* a run that ended with a numerical failure (status nonfinite, not_converged, zeno, failed) or a branch that
  stalled, whose corrector failed or that met a singular step exits with 1; a Lyapunov spectrum that has not
  converged is a result with its error bars (exit 0, its status says so).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import warnings

from ..errors import TippediskError, TippediskWarning
from ..version import __version__
from . import (animate, basins, bifurcation, continuation, critical_spin, fit, lyapunov, outcome_map,  # noqa: F401
               periodic_orbits, plot, poincare, simulate, stability_map, study)  # registration
from .registry import COMMANDS

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report it


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


def _one_line_warnings(command: str):
    """Show the library's warnings (e.g. a damaged chunk recomputed) as one line each."""

    def show(message, category, filename, lineno, file=None, line=None):
        kind = "note" if issubclass(category, TippediskWarning) else "warning"
        text = " ".join(str(message).split())
        print(f"tippedisk {command}: {kind}: {text}", file=sys.stderr)

    return show


def main(argv: list[str] | None = None) -> int:
    code = _run(argv)
    if argv is None:  # the real command: its result is written and said; Ctrl-C while the interpreter shuts down
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # (atexit handlers, e.g. dask's client) would print a traceback
    return code


def _run(argv: list[str] | None) -> int:
    for stream in (sys.stdout, sys.stderr):  # file names with bytes that are not UTF-8 print as \xNN
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    command = "?"
    try:
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exc:  # --help, --version, or a usage error (one line on stderr, status 2)
            return int(exc.code or 0)
        command = args.command
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warnings(command)
            return COMMANDS[command].run(args)
    except TippediskError as exc:
        print(f"tippedisk {command}: error: {' '.join(exc.cli_message().split())}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"tippedisk {command}: error: not enough memory for this request; use fewer grid points "
              "or a shorter run", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        text = str(exc) if str(exc) else "interrupted; nothing stored"
        print(f"tippedisk {command}: {text}", file=sys.stderr)
        if argv is None:  # the real command: do not wait for worker threads finishing their chunk
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader of the output went away (| head): nothing to say to it
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # the environment (disk full, a file removed meanwhile): one line, not a traceback
        where = f" '{exc.filename}'" if getattr(exc, "filename", None) else ""
        print(f"tippedisk {command}: error: {exc.strerror or exc}{where}; check the path, the disk space and "
              "the permissions", file=sys.stderr)
        return 2

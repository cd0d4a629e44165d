"""``tippedisk study``: run a study of the installed package ``tippedisk_studies`` (the repository's studies/)."""

from __future__ import annotations

import importlib
import pkgutil
import re
import shutil
from pathlib import Path

from ..errors import Interrupted, OutputError, ParameterError
from ..files import check_output, show
from .registry import command

STUDIES_PACKAGE = "tippedisk_studies"


def names() -> list[str]:
    """Study names, sorted (modules of tippedisk_studies not starting with an underscore)."""
    package = importlib.import_module(STUDIES_PACKAGE)
    return sorted(m.name for m in pkgutil.iter_modules(package.__path__) if not m.name.startswith("_"))


def run(name: str, output_dir: str = "output", quick: bool = False):
    """Run study ``name``; returns what its ``main`` returns."""
    if name not in names():
        raise ParameterError(f"unknown study {name!r}; `tippedisk study --list` prints the names")
    module = importlib.import_module(f"{STUDIES_PACKAGE}.{name}")
    return module.main(output_dir, quick=quick)


def summary(doc: str | None) -> str:
    """The first sentence of a docstring on one line, whole (not its first line, which cut sentences)."""
    text = " ".join((doc or "").strip().split("\n\n")[0].split())
    end = re.search(r"(?<!\bFig)(?<!\bFigs)(?<!\bSect)(?<!e\.g)(?<!i\.e)[.?!](?=\s|$)", text)
    return text[:end.end()] if end else text


def _arguments(p) -> None:
    try:
        available = names()
    except ImportError:  # pragma: no cover - the studies are not installed
        available = []
    p.add_argument("name", nargs="?", metavar="NAME", help="study name: " + (", ".join(available) or "(none installed)"))
    p.add_argument("--list", action="store_true", help="print the study names, each with the first sentence of its docstring")
    p.add_argument("--output-dir", default="output",
                   help="folder for the datasets and figures (default output/; created if missing; a study "
                        "replaces its own files there)")
    p.add_argument("--quick", action="store_true", help="reduced size (seconds): a smoke test of the study")


@command("study", "run a study (datasets + figures); --list names them", _arguments)
def study(args) -> int:
    if args.list:
        for name in names():
            print(f"{name:<30} {summary(importlib.import_module(f'{STUDIES_PACKAGE}.{name}').__doc__)}")
        return 0
    if not args.name:
        raise ParameterError("give a study name or --list")
    if args.name not in names():
        raise ParameterError(f"unknown study {args.name!r}; choose one of {', '.join(names())}")
    out = Path(args.output_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"--output-dir '{show(out)}' is a file; give a folder")
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"cannot create --output-dir '{show(out)}' ({exc.strerror}); give another folder") from None
    check_output(out / "probe.nc", option="--output-dir")  # writable, before the study starts
    try:
        run(args.name, args.output_dir, quick=args.quick)
    except OutputError:  # e.g. a full disk: no half-made output folder left behind
        if created:
            shutil.rmtree(out, ignore_errors=True)
        raise
    except KeyboardInterrupt:
        raise Interrupted(f"interrupted; the files the study finished stay in '{show(out)}' (rerun to redo it)") from None
    return 0

"""Find and run the study scripts of the repository's ``studies/`` folder.

A study is ``studies/NAME.py`` with a ``main(output_dir)`` that writes a dataset and a
figure. The folder is ``$TIPPEDISK_STUDIES`` or the ``studies/`` of the source checkout.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

from .errors import ParameterError


def folder() -> Path:
    path = Path(os.environ.get("TIPPEDISK_STUDIES", Path(__file__).resolve().parents[2] / "studies"))
    if not path.is_dir():
        raise ParameterError(f"no studies folder at {str(path)!r}; run from a source checkout or set TIPPEDISK_STUDIES")
    return path


def names() -> list[str]:
    """Study names, sorted."""
    return sorted(p.stem for p in folder().glob("*.py") if not p.stem.startswith("_"))


def run(name: str, output_dir: str = "output"):
    """Run study ``name``; returns what its ``main`` returns."""
    if name not in names():
        raise ParameterError(f"unknown study {name!r}; `tippedisk study --list` prints the names")
    path = folder() / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"tippedisk_study_{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(path.parent))  # studies share helpers such as _moreau_study.py
    try:
        spec.loader.exec_module(module)
        return module.main(output_dir)
    finally:
        sys.path.remove(str(path.parent))

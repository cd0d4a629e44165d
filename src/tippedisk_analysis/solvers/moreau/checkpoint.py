"""Checkpoints of long Moreau runs: the step loop's full state in an .npz file, written atomically.

A later call with the same run (same fingerprint) resumes from it; the result is bitwise that
of an uninterrupted run.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from ...errors import ParameterError
from ...files import atomic_write, show
from ...parameters import to_dict
from .layout import DT


def fingerprint(model, setup, initial, t_end, state, par, flags) -> str:
    """Everything that determines a run, to refuse resuming another run's checkpoint."""
    return json.dumps({"model": model.name, "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
                       "state": None if state is None else np.asarray(state[0]).tolist() + np.asarray(state[1]).tolist(),
                       "par": par.tolist(), "ipar": flags.tolist()}, sort_keys=True)


def stored_progress(path) -> tuple[float, float] | None:
    """(simulated time reached, t_end) of the checkpoint at ``path``; None if missing or unreadable."""
    try:
        with np.load(path) as f:
            run = json.loads(str(f["fingerprint"]))
            return int(f["done"]) * float(run["par"][DT]), float(run["t_end"])
    except Exception:  # noqa: BLE001 - missing, damaged or foreign: nothing to report
        return None


class CheckpointError(ParameterError):
    """A checkpoint that cannot be resumed: damaged, incomplete, or of another run."""


class Checkpoint:
    """The loop state of one Moreau run in an .npz file."""

    FIELDS = ("q", "u", "ex_G", "P_last", "stats", "out", "done", "status")

    def __init__(self, path, run_fingerprint: str):
        self.path = Path(path)
        self.fingerprint = run_fingerprint

    def exists(self) -> bool:
        return self.path.is_file()

    def load(self) -> dict:
        try:
            with np.load(self.path) as f:
                stored = {name: f[name].copy() for name in f.files}
        except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
            raise CheckpointError(f"checkpoint '{show(self.path)}' is unreadable ({exc.__class__.__name__}); "
                                 "delete it to start afresh",
                                 cli=f"checkpoint '{show(self.path)}' is unreadable ({exc.__class__.__name__}); "
                                     "give --overwrite (or delete it) to start afresh") from None
        if str(stored.get("fingerprint")) != self.fingerprint:
            raise CheckpointError(f"checkpoint '{show(self.path)}' belongs to a different run; delete it or "
                                 "choose another output file",
                                 cli=f"checkpoint '{show(self.path)}' belongs to a different run; give --overwrite "
                                     "(or delete it) to start afresh, or another --output")
        missing = [name for name in self.FIELDS if name not in stored]
        if missing:
            raise CheckpointError(f"checkpoint '{show(self.path)}' lacks {', '.join(missing)}; delete it to start "
                                 "afresh", cli=f"checkpoint '{show(self.path)}' lacks {', '.join(missing)}; give "
                                               "--overwrite (or delete it) to start afresh")
        return {name: stored[name] for name in self.FIELDS}

    def save(self, **state) -> None:
        """Store the loop state (unique temporary file, then an atomic rename: files.atomic_write)."""

        def write(tmp):
            with open(tmp, "wb") as f:  # a file object: np.savez would append .npz to a name
                np.savez(f, fingerprint=self.fingerprint, **state)

        atomic_write(self.path, write)

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)

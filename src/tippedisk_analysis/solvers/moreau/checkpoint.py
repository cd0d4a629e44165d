"""Checkpoints of long Moreau runs: the step loop's full state in an .npz file, written atomically.

A later call with the same run (same fingerprint) resumes from it; the result is bitwise that
of an uninterrupted run.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from ...errors import ParameterError
from ...parameters import to_dict


def fingerprint(model, setup, initial, t_end, state, par, flags) -> str:
    """Everything that determines a run, to refuse resuming another run's checkpoint."""
    return json.dumps({"model": model.name, "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
                       "state": None if state is None else np.asarray(state[0]).tolist() + np.asarray(state[1]).tolist(),
                       "par": par.tolist(), "ipar": flags.tolist()}, sort_keys=True)


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
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise ParameterError(f"checkpoint {str(self.path)!r} is unreadable ({exc.__class__.__name__}); "
                                 "delete it to start afresh") from None
        if str(stored.get("fingerprint")) != self.fingerprint:
            raise ParameterError(f"checkpoint {str(self.path)!r} belongs to a different run; delete it or "
                                 "choose another output file")
        missing = [name for name in self.FIELDS if name not in stored]
        if missing:
            raise ParameterError(f"checkpoint {str(self.path)!r} lacks {', '.join(missing)}; delete it to start afresh")
        return {name: stored[name] for name in self.FIELDS}

    def save(self, **state) -> None:
        tmp = self.path.with_name(f"{self.path.name}.{os.getpid()}.part.npz")
        try:
            np.savez(tmp, fingerprint=self.fingerprint, **state)
            os.replace(tmp, self.path)
        finally:
            tmp.unlink(missing_ok=True)

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)

"""Bad inputs, collisions, huge grids, unwritable paths and Ctrl-C through the real command line.

Every row runs ``tippedisk`` in a subprocess and checks the promise of cli/__init__.py: the exit
status, one line on stderr without a traceback, and nothing half-written (no output where none
is due, no temporary ``.part`` file anywhere). Below the table: two writers to one output, SIGINT
sent mid-run (resume is bit-identical), a damaged chunk recomputed with a note.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import tippedisk_analysis as td
from tippedisk_analysis.files import HOLD_VARIABLE

SRC = str(Path(__file__).resolve().parents[1] / "src")
ENV = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
CLI = [sys.executable, "-m", "tippedisk_analysis.cli"]
BAD = os.fsdecode(b"\xff-run.nc")  # a file name that is not UTF-8
MAP = ["outcome-map", "--omega", "10:80:40", "--eps", "0.05:0.3:10", "--t-end", "3", "--chunk-size", "10"]


SAFETY_TIMEOUT = 900  # [s] only ends a command that hangs; no test waits for a time to pass


def tippedisk(*args, cwd, timeout=SAFETY_TIMEOUT, runner=CLI) -> subprocess.CompletedProcess:
    return subprocess.run([*runner, *map(str, args)], cwd=cwd, env=ENV, capture_output=True, timeout=timeout)


def _stderr(proc) -> str:
    return proc.stderr.decode("utf-8", "backslashreplace")


def _snapshot(root: Path) -> dict:
    return {p.relative_to(root): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "dir"
            for p in sorted(root.rglob("*"))}


PROGRESS = re.compile(r"^([\w -]+:\s+\d+%\||tippedisk [\w-]+: note: compiling )")
"""A tqdm bar (shown once work has run for 2 s) or the notice of a slow first compile (a cold heyoka cache)."""


def _message(err: str) -> str:
    """The one line a command ends with; before it only progress-bar updates and compile notices are allowed
    (a slow machine shows what a fast one finishes first), never a traceback."""
    lines = [line for line in err.replace("\r", "\n").splitlines() if line.strip()]
    assert lines and "Traceback" not in err, err
    assert all(PROGRESS.match(line) for line in lines[:-1]), err
    return lines[-1]


def _no_part_files(root: Path) -> None:
    parts = [p for p in root.rglob("*") if ".part" in os.fsdecode(p.name)]
    assert not parts, parts


@pytest.fixture(scope="module")
def ws(tmp_path_factory):
    """A workspace: a dataset, a directory, an empty (nonfinite) run, a foreign file, a non-UTF-8 name."""
    root = tmp_path_factory.mktemp("faults")
    proc = tippedisk("simulate", "--t-end", "0.05", "-o", "existing.nc", cwd=root)
    assert proc.returncode == 0, _stderr(proc)
    proc = tippedisk("simulate", "--alpha-dot", "1e200", "--t-end", "0.05", "-o", "empty.nc", cwd=root)
    assert proc.returncode == 1 and td.load(root / "empty.nc").sizes["time"] == 0  # status nonfinite, 0 samples
    (root / "adir").mkdir()
    (root / "fig.png").mkdir()  # a directory named like a figure
    (root / "existing.png").write_bytes(b"\x89PNG not really")
    (root / "notes.nc").write_text("not a dataset")
    shutil.copy(root / "existing.nc", root / os.fsencode(BAD).decode("utf-8", "surrogateescape"))
    return root


ROWS = [
    # id, arguments, exit status, fragment of the one-line message
    ("output-is-a-directory", ["simulate", "-o", "adir"], 2, "is a directory"),
    ("output-is-a-device", ["simulate", "-o", "/dev/full"], 2, "not a regular file"),
    ("output-directory-missing", ["simulate", "-o", "missing/run.nc"], 2, "does not exist"),
    ("output-directory-unwritable", ["simulate", "-o", "/sys/run.nc"], 2, "cannot create files in '/sys'"),
    ("output-exists", ["simulate", "-o", "existing.nc"], 2, "exists; give --overwrite"),
    ("output-not-utf8", ["simulate", "-o", BAD], 2, "not valid UTF-8"),
    ("map-output-is-a-directory", [*MAP, "-o", "adir"], 2, "is a directory"),
    ("bifurcation-output-exists", ["bifurcation", "--omega", "20:80:3", "-o", "existing.nc"], 2, "--overwrite"),
    ("plot-output-is-a-directory", ["plot", "existing.nc", "-o", "fig.png"], 2, "is a directory"),
    ("plot-output-exists", ["plot", "existing.nc"], 2, "exists; give --overwrite"),
    ("plot-no-samples", ["plot", "empty.nc", "-o", "empty.png"], 2, "holds no samples"),
    ("plot-foreign-file", ["plot", "notes.nc", "-o", "notes.png"], 2, "not a netCDF"),
    ("plot-input-not-utf8", ["plot", BAD, "-o", "bad.png"], 2, "not a valid UTF-8 file name"),
    ("animate-no-samples", ["animate", "empty.nc", "-o", "empty.gif"], 2, "holds no samples"),
    ("animate-unknown-format", ["animate", "existing.nc", "-o", "run.txt"], 2, "cannot write an animation"),
    ("outcome-map-5-axes", ["outcome-map", "--omega", "10:80:60", "--eps", "0.1:0.2:60", "--mu", "0.1:0.3:60",
                            "--e", "0.001:0.003:60", "--dgamma0", "0.05:0.1:60", "-o", "big.nc"], 2, "of memory"),
    ("outcome-map-100000^2", ["outcome-map", "--omega", "10:80:100000", "--eps", "0.1:0.2:100000", "-o", "big.nc"],
     2, "use fewer grid points"),
    ("bifurcation-1e8", ["bifurcation", "--omega", "20:80:100000000", "-o", "big.nc"], 2, "of memory"),
    ("stability-map-30000^2", ["stability-map", "--omega", "0:100:30000", "--eps", "0.02:0.5:30000", "-o", "big.nc"],
     2, "of memory"),
    ("lyapunov-100000^2", ["lyapunov", "--omega", "10:80:100000", "--eps", "0.02:0.4:100000", "-o", "big.nc"], 2,
     "use fewer grid points"),
    ("basins-100000^2", ["basins", "--dgamma0=-3:3:100000", "--beta0", "1:2:100000", "-o", "big.nc"], 2,
     "use fewer grid points"),
    ("lyapunov-output-exists", ["lyapunov", "-o", "existing.nc"], 2, "exists; give --overwrite"),
    ("periodic-orbits-output-exists", ["periodic-orbits", "--system", "hopf", "-o", "existing.nc"], 2,
     "exists; give --overwrite"),
    ("simulate-ode-1e9-s", ["simulate", "--t-end", "1e9", "-o", "big.nc"], 2, "--dt-output"),
    ("simulate-moreau-1e6-s", ["simulate", "--model", "m2", "--t-end", "1e6", "-o", "big.nc"], 2, "--store-every"),
    ("poincare-1e12-s", ["poincare", "--t-end", "1e12", "-o", "big.nc"], 2, "--max-crossings"),
    ("scheduler-local-0", [*MAP, "--scheduler", "local:0", "-o", "m.nc"], 2, "N >= 1"),
    ("scheduler-local-x", [*MAP, "--scheduler", "local:x", "-o", "m.nc"], 2, "N >= 1"),
    ("outcome-map-stop-below-start", ["outcome-map", "--omega", "80:10:3", "--eps", "0.1:0.2:2", "-o", "m.nc"], 2,
     "STOP < START"),
    ("bifurcation-stop-below-start", ["bifurcation", "--omega", "80:20:3", "-o", "b.nc"], 2, "STOP < START"),
    ("stability-map-stop-below-start", ["stability-map", "--omega", "80:10:3", "--eps", "0.1:0.2:2", "-o", "s.nc"],
     2, "STOP < START"),
    ("normalize-euler-moreau", ["simulate", "--model", "m1", "--normalize-quaternion", "-o", "n.nc"], 2,
     "uses Euler angles"),
    ("normalize-ode", ["simulate", "--model", "ode2", "--normalize-quaternion", "-o", "n.nc"], 2,
     "--normalize-quaternion applies to the Moreau quaternion models"),
    ("disk-given-incomplete", ["simulate", "--disk", "given", "--mass", "0.5", "-o", "n.nc"], 2, "missing"),
    ("disk-inertia-without-given", ["simulate", "--A", "3e-4", "-o", "n.nc"], 2, "--disk given"),
    ("disk-geometry-with-mass", ["simulate", "--disk", "geometry", "--mass", "0.5", "-o", "n.nc"], 2,
     "follow from the geometry"),
    ("disk-hole-without-geometry", ["simulate", "--hole-offset", "0.01", "-o", "n.nc"], 2, "--disk geometry"),
    ("disk-geometry-e-beyond-hole", ["stability-map", "--omega", "30:40:2", "--eps", "0.1", "--e", "0.001:0.02:3",
                                     "--disk", "geometry", "-o", "s.nc"], 2, "hole offset"),
    ("unknown-model", ["simulate", "--model", "m11", "-o", "n.nc"], 2, "unknown model"),
    ("unknown-study", ["study", "fig99"], 2, "unknown study"),
    ("study-output-dir-is-a-file", ["study", "stability_map", "--output-dir", "existing.nc"], 2, "is a file"),
]


@pytest.mark.parametrize("args, status, fragment", [r[1:] for r in ROWS], ids=[r[0] for r in ROWS])
def test_bad_input_one_line_nothing_written(ws, args, status, fragment):
    before = _snapshot(ws)
    proc = tippedisk(*args, cwd=ws)
    after = _snapshot(ws)
    err = _stderr(proc)
    assert proc.returncode == status, err
    assert "Traceback" not in err and err.count("\n") == 1 and "error:" in err, err
    assert fragment in err, err
    assert after == before  # nothing written, nothing replaced, no temporary file
    assert proc.stdout == b""


def test_mp4_without_ffmpeg_is_refused(ws):
    from matplotlib import animation

    if animation.writers.is_available("ffmpeg"):
        pytest.skip("ffmpeg is installed: .mp4 works")
    proc = tippedisk("animate", "existing.nc", "-o", "run.mp4", cwd=ws)
    assert proc.returncode == 2 and "needs ffmpeg" in _stderr(proc) and _stderr(proc).count("\n") == 1
    assert not (ws / "run.mp4").exists()


def test_damaged_checkpoint_is_one_line_and_overwrite_discards_it(tmp_path):
    (tmp_path / "m.nc.checkpoint.npz").write_bytes(b"PK\x03\x04 damaged")
    proc = tippedisk("simulate", "--model", "m5", "--t-end", "0.02", "-o", "m.nc", cwd=tmp_path)
    err = _stderr(proc)
    assert proc.returncode == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert "checkpoint 'm.nc.checkpoint.npz' is unreadable (BadZipFile); give --overwrite" in err
    assert not (tmp_path / "m.nc").exists()
    proc = tippedisk("simulate", "--model", "m5", "--t-end", "0.02", "-o", "m.nc", "--overwrite", cwd=tmp_path)
    assert proc.returncode == 0, _stderr(proc)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.nc"]


def test_chunks_of_another_configuration_name_the_fix(tmp_path):
    chunks = tmp_path / "m.nc.chunks"
    chunks.mkdir()
    (chunks / "config.json").write_text('{"other": 1}')
    (chunks / "chunk_00000.nc").write_bytes(b"x")
    small = ["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "--t-end", "0.2", "-o", "m.nc"]
    proc = tippedisk(*small, cwd=tmp_path)
    err = _stderr(proc)
    assert proc.returncode == 2 and err.count("\n") == 1
    assert "different outcome map configuration" in err and "--overwrite" in err and "--output" in err
    assert (chunks / "chunk_00000.nc").exists() and not (tmp_path / "m.nc").exists()
    proc = tippedisk(*small, "--overwrite", cwd=tmp_path)
    assert proc.returncode == 0, _stderr(proc)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.nc"]


def _concurrently(args, cwd, n=2):
    procs = [subprocess.Popen([*CLI, *args], cwd=cwd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for _ in range(n)]
    outputs = [p.communicate(timeout=SAFETY_TIMEOUT) for p in procs]
    return [(p.returncode, out, err) for p, (out, err) in zip(procs, outputs)]


@pytest.mark.parametrize("args", [
    ["simulate", "--t-end", "0.5", "-o", "c.nc", "--overwrite"],
    ["outcome-map", "--omega", "10:80:10", "--eps", "0.05:0.3:4", "--t-end", "1", "--chunk-size", "4", "-o", "c.nc",
     "--overwrite"],
], ids=["simulate", "outcome-map"])
def test_two_writers_to_one_output_both_finish(tmp_path, args):
    for code, out, err in _concurrently(args, tmp_path):
        assert code == 0 and b"Traceback" not in err, err.decode()
    assert td.load(tmp_path / "c.nc").attrs["status"] == "completed"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.nc"]  # no chunk directory, no temporary file


def _as_from_a_terminal():
    """In the child before exec: SIGINT to its default, as a command typed at a terminal has it (a suite
    started in the background by a non-interactive shell inherits SIGINT ignored, and Python then never
    raises KeyboardInterrupt)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class _Running:
    """A command started in the background whose stderr is collected as it arrives."""

    def __init__(self, args, cwd, runner=CLI, hold_after: str | None = None):
        env = {**ENV, HOLD_VARIABLE: hold_after} if hold_after else ENV
        self.proc = subprocess.Popen([*runner, *args], cwd=cwd, env=env, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, preexec_fn=_as_from_a_terminal)
        self._err = bytearray()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        while chunk := os.read(self.proc.stderr.fileno(), 4096):
            self._err += chunk

    @property
    def stderr(self) -> str:
        return bytes(self._err).decode("utf-8", "backslashreplace")


def _interrupt(args, cwd, when, runner=CLI, hold_after: str | None = None):
    """Start the command, wait for the event ``when(run)`` (a chunk file, a checkpoint, a progress line on
    ``run.stderr``), send SIGINT as Ctrl-C does, return (status, stderr).

    The trigger is an event the command produces, never elapsed time, so a cold heyoka cache or a loaded
    machine only makes the test wait longer; ``hold_after`` ("chunk", "checkpoint") makes the command wait
    after that event until the signal (files.hold_for_interrupt), so a run that would finish milliseconds
    later cannot outrun the test. SAFETY_TIMEOUT only ends a run that hangs."""
    run = _Running(args, cwd, runner, hold_after)
    deadline = time.monotonic() + SAFETY_TIMEOUT
    while run.proc.poll() is None and not when(run):
        assert time.monotonic() < deadline, f"no trigger event within {SAFETY_TIMEOUT} s: {run.stderr}"
        time.sleep(0.02)
    assert run.proc.poll() is None, f"the run ended before it could be interrupted: make it longer. {run.stderr}"
    run.proc.send_signal(signal.SIGINT)
    run.proc.wait(timeout=SAFETY_TIMEOUT)
    run._reader.join(timeout=SAFETY_TIMEOUT)
    return run.proc.returncode, run.stderr


@pytest.mark.slow
def test_sigint_mid_outcome_map_resumes_bit_identically_and_recomputes_a_damaged_chunk(tmp_path):
    chunks = tmp_path / "m.nc.chunks"
    code, err = _interrupt([*MAP, "-o", "m.nc"], tmp_path, lambda run: len(list(chunks.glob("chunk_*.nc"))) >= 2)
    message = _message(err)
    assert code == 130 and message.startswith("tippedisk outcome-map: interrupted; "), err
    assert "of 40 chunks stored" in message and "rerun the same command to resume" in message
    stored = sorted(chunks.glob("chunk_*.nc"))
    assert len(stored) >= 2 and not (tmp_path / "m.nc").exists()
    _no_part_files(tmp_path)
    stored[0].write_bytes(stored[0].read_bytes()[:100])  # damaged, e.g. by a full disk
    proc = tippedisk(*MAP, "-o", "m.nc", cwd=tmp_path)
    err = _stderr(proc)
    assert proc.returncode == 0, err
    notes = [line for line in err.splitlines() if "note:" in line]
    assert len(notes) == 1 and f"chunk 'm.nc.chunks/{stored[0].name}' is damaged" in notes[0] and "recomputing" in notes[0]
    fresh = tippedisk(*MAP, "-o", "fresh.nc", cwd=tmp_path)
    assert fresh.returncode == 0
    resumed, reference = td.load(tmp_path / "m.nc"), td.load(tmp_path / "fresh.nc")
    xr.testing.assert_identical(resumed.drop_attrs(), reference.drop_attrs())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh.nc", "m.nc"]


def test_sigint_before_the_first_chunk_leaves_nothing_that_blocks_other_settings(tmp_path):
    code, err = _interrupt([*MAP, "-o", "m.nc"], tmp_path, lambda run: (tmp_path / "m.nc.chunks").is_dir())
    message = _message(err)
    assert code == 130 and message.startswith("tippedisk outcome-map: interrupted; "), err
    if "0 of 40 chunks stored" in message:  # interrupted before the first chunk: no directory is left behind
        assert not (tmp_path / "m.nc.chunks").exists()
    other = ["outcome-map", "--omega", "30:50:2", "--eps", "0.1:0.2:2", "--t-end", "0.2", "-o", "m.nc", "--overwrite"]
    assert tippedisk(*other, cwd=tmp_path).returncode == 0


def test_sigint_mid_bifurcation_resumes(tmp_path):
    args = ["bifurcation", "--omega", "20:80:64", "--t-end", "6", "--t-transient", "4", "-o", "b.nc"]
    chunks = tmp_path / "b.nc.chunks"
    code, err = _interrupt(args, tmp_path, lambda run: any(chunks.glob("chunk_*.nc")), hold_after="chunk")
    message = _message(err)
    assert code == 130 and "1 of 8 chunks stored" in message and "resume" in message, err
    proc = tippedisk(*args, cwd=tmp_path)
    assert proc.returncode == 0, _stderr(proc)
    ds = td.load(tmp_path / "b.nc")
    assert ds.sizes["omega"] == 64 and int(ds["n_crossings"].sum()) == ds.sizes["point"]


@pytest.mark.slow
def test_sigint_mid_stability_map(tmp_path):
    """Interrupted once its progress bar shows (points computed): one line, nothing stored."""
    args = ["stability-map", "--omega", "0:100:1000", "--eps", "0.02:0.5:1000", "-o", "s.nc"]
    code, err = _interrupt(args, tmp_path, lambda run: "stability map:" in run.stderr)
    message = _message(err)
    assert code == 130 and message.startswith("tippedisk stability-map: interrupted after "), err
    assert "nothing stored" in message
    assert list(tmp_path.iterdir()) == []


CHECKPOINT_EVERY_STEP = [sys.executable, "-c", (
    "import sys; import tippedisk_analysis.defaults as d; d.CHECKPOINT_SECONDS = 0.0; "
    "from tippedisk_analysis.cli import main; sys.exit(main())")]


@pytest.mark.slow
def test_sigint_mid_moreau_run_resumes_bit_identically_from_its_checkpoint(tmp_path):
    args = ["simulate", "--model", "m2", "--t-end", "2", "-o", "m.nc"]
    checkpoint = tmp_path / "m.nc.checkpoint.npz"
    code, err = _interrupt(args, tmp_path, lambda run: checkpoint.exists(), runner=CHECKPOINT_EVERY_STEP,
                           hold_after="checkpoint")
    message = _message(err)
    assert code == 130 and "interrupted; checkpoint at t = " in message, err
    assert "rerun the same command to resume" in message
    assert checkpoint.exists() and not (tmp_path / "m.nc").exists()
    _no_part_files(tmp_path)
    proc = tippedisk(*args, cwd=tmp_path, runner=CHECKPOINT_EVERY_STEP)
    assert proc.returncode == 0, _stderr(proc)
    assert tippedisk(*args[:-1], "fresh.nc", cwd=tmp_path).returncode == 0
    resumed, fresh = td.load(tmp_path / "m.nc"), td.load(tmp_path / "fresh.nc")
    for name in fresh.data_vars:
        np.testing.assert_array_equal(resumed[name].values, fresh[name].values, err_msg=name)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh.nc", "m.nc"]


def test_output_files_are_never_half_written(tmp_path):
    """A reader polling the output while two writers replace it only ever sees complete datasets."""
    td.save(xr.Dataset({"a": ("x", [1.0])}, attrs={"producer": "tippedisk_analysis", "kind": "simulation",
                                                     "status": "completed"}), tmp_path / "c.nc")
    seen, stop = [], threading.Event()

    def read():
        while not stop.is_set():
            try:
                seen.append(td.load(tmp_path / "c.nc").attrs["status"])
            except td.DatasetError as exc:
                seen.append(str(exc))
            time.sleep(0.01)

    reader = threading.Thread(target=read)
    reader.start()
    try:
        results = _concurrently(["simulate", "--t-end", "0.15", "-o", "c.nc", "--overwrite"], tmp_path)
    finally:
        stop.set()
        reader.join()
    assert all(code == 0 for code, _, _ in results)
    assert seen and set(seen) == {"completed"}

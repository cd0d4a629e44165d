"""Every benchmark runs in its quick mode and prints its figures (a smoke run: benchmarks rot unless something
runs them). No timing is asserted: the figures belong in the closing notes and docs, not in pass/fail."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = sorted((Path(__file__).resolve().parents[1] / "benchmarks").glob("bench_*.py"))
FIGURE = re.compile(r"\d(\.\d+)?(e[-+]?\d+)?\s*(ms|s|x|steps/s|MB)\b")


def test_the_benchmarks_are_found():
    assert {p.stem for p in BENCHMARKS} >= {"bench_ode", "bench_startup", "bench_moreau", "bench_stability"}


@pytest.mark.slow
@pytest.mark.parametrize("path", BENCHMARKS, ids=lambda p: p.stem)
def test_benchmark_quick_mode_finishes_and_prints_its_figures(path):
    proc = subprocess.run([sys.executable, str(path), "--quick"], capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    figures = [line for line in proc.stdout.splitlines() if FIGURE.search(line)]
    assert len(figures) >= 2, proc.stdout

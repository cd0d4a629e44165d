"""Figures of Sect. 6 (plotting/simulation.py): stroboscope viewpoint, no clipped curves, every run drawn."""

import math
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import xarray as xr

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import tippedisk_analysis as td  # noqa: E402
from tippedisk_analysis.plotting import simulation as sim  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture(scope="module")
def fig17():
    return td.load(DATA / "fig17_stroboscope.nc")


def test_stroboscope_shows_one_frame_per_full_turn(fig17):
    """One viewpoint: successive frames are a full turn (2 pi in alpha) apart, never half a turn."""
    frames = sim.stroboscope_frames(fig17)
    alpha = fig17.alpha.values[frames]
    steps = np.abs(np.diff(alpha))
    rate = float(np.max(np.abs(fig17.alpha_dot.values))) * float(fig17.time[1] - fig17.time[0])
    np.testing.assert_allclose(steps, 2 * math.pi, atol=rate + 1e-9)
    assert float(fig17.time.values[frames[-1]]) > 1.29  # the last frame shows the finished inversion
    fig = sim.stroboscopic_figure(fig17, description="Fig. 16 text")
    assert len(fig.axes) == 2 and "Fig. 16 text" in fig.axes[1].texts[0].get_text()
    plt.close(fig)


def test_wrapped_angle_keeps_every_sample_in_range():
    gamma = np.linspace(-2.0, 40.0, 2001)
    w = sim.wrapped_angle(gamma)
    finite = w[np.isfinite(w)]
    assert finite.size == gamma.size  # only separators were added
    assert np.all((finite >= -0.5 * math.pi) & (finite < 1.5 * math.pi))
    np.testing.assert_allclose(np.mod(finite - gamma + 1e-12, 2 * math.pi), 0.0, atol=1e-9)


def test_comparison_figure_draws_every_run_unclipped_and_marks_events():
    t = np.linspace(0.0, 25.0, 2501)
    runs = {}
    for label, gamma in {"falls": np.where(t < 17, 1.6, 1.6 + 3.0 * (t - 17) ** 2),
                         "stays": 1.6 + 0.1 * np.sin(30 * t)}.items():
        runs[label] = xr.Dataset({"gamma": ("time", gamma), "E_tot": ("time", 0.38 - 0.001 * t)}, coords={"time": t})
    fig = sim.comparison_figure(runs, styles={"stays": {"color": "tab:blue", "marker": "s"}},
                                events={"falls": (17.5, "not inverted")}, zoom=0.8, wrap=True)
    gamma_ax, zoom_ax, energy_ax = fig.axes[:3]
    low, high = gamma_ax.get_ylim()
    for line in gamma_ax.lines:
        y = np.asarray(line.get_ydata(), dtype=float)
        assert np.all(y[np.isfinite(y)] >= low) and np.all(y[np.isfinite(y)] <= high)  # nothing clipped
    labels = [line.get_label() for line in gamma_ax.lines]
    assert {"falls", "stays"} <= set(labels) and any("not inverted from t = 17.5 s" in lab for lab in labels)
    assert {line.get_label() for line in energy_ax.lines} >= {"falls", "stays"}
    plt.close(fig)


def test_simulation_figure_labels_levels_outside_the_axes():
    ds = td.load(DATA / "fig13_ode_inversion.nc")
    fig = sim.simulation_figure(ds, companion=ds)
    z_ax = fig.axes[1]
    texts = {a.get_text(): a for a in z_ax.texts}
    assert {"r - e", "r + e"} <= set(texts)
    assert all(a.xy[0] > 1.0 for a in texts.values())  # right of the plot area, where no curve runs
    assert all("[" in ax.get_ylabel() and "]" in ax.get_ylabel() for ax in fig.axes)
    plt.close(fig)

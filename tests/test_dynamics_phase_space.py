"""Basins of attraction and Poincaré sections of any System (tippedisk_analysis.dynamics), proven on systems
with known answers: AUTO-07p's 'ab', the damped double well, the van der Pol oscillator."""

from __future__ import annotations

import math
import re
from pathlib import Path

import heyoka as hy
import numpy as np
import pytest
from scipy.optimize import brentq

from tippedisk_analysis import ParameterError
from tippedisk_analysis import dynamics as dy

VDP_PERIOD = 6.6632868593231  # van der Pol, mu = 1 (literature value)
AB_PERIOD_012 = 2.6727661404  # 'ab' at D = 0.12: AUTO-07p's period of the stable orbit


@pytest.fixture(scope="module")
def ab():
    return dy.textbook_system("ab")


AB_GRID = dict(names=("u1", "u2"), lower=(-0.2, -1.0), upper=(1.2, 10.0), cells=(70, 110))
AB_AXES = {"u1": (0.0, 1.0, 5), "u2": (0.0, 8.0, 5)}


def test_ab_has_one_periodic_attractor_at_d_012_with_auto07p_period(ab):
    """Between the homoclinic limit (D = 0.1055) and the Hopf point (0.1309) the orbit born at the Hopf point is
    the only attractor: every initial condition reaches it, and its period is AUTO-07p's."""
    ds = dy.basins(ab, dy.Grid(**AB_GRID), AB_AXES, pars=ab.with_pars(D=0.12), horizon=400.0, progress=False)
    assert ds.attrs["kind"] == "basins" and ds.attrs["status"] == "completed"
    assert ds.sizes["attractor"] == 1 and np.all(ds.outcome.values == 0)
    assert int(ds.attractor_kind[0]) == 1  # periodic
    assert float(ds.attractor_period[0]) == pytest.approx(AB_PERIOD_012, rel=1e-6)
    assert float(ds.basin_fraction[0]) == 1.0


def test_ab_has_the_lower_equilibrium_as_its_attractor_at_d_0095(ab):
    """Below the homoclinic limit the orbit is gone and the upper equilibrium is unstable (below its Hopf point):
    every run ends on the lower equilibrium u2 = B u1 / (1 + beta), D = u1 exp(-u2) / (1 - u1)."""
    D = 0.095
    u1 = brentq(lambda u: u * math.exp(-14.0 * u / 3.0) / (1 - u) - D, 1e-9, 0.3)
    ds = dy.basins(ab, dy.Grid(**AB_GRID), AB_AXES, pars=ab.with_pars(D=D), horizon=400.0, progress=False)
    assert ds.sizes["attractor"] == 1 and np.all(ds.outcome.values == 0)
    assert int(ds.attractor_kind[0]) == 0  # equilibrium
    np.testing.assert_allclose(ds.attractor_state.values[0], [u1, 14.0 * u1 / 3.0], atol=1e-9)


def test_double_well_basins_are_swapped_by_the_symmetry():
    """x'' + 0.3 x' - x + x^3 = 0: two stable foci (+-1, 0) whose basins are images under (x, v) -> -(x, v).
    The foci decay slowly (rate 0.15, period 4.5): the spiral's equilibrium is recognised from its Lyapunov
    function, not only from the spreads of one short window."""
    well = dy.textbook_system("double_well")
    grid = dy.Grid(("x", "v"), (-2.5, -2.5), (2.5, 2.5), (50, 50))
    ds = dy.basins(well, grid, {"x": (-2.0, 2.0, 10), "v": (-2.0, 2.0, 10)}, horizon=500.0, progress=False)
    assert ds.sizes["attractor"] == 2 and np.all(ds.attractor_kind.values == 0)
    np.testing.assert_allclose(np.sort(ds.attractor_state.values[:, 0]), [-1.0, 1.0], atol=1e-9)
    np.testing.assert_allclose(ds.attractor_state.values[:, 1], 0.0, atol=1e-9)
    outcome = ds.outcome.values
    assert set(np.unique(outcome)) == {0, 1}
    assert np.all(outcome != outcome[::-1, ::-1])  # the grid is symmetric about the saddle at 0
    np.testing.assert_array_equal(ds.basin_fraction.values, [0.5, 0.5])


def test_van_der_pol_cycle_longer_than_the_locate_window_is_periodic():
    """mu = 1: the period 6.66 exceeds the default locate window (100 samples of 0.05 = 5 time units); the run
    goes on until it returns, and the one attractor is the cycle with the literature period."""
    vdp = dy.textbook_system("vanderpol")
    grid = dy.Grid(("x", "y"), (-3.0, -4.0), (3.0, 4.0), (60, 80))
    ds = dy.basins(vdp, grid, {"x": (-2.5, 2.5, 6), "y": (-3.0, 3.0, 6)}, pars=vdp.with_pars(mu=1.0), horizon=300.0,
                   progress=False)
    assert ds.sizes["attractor"] == 1 and np.all(ds.outcome.values == 0) and int(ds.attractor_kind[0]) == 1
    assert float(ds.attractor_period[0]) == pytest.approx(VDP_PERIOD, rel=1e-9)


def test_basins_name_a_grid_coordinate_the_system_does_not_have(ab):
    with pytest.raises(ParameterError, match="'w' is neither a state nor an observable of ab"):
        dy.basins(ab, dy.Grid(("u1", "w"), (0, 0), (1, 1), (4, 4)), AB_AXES, progress=False)


def test_van_der_pol_section_returns_with_the_period_to_the_same_point():
    vdp = dy.textbook_system("vanderpol")
    ds = dy.poincare_section(vdp, [2.0, 0.0], "x", 0.0, pars=vdp.with_pars(mu=1.0), t_end=200.0, transient=50.0)
    assert ds.attrs["kind"] == "poincare" and ds.attrs["status"] == "completed"
    assert ds.sizes["crossing"] == math.floor((200.0 - ds.time.values[0]) / VDP_PERIOD) + 1
    np.testing.assert_allclose(np.diff(ds.time.values), VDP_PERIOD, atol=1e-10)
    np.testing.assert_allclose(ds.x.values, 0.0, atol=1e-12)  # on the section
    assert np.all(ds.y.values > 0)  # upward crossings of x = 0 have y = x' > 0
    np.testing.assert_allclose(ds.y.values, ds.y.values[-1], atol=1e-10)  # one fixed point of the return map
    assert np.all(ds.time.values >= 50.0)  # after the transient
    from tippedisk_analysis.plotting.trajectories import poincare_figure

    ax = poincare_figure(ds).axes[0]  # the fixed point drawn as one point, not spread over a 1e-12 axis
    assert np.diff(ax.get_xlim())[0] >= 1.99e-3 and np.diff(ax.get_ylim())[0] >= 1.99e-3 * ds.y.values.max()


def test_a_section_on_an_observable_with_a_crossing_limit():
    """The radius r^2 = x^2 + v^2 of the harmonic oscillator is constant: no crossings of a larger level, and
    the crossings of the angle observable (modulo 2 pi) come once per period 2 pi."""
    x, v = hy.make_vars("x", "v")
    osc = dy.System("oscillator", (x, v), (v, -x), observables={"r2": x * x + v * v, "angle": hy.atan2(v, x)})
    none = dy.poincare_section(osc, [1.0, 0.0], "r2", 4.0, direction="any", t_end=30.0)
    assert none.sizes["crossing"] == 0 and none.attrs["status"] == "completed"
    ds = dy.poincare_section(osc, [1.0, 0.0], "angle", 1.0, modulo=True, direction="negative", t_end=100.0,
                             max_crossings=5)
    assert ds.sizes["crossing"] == 5 and "collected 5 crossing(s)" in ds.attrs["message"]
    np.testing.assert_allclose(np.diff(ds.time.values), 2 * math.pi, atol=1e-10)
    np.testing.assert_allclose(ds.angle.values, 1.0, atol=1e-10)
    np.testing.assert_allclose(ds.r2.values, 1.0, atol=1e-12)


def test_a_section_of_a_quantity_the_system_does_not_have():
    vdp = dy.textbook_system("vanderpol")
    with pytest.raises(ParameterError, match="'z' is neither a state nor an observable of vanderpol"):
        dy.poincare_section(vdp, [2.0, 0.0], "z")
    with pytest.raises(ParameterError, match="direction 'up' unknown"):
        dy.poincare_section(vdp, [2.0, 0.0], "x", direction="up")


def test_the_worked_example_of_docs_dynamics_runs_and_says_what_it_shows(tmp_path, monkeypatch):
    """docs/dynamics.md's Brusselator (a = 1) and docs/dynamics_hybrid.md's ball: their code blocks run as
    printed, and the pages' claims hold: the Hopf point at b = 1 + a^2 = 2 with frequency a = 1, stable orbits,
    the section's return time equal to the shooting period, the Lyapunov exponents (0, Floquet exponent), one
    periodic attractor with that period; the ball's period-1 orbit."""
    docs = Path(__file__).resolve().parents[1] / "docs"
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    for page in ("dynamics.md", "dynamics_hybrid.md"):
        for block in re.findall(r"```python\n(.*?)```", (docs / page).read_text(), re.S):
            exec(compile(block, f"docs/{page}", "exec"), ns)
    eq, po, ps, ly, at, T = (ns[k] for k in ("eq", "po", "ps", "ly", "at", "T"))
    assert eq.attrs["labels"] == "HOPF1"
    i = int(eq.special_index[0])
    assert float(eq.b[i]) == pytest.approx(2.0, abs=1e-12) and float(eq.special_frequency[0]) == pytest.approx(1.0)
    assert float(eq.special_l1[0]) < 0 and np.all(po.stability.values == 0)
    np.testing.assert_allclose(np.diff(ps.time.values), T, atol=1e-10)
    k = int(po.special_index[list(po.special_label.values).index("UZ1")])
    mu = po.multiplier_real.values[k][po.multiplier_trivial.values[k] == 0][0]
    assert abs(float(ly.exponents[0])) < 1e-3 and float(ly.exponents[1]) == pytest.approx(math.log(mu) / T, rel=1e-3)
    assert at.sizes["attractor"] == 1 and int(at.attractor_kind[0]) == 1
    assert float(at.attractor_period[0]) == pytest.approx(T, rel=1e-9)
    # the hybrid example: the bouncing ball's period-1 orbit, one impact per forcing period 2 pi / omega
    orbit = ns["orbit"]
    assert orbit.status == "converged" and orbit.period == pytest.approx(2 * math.pi / 20.0, rel=1e-12)
    assert orbit.stability == "stable" and abs(np.prod(orbit.multipliers[~orbit.trivial]) - 0.25) < 1e-10

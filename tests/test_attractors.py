"""Attractors by recurrences: the generic core on textbook systems with known attractors first
(a bistable gradient system and the damped Duffing oscillator with known basin boundaries, the Hopf
normal form and van der Pol limit cycles, a line of equilibria, labels), then the tippedisk problem
(spins checked against the closed-form stationary solutions), outcome maps, basins and basin fractions."""

from __future__ import annotations

import copy
import functools
import math

import heyoka as hy
import numpy as np
import pytest
import xarray as xr

from tippedisk_analysis import ParameterError, load
from tippedisk_analysis.analysis import basins as bs
from tippedisk_analysis.analysis import outcome_map as om
from tippedisk_analysis.analysis import stability
from tippedisk_analysis.analysis import stationary as st
from tippedisk_analysis.analysis.reduced import full_from_reduced
from tippedisk_analysis.cli import main
from tippedisk_analysis.dynamics import attractors as at
from tippedisk_analysis.dynamics import sweeps
from tippedisk_analysis.models import ode
from tippedisk_analysis.parameters import Friction, Setup


# ------------------------------------------------------------------ textbook problems
class Planar(at.Problem):
    """x' = f(x, y), y' = g(x, y) observed as (x, y); products instead of powers (heyoka's pow
    recursion divides by the base, which is 0 on the axes)."""

    state_names = ("x", "y")

    def __init__(self, rhs, n_pars=0, grid=None, terminal=None, name=""):
        self.rhs, self.n_pars, self.name = rhs, n_pars, name
        self.grid = grid or at.Grid(("x", "y"), (-3.0, -3.0), (3.0, 3.0), (60, 60))
        self.terminal = terminal
        self.terminal_labels = ("hit",) if terminal else ()

    @functools.lru_cache  # noqa: B019 - one compiled integrator per problem instance
    def integrator(self, batch_size):
        x, y = hy.make_vars("x", "y")
        p = [hy.par[i] for i in range(self.n_pars)]
        f, g = self.rhs(x, y, *p)
        kw = {"pars": np.zeros((self.n_pars, batch_size))} if self.n_pars else {}
        if self.terminal:
            kw["t_events"] = [hy.t_event_batch(self.terminal(x, y))]
        return hy.taylor_adaptive_batch([(x, f), (y, g)], np.zeros((2, batch_size)), tol=1e-12, **kw)

    def observe(self, states, pars):
        return np.asarray(states, dtype=float)


BISTABLE = Planar(lambda x, y: (x - x * x * x, -y), name="bistable")  # fixed points (+-1, 0), boundary x = 0
DUFFING = Planar(lambda x, y: (y, -0.25 * y + x - x * x * x), name="duffing")  # damped double well
HOPF = Planar(lambda x, y, mu, w: (mu * x - w * y - x * (x * x + y * y), w * x + mu * y - y * (x * x + y * y)),
              n_pars=2, name="hopf")
VDP = Planar(lambda x, y: (y, (1.0 - x * x) * y - x), grid=at.Grid(("x", "y"), (-4, -4), (4, 4), (80, 80)), name="vdp")
LINE = Planar(lambda x, y: (-x * (1.0 + y * y), 0.0 * y), name="line")  # every (0, y) is an equilibrium
SETTINGS = at.RecurrenceSettings(dt=0.1, horizon=200.0)


def grid_points(xs, ys):
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    return np.array([X.ravel(), Y.ravel()])


def table_of(problem, res, groups=None):
    cols = at.chunk_result(problem, res, 0)
    return at.assemble_table(problem, cols, np.zeros(len(res.labels)) if groups is None else groups, 1.0)


def test_grid_cells_wrap_and_flag_the_outside():
    g = at.Grid(("a", "phi"), (0.0, -math.pi), (1.0, math.pi), (10, 8), (False, True))
    keys = g.keys(np.array([[0.05, 0.05, 1.5, np.nan], [-math.pi + 0.1, math.pi + 0.1, 0.0, 0.0]]))
    assert keys[0] == keys[1] and keys[2] == -1 and keys[3] == -1  # phi wraps; outside and NaN: -1
    np.testing.assert_allclose(g.centre(keys[:1])[:, 0], [0.05, -math.pi + math.pi / 8])
    assert g.difference(np.array([0.0, math.pi - 0.01]), np.array([0.0, -math.pi + 0.01]))[1] == pytest.approx(
        -0.02 / (2 * math.pi / 8))
    with pytest.raises(ParameterError, match="lower < upper"):
        at.Grid(("a",), (1.0,), (0.0,), (3,))
    with pytest.raises(ParameterError, match="attractor_locate_steps"):
        at.RecurrenceSettings(attractor_locate_steps=4)


def test_bistable_basins_follow_the_known_boundary():
    """x' = x - x^3, y' = -y: two attractors (+-1, 0), basin boundary x = 0 (the saddle's stable manifold)."""
    xs = np.concatenate([np.linspace(-2.5, -0.05, 12), np.linspace(0.05, 2.5, 12)])
    x0 = grid_points(xs, np.linspace(-2.5, 2.5, 9))
    res = at.map_points(BISTABLE, SETTINGS, x0, np.zeros(0))
    outcome, table, _ = table_of(BISTABLE, res)
    assert len(table) == 2 and all(d.kind == "equilibrium" for d in table)
    for d in table:
        np.testing.assert_allclose(np.abs(d.representative), [1.0, 0.0], atol=1e-9)
    side = np.sign([table[k].representative[0] for k in outcome])
    np.testing.assert_array_equal(side, np.sign(x0[0]))
    assert res.t_assign.max() < SETTINGS.horizon and np.median(res.t_assign) < min(f.t_found for f in res.attractors)


def test_duffing_basins_agree_with_long_integrations():
    """Damped double well: the basin boundary is the saddle's stable manifold (spirals); the labels agree
    with the sign of x after a long direct integration of every initial condition."""
    x0 = grid_points(np.linspace(-2.0, 2.0, 14), np.linspace(-2.0, 2.0, 14))
    res = at.map_points(DUFFING, SETTINGS, x0, np.zeros(0))
    outcome, table, _ = table_of(DUFFING, res)
    assert sorted(np.round(d.representative[0], 9) for d in table) == [-1.0, 1.0]
    ta = hy.taylor_adaptive([(v, f) for v, f in zip(hy.make_vars("x", "y"), DUFFING.rhs(*hy.make_vars("x", "y")))],
                            [0.0, 0.0], tol=1e-14)
    reference = []
    for x in x0.T:
        ta.time, ta.state[:] = 0.0, x
        ta.propagate_until(300.0)
        reference.append(np.sign(ta.state[0]))
    np.testing.assert_array_equal(np.sign([table[k].representative[0] for k in outcome]), reference)


@pytest.mark.parametrize("mu, w", [(0.5, 2.0), (1.0, 1.0)])
def test_hopf_limit_cycle_period_and_amplitude(mu, w):
    x0 = grid_points(np.linspace(-2.0, 2.0, 5), np.linspace(-2.0, 2.0, 5))[:, [0, 3, 7, 11, 13, 17, 21, 24]]
    res = at.map_points(HOPF, SETTINGS, x0, np.array([mu, w]))
    outcome, table, _ = table_of(HOPF, res)
    assert len(table) == 1 and set(outcome) == {0}
    d = table[0]
    assert d.kind == "periodic"
    assert d.period == pytest.approx(2 * math.pi / w, rel=1e-9)
    assert d.amplitude == pytest.approx(math.sqrt(mu), rel=1e-5)
    np.testing.assert_allclose(d.centroid, [0.0, 0.0], atol=1e-3)


def test_van_der_pol_period():
    """mu = 1: the limit cycle's period is 6.6632868593 (e.g. Strogatz; Grasman) and x oscillates with
    amplitude 2.0086."""
    res = at.map_points(VDP, SETTINGS, np.array([[0.5, -3.0, 3.5], [0.0, 2.0, -1.0]]), np.zeros(0))
    _, table, _ = table_of(VDP, res)
    assert [d.kind for d in table] == ["periodic"]
    assert table[0].period == pytest.approx(6.6632868593, rel=1e-8)
    assert table[0].amplitude == pytest.approx(2.00861986, rel=1e-5)


def test_continuation_matches_the_cycle_across_parameters():
    """The Hopf cycle continued over mu (radius sqrt(mu)): one id throughout; a new id where it is gone."""
    mus = [0.3, 0.5, 0.8, -0.5]
    pars = np.array([[m, 1.5] for m in mus for _ in range(3)]).T
    groups = np.repeat(np.arange(len(mus)), 3)
    x0 = np.array([np.tile([1.5, -1.0, 0.2], len(mus)), np.tile([0.0, 1.0, -0.3], len(mus))])
    res = at.map_points(HOPF, SETTINGS, x0, pars, groups)
    cols = at.chunk_result(HOPF, res, 0)
    outcome, table, first = at.assemble_table(HOPF, cols, groups, threshold=10.0)
    kinds = [table[k].kind for k in outcome]
    assert kinds[:9] == ["periodic"] * 9 and set(outcome[:9]) == {0}
    assert kinds[9:] == ["equilibrium"] * 3 and set(outcome[9:]) == {1} and first == [0, 3]


def test_line_of_equilibria():
    """x' = -x (1 + y^2), y' = 0: every (0, y) is an equilibrium. The cells see one attractor per member
    reached (each run's own y0); a problem that knows the family merges them into one (as the tippedisk
    does with its spin segments)."""
    x0 = grid_points(np.linspace(-2.0, 2.0, 5), np.linspace(-1.0, 1.0, 7))
    res = at.map_points(LINE, SETTINGS, x0, np.zeros(0))
    outcome, table, _ = table_of(LINE, res)
    assert len(table) == 7 and all(d.kind == "equilibrium" for d in table)
    np.testing.assert_allclose([table[k].representative[1] for k in outcome], x0[1], atol=1e-12)
    np.testing.assert_allclose([table[k].representative[0] for k in outcome], 0.0, atol=1e-10)

    class Family(Planar):
        def same_attractor(self, a, b):
            return a.kind == b.kind == "equilibrium"

    family = Family(LINE.rhs)
    outcome, table, _ = table_of(family, at.map_points(family, SETTINGS, x0, np.zeros(0)))
    assert len(table) == 1 and set(outcome) == {0}


def test_labels_left_grid_terminal_and_undecided():
    drift = Planar(lambda x, y: (1.0 + 0.0 * x, 0.0 * y), terminal=lambda x, y: x - 2.0)
    res = at.map_points(drift, at.RecurrenceSettings(dt=0.1, horizon=50.0), np.array([[0.0], [0.0]]), np.zeros(0))
    assert res.labels[0] == drift.labels()["hit"] and res.t_assign[0] == pytest.approx(2.0, abs=1e-12)
    away = Planar(lambda x, y: (1.0 + 0.0 * x, 0.0 * y))
    res = at.map_points(away, at.RecurrenceSettings(dt=0.1, horizon=50.0), np.array([[0.0], [0.0]]), np.zeros(0))
    assert res.labels[0] == at.SPECIAL_LABELS["left_grid"]
    slow = Planar(lambda x, y: (0.01 + 0.0 * x, 0.0 * y), grid=at.Grid(("x", "y"), (-3, -3), (3, 3), (600, 6)))
    res = at.map_points(slow, at.RecurrenceSettings(dt=0.1, horizon=5.0), np.array([[0.0], [0.0]]), np.zeros(0))
    assert res.labels[0] == at.SPECIAL_LABELS["undecided"] and res.t_assign[0] == pytest.approx(5.0)


# ---------------------------------------------------------------------- the tippedisk
def _near_spin(omega, eps, kick=0.02, n=4):
    """Model states near the inverted spin at omega (perturbed beta, gamma rates), parameters at eps."""
    setup = Setup(friction=Friction(eps=eps))
    x = st.stationary_state("inverted", [omega])[:, 0]
    states = []
    for k in range(n):
        y = x.copy()
        y[0] += kick * math.cos(k)
        y[1] += kick * math.sin(k)
        y[5] += 10 * kick * math.sin(2 * k)
        states.append(full_from_reduced(y))
    return np.array(states).T, ode.parameter_vector(setup)


def test_runs_near_a_stable_spin_end_in_the_stationary_solution():
    """eps = 0.25: the inverted spin is stable for 29.2672 < Omega < 33.7924 (docs/stability.md)."""
    x0, pars = _near_spin(31.0, 0.25)
    prob = bs.problem()
    res = at.map_points(prob, bs.recurrence_settings(60.0), x0, pars)
    outcome, table, _ = table_of(prob, res)
    assert len(table) == 1 and set(outcome) == {0}
    d = table[0]
    assert d.kind == "equilibrium" and d.extra["branch"] == 1.0
    assert d.extra["stationary_deviation"] <= 1e-6 and d.extra["max_real_eig"] < 0
    np.testing.assert_allclose(d.representative, st.stationary_state("inverted", [d.extra["omega"]])[:, 0], atol=1e-6)
    assert d.extra["segment_min"] == pytest.approx(29.2672, abs=1e-3)
    assert d.extra["segment_max"] == pytest.approx(33.7924, abs=1e-3)
    # the runs themselves converge to the closed-form spin (reduced state, at their own spin rate)
    ta = copy.copy(prob.integrator(4))
    ta.set_time(np.zeros(4))
    ta.state[:], ta.pars[:] = x0, np.repeat(pars[:, None], 4, axis=1)
    ta.propagate_until(200.0)
    red = bs.reduced_of(np.array(ta.state))
    spin = bs.evaluate_observables(np.array(ta.state), pars)["alpha_dot"]
    red[1] = (red[1] + math.pi) % (2 * math.pi) - math.pi
    # to the batch runs' accuracy: tol 1e-10 relative to |alpha| ~ 6000 rad after 200 s leaves ~1e-6 (the
    # distance stays there from 200 to 300 s, and moves with the start's alpha: the integration's floor)
    np.testing.assert_allclose(red, st.stationary_state("inverted", spin), atol=5e-6)
    assert np.all((spin > d.extra["segment_min"]) & (spin < d.extra["segment_max"]))


def test_no_equilibrium_where_the_spin_is_unstable():
    """eps = 0.1 (the paper's value): both branches are unstable at Omega = 40 rad/s: no equilibrium attractor."""
    x0, pars = _near_spin(40.0, 0.1, n=4)
    prob = bs.problem()
    assert stability.max_real_eig("inverted", 40.0, pars) > 0
    res = at.map_points(prob, bs.recurrence_settings(60.0), x0, pars)
    assert all(res.attractors[k].description.kind != "equilibrium" for k in res.labels if k >= 0)


SMALL = {"omega": (5.0, 80.0, 8), "eps": (0.05, 0.3, 3)}


@pytest.fixture(scope="module")
def attractor_map():
    return om.outcome_map(SMALL, t_end=60.0, classify="attractors", progress=False, chunk_size=16)


def test_outcome_map_on_attractors_schema(attractor_map, tmp_path):
    ds = attractor_map
    assert ds.attrs["kind"] == "outcome_map" and ds.attrs["classify"] == "attractors"
    assert ds["outcome"].dims == ("omega", "eps") and ds["outcome"].dtype == np.int16
    values, meanings = list(ds["outcome"].attrs["flag_values"]), ds["outcome"].attrs["flag_meanings"].split()
    assert set(np.unique(ds["outcome"])) <= set(values) and len(values) == len(meanings)
    n = ds.sizes["attractor"]
    assert values[-n:] == list(range(n))
    for name in ("attractor_kind", "attractor_branch", "attractor_period", "attractor_amplitude", "attractor_state",
                 "assignment_time", "valid", "inversion_time", "fall_time"):
        assert name in ds
    assert ds["attractor_state"].dims == ("attractor", "reduced_state")
    assert int(ds["attractor_n_points"].sum()) == int((ds["outcome"] >= 0).sum())
    for name in ds.data_vars:
        if np.issubdtype(ds[name].dtype, np.floating):
            assert np.all(np.isfinite(ds[name])), name
    path = tmp_path / "m.nc"
    om.outcome_map(SMALL, t_end=60.0, classify="attractors", progress=False, chunk_size=16, output=path)
    xr.testing.assert_identical(load(path), ds)
    assert 0 < float(ds["assignment_time"].max()) <= 60.0 + 1e-9


def test_outcome_map_on_attractors_physics(attractor_map):
    """Slow spins fall; eps = 0.3 with Omega >= 40 ends in the stable inverted spin segment; the final
    state of every equilibrium run lies within the attractor's radius of the spin family."""
    ds = attractor_map
    kinds = ds["attractor_kind"].attrs["flag_meanings"].split()
    names = dict(zip(ds["outcome"].attrs["flag_values"], ds["outcome"].attrs["flag_meanings"].split()))
    assert names[int(ds["outcome"].sel(omega=5.0, eps=0.3))] == "fell"
    fast = ds["outcome"].sel(eps=0.3).where(ds["omega"] >= 40, drop=True).values.astype(int)
    assert all(kinds[int(ds["attractor_kind"][k])] == "equilibrium" for k in fast)
    eq = [k for k in range(ds.sizes["attractor"]) if kinds[int(ds["attractor_kind"][k])] == "equilibrium"]
    for k in eq:
        a = ds.isel(attractor=k)
        assert float(a["attractor_stationary_deviation"]) <= 1e-6 and float(a["attractor_max_real_eig"]) < 0
        sel = ds["outcome"] == k
        assert float(ds["attractor_distance"].where(sel).max()) <= float(a["attractor_radius"])
    undecided = float((ds["outcome"] == bs.labels()["undecided"]).mean())
    assert undecided <= 0.05
    # rolling and wobbling are transients: they lose energy
    for k in range(ds.sizes["attractor"]):
        if kinds[int(ds["attractor_kind"][k])] in ("rolling", "wobbling"):
            assert float(ds["attractor_energy_drift"][k]) < 0


def test_rule_based_maps_are_unchanged_by_default():
    cfg = om.MapConfig(ranges={"omega": (30.0, 40.0, 2), "eps": (0.1, 0.1, 1)}, t_end=0.5)
    assert cfg.classify == "rules" and "classify" not in cfg.to_dict()
    with pytest.raises(ParameterError, match="classify"):
        om.MapConfig(ranges={"omega": (30.0, 40.0, 2), "eps": (0.1, 0.1, 1)}, classify="magic")


def test_interrupted_attractor_map_resumes_identically(tmp_path):
    cfg = om.MapConfig(ranges={"omega": (20.0, 60.0, 4), "eps": (0.1, 0.25, 2)}, t_end=30.0, classify="attractors",
                       chunk_size=3)
    out = tmp_path / "m.nc"

    def stop(i, seen=[]):  # noqa: B006 - deliberate accumulator
        seen.append(i)
        if len(seen) == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweeps.run_sweep(om.sweep(cfg), output=out, threads=1, progress=False, on_chunk=stop)
    resumed = sweeps.run_sweep(om.sweep(cfg), output=out, progress=False)
    xr.testing.assert_identical(resumed, sweeps.run_sweep(om.sweep(cfg), progress=False))


def test_basins_cli_dataset_and_figure(tmp_path):
    out = tmp_path / "b.nc"
    argv = ["basins", "--omega", "40", "--eps", "0.25", "--dgamma0", "-3.1:3.1:5", "--beta0", "1.3:1.8:3",
            "--t-end", "40", "-o", str(out)]
    assert main(argv) == 0
    ds = load(out)
    assert ds.attrs["kind"] == "basins" and ds["outcome"].dims == ("beta0", "dgamma0")  # INITIAL order
    assert float(ds["basin_fraction"].sum() + ds["label_fraction"].sum()) == pytest.approx(1.0)
    assert main(["plot", str(out)]) == 0 and out.with_suffix(".png").stat().st_size > 10_000
    assert main(["basins", "--omega", "40", "-o", str(tmp_path / "x.nc")]) == 2  # no range


def test_basin_fractions_over_eps_match_attractors(tmp_path):
    out = tmp_path / "f.nc"
    assert main(["basin-fractions", "--over", "eps=0.2:0.3:3", "--samples", "6", "--omega", "50",
                 "--dgamma0", "-1:1", "--beta0", "1.45:1.7", "--t-end", "40", "-o", str(out)]) == 0
    ds = load(out)
    assert ds.attrs["kind"] == "basin_fractions" and ds["basin_fraction"].dims == ("eps", "attractor")
    total = ds["basin_fraction"].sum("attractor") + ds["label_fraction"].sum("label")
    np.testing.assert_allclose(total, 1.0)
    # the inverted spin segment at eps = 0.25 and 0.3 is one attractor (matched across eps)
    kinds = ds["attractor_kind"].attrs["flag_meanings"].split()
    eq = [k for k in range(ds.sizes["attractor"]) if kinds[int(ds["attractor_kind"][k])] == "equilibrium"]
    assert len(eq) == 1 and float(ds["inverted_fraction"].sel(eps=0.3)) > 0.5
    assert main(["plot", str(out)]) == 0


def test_fractions_config_refuses_bad_input():
    with pytest.raises(ParameterError, match="cannot continue"):
        bs.FractionsConfig(parameter="zeta", values=[1, 2, 2], ranges={"beta0": [1.2, 1.9]})
    with pytest.raises(ParameterError, match="sampled ranges"):
        bs.FractionsConfig(parameter="omega", values=[10, 80, 3], ranges={"omega": [1, 2]})
    with pytest.raises(ParameterError, match="puts the disk flat"):
        bs.BasinConfig(axes={"beta0": [0.0, 1.0, 3]})


def test_stored_benchmark_map_meets_the_checks_of_issue_13():
    """data/attractors/attractor_map.nc (study attractor_map: the 64 x 64 benchmark map, horizon 60 s)."""
    from pathlib import Path

    ds = load(Path(__file__).resolve().parents[1] / "data" / "attractors" / "attractor_map.nc")
    assert ds.sizes == {**ds.sizes, "omega": 64, "eps": 64} and ds.attrs["classify"] == "attractors"
    assert float((ds["outcome"] == bs.labels()["undecided"]).mean()) <= 0.02
    kinds = ds["attractor_kind"].attrs["flag_meanings"].split()
    for k in range(ds.sizes["attractor"]):
        a = ds.isel(attractor=k)
        kind = kinds[int(a["attractor_kind"])]
        assert kind in ("equilibrium", "rolling", "wobbling")  # no periodic or irregular attractor
        if kind == "equilibrium":
            assert float(a["attractor_stationary_deviation"]) <= 1e-6 and int(a["attractor_branch"]) == 1
            np.testing.assert_allclose(a["attractor_state"], st.stationary_state("inverted", [float(
                a["attractor_omega"])])[:, 0], atol=1e-6)
            assert float(ds["attractor_distance"].where(ds["outcome"] == k).max()) <= float(a["attractor_radius"])
        else:
            assert float(a["attractor_energy_drift"]) < 0  # transients: they dissipate
    assert int((ds["valid"] == 0).sum()) == 0

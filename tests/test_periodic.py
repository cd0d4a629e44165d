"""Periodic orbits (dynamics/ flows, shooting, orbits, orbit_branches; analysis/orbits.py): shooting, Floquet multipliers and branches, proven on textbook
systems with exactly known answers or independent measurements; on the tippedisk, the statuses that say
there is no periodic orbit (docs/periodic_orbits.md)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import quad

import tippedisk_analysis as td
from tippedisk_analysis.dynamics import continuation as co
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import orbits
from tippedisk_analysis.errors import ParameterError

VDP_PERIOD = 6.6632868593231  # mu = 1 (literature value, 14 digits)


@pytest.fixture(scope="module")
def vdp():
    return dy.find_orbit(dy.textbook_system("vanderpol"), [2.0, 0.0], 6.66)


def _crossings(flow, x, pars, t_end, dt=0.01, index=0):
    """Times and states of upward crossings of x[index] = 0 of a simulation (Newton on the crossing time)."""
    times = dt * np.arange(int(t_end / dt) + 1)
    S = flow.trajectory(x, times, pars)
    out = []
    for j in np.flatnonzero((S[:-1, index] < 0) & (S[1:, index] >= 0)):
        s = times[j]
        for _ in range(20):
            z = flow.advance(x, s, pars)
            s -= z[index] / flow.rhs(z, pars)[index]
        out.append((s, flow.advance(x, s, pars)))
    return out


# ----------------------------------------------------------------------------- shooting and multipliers


def test_van_der_pol_period_and_multiplier_against_a_long_simulation(vdp):
    assert vdp.status == "converged" and vdp.residual < 1e-12
    assert vdp.period == pytest.approx(VDP_PERIOD, abs=1e-11)
    system = vdp.system
    flow = dy.Flow(system)
    # the period: return times of a long simulation from far off the orbit, after the transient
    cr = _crossings(flow, np.array([0.1, 0.0]), system.pars, 300.0)
    assert np.diff([t for t, _ in cr[-10:]]) == pytest.approx(vdp.period, abs=1e-9)
    # the nontrivial multiplier: Liouville (a planar flow: exp of the integral of div f over a period) ...
    mu = vdp.multipliers[~vdp.trivial][0].real
    div = 1.0 * (1 - vdp.samples[:, 0] ** 2)
    assert mu == pytest.approx(math.exp(div.mean() * vdp.period), rel=1e-9)
    # ... and the contraction of a perturbation of the section point measured over one return
    x_on = cr[-1][1]
    delta = 1e-4
    t_ret, x_ret = [c for c in _crossings(flow, x_on + [0.0, delta], system.pars, 1.5 * vdp.period)
                    if c[0] > 0.5 * vdp.period][0]
    assert (x_ret[1] - x_on[1]) / delta == pytest.approx(mu, rel=2e-3)


def test_variational_monodromy_matches_finite_differences(vdp):
    for orbit in (vdp, dy.find_orbit(dy.textbook_system("roessler"), [4.58086947, 0.0, 1.52654668], 5.749)):
        M = dy.ShootingProblem(orbit.system).flow.variational(orbit.states[0], orbit.period, orbit.pars)[1]
        fd = dy.monodromy_fd(orbit.system, orbit.states[0], orbit.period, orbit.pars)
        assert np.abs(M - fd).max() < 1e-6 * max(1.0, np.abs(M).max())
        mu_fd = np.sort_complex(np.linalg.eigvals(fd))
        assert np.abs(np.sort_complex(orbit.multipliers) - mu_fd).max() < 1e-6
        assert orbit.trivial.sum() == 1 and abs(orbit.multipliers[orbit.trivial][0] - 1) < 1e-9


def test_stable_orbit_returns_to_itself_after_ten_periods(vdp):
    flow = dy.Flow(vdp.system)
    x = vdp.states[0]
    for _ in range(10):
        y = flow.advance(x, vdp.period, vdp.pars)
        assert np.abs(y - x).max() < 1e-8
        x = y


@pytest.mark.parametrize("segments, phase", [(1, "integral"), (4, "poincare"), (5, "integral")])
def test_multiple_shooting_and_integral_phase_give_the_same_orbit(vdp, segments, phase):
    orbit = dy.find_orbit(vdp.system, [2.0, 0.1], 6.7, segments=segments, phase=phase)
    assert orbit.status == "converged" and len(orbit.states) == segments
    assert orbit.period == pytest.approx(vdp.period, abs=1e-10)
    assert np.abs(orbit.multipliers - vdp.multipliers).max() < 1e-9


def test_unstable_orbit_multiplier_gives_the_growth_rate_of_a_simulation():
    """van der Pol with mu = -1: the time-reversed oscillator, its cycle repels (multiplier ~1163)."""
    system = dy.textbook_system("vanderpol")
    pars = system.with_pars(mu=-1.0)
    orbit = dy.find_orbit(system, [2.0, 0.0], 6.66, pars)
    assert orbit.status == "converged" and orbit.stability == dy.STABILITY["unstable"]
    rate = orbit.exponents[~orbit.trivial].max()
    flow = dy.Flow(system)
    x0 = orbit.states[0]  # on the section x ... the perturbation grows by mu per return
    delta = 1e-10
    vals, vecs = np.linalg.eig(dy.ShootingProblem(system, pars).flow.variational(x0, orbit.period, pars)[1])
    v = vecs[:, np.argmax(np.abs(vals))].real
    n = 3
    y = flow.advance(x0 + delta * v / np.linalg.norm(v), n * orbit.period, pars)
    growth = math.log(np.linalg.norm(y - x0) / delta) / (n * orbit.period)
    assert growth == pytest.approx(rate, rel=0.02)


def test_equilibria_are_never_labelled_as_orbits():
    hopf = dy.textbook_system("hopf")
    stable_focus = hopf.with_pars(beta=-0.05)  # no cycle: every guess collapses onto the equilibrium
    orbit = dy.find_orbit(hopf, [0.05, 0.0, 0.0], 2 * math.pi, stable_focus)
    assert orbit.status in ("equilibrium", "not_converged") and not orbit.converged
    tiny = dy.find_orbit(dy.textbook_system("vanderpol"), [1e-3, 0.0], 6.3, [-1.0])  # stable origin, tiny guess
    assert tiny.status == "equilibrium" and "not a periodic orbit" in tiny.message
    ds = dy.orbits_dataset([tiny], "no_orbit", tiny.message, {})
    assert int(ds.orbit_status[0]) == dy.STATUS["equilibrium"] and ds.attrs["n_orbits"] == 0


def test_a_multiplier_beyond_the_float_range_is_stored_unstable_not_zero():
    orbit = dy.find_orbit(dy.textbook_system("vanderpol"), [2.0, 0.0], 6.66)
    overflowed = dataclasses.replace(orbit, multipliers=np.array([complex(math.inf, math.nan), 1.0 + 0j]),
                                     trivial=np.array([False, True]))
    ds = dy.orbits_dataset([overflowed], "completed", "", {})
    assert float(ds.multiplier_real[0, 0]) == math.inf and float(ds.multiplier_imag[0, 0]) == 0.0


def test_bad_guesses_are_one_line_errors():
    system = dy.textbook_system("vanderpol")
    with pytest.raises(ParameterError, match="period guess"):
        dy.find_orbit(system, [2.0, 0.0], -1.0)
    with pytest.raises(ParameterError, match="2 finite numbers"):
        dy.find_orbit(system, [2.0, 0.0, 1.0], 6.0)
    with pytest.raises(ParameterError, match="no parameter"):
        dy.orbit_problem(dy.find_orbit(system, [2.0, 0.0], 6.66), "nu")
    with pytest.raises(ParameterError, match="unknown system"):
        dy.textbook_system("pendulum")


# ----------------------------------------------------------------------------- from a Hopf point


def test_hopf_normal_form_period_and_amplitude_near_the_hopf_point():
    system = dy.textbook_system("hopf")  # l1 (cartesian) = -1, omega = 1, c = 0.5: r^2 = beta, T = 2 pi/(1 + c r^2)
    ratios = []
    for radius in (0.1, 0.03, 0.01):
        orbit, g = dy.orbit_from_hopf(system, "beta", 0.0, [0.0, 0.0, 0.0], radius=radius)
        assert orbit.status == "converged" and g.a == pytest.approx(1.0) and g.omega == pytest.approx(1.0)
        assert orbit.period == pytest.approx(2 * math.pi / (1 + 0.5 * g.value), rel=1e-11)
        ratios.append(orbit.amplitude / math.sqrt(g.value))
    assert abs(ratios[-1] - 1) < abs(ratios[0] - 1) and ratios[-1] == pytest.approx(1.0, abs=2e-4)
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-1.0, 0.05)}, direction=-1)
    assert br.special_points[-1].kind == "hopf" and abs(br.special_points[-1].u[-1]) < 1e-9
    assert br.special_points[-1].data["frequency"] == pytest.approx(1.0, abs=1e-8)  # period -> 2 pi / omega


def test_bautin_fold_of_cycles_exactly_where_the_normal_form_puts_it():
    """z' = (beta + i) z + z|z|^2 - z|z|^4: fold at beta = -1/4, r^2 = 1/2; nontrivial multiplier
    exp(2 pi 2 r^2 (1 - 2 r^2))."""
    system = dy.textbook_system("bautin")
    orbit, g = dy.orbit_from_hopf(system, "beta", 0.0, [0.0, 0.0], radius=0.2)
    assert g.l1 == pytest.approx(2.0) and orbit.stability == dy.STABILITY["unstable"]  # subcritical
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-0.5, 0.3)}, direction=-1)
    folds = [sp for sp in br.special_points if sp.kind == "fold"]
    assert len(folds) == 1 and folds[0].label == "LP1"
    assert folds[0].u[-1] == pytest.approx(-0.25, abs=1e-9)
    fold_orbit = prob.orbit(folds[0].u)
    assert fold_orbit.amplitude ** 2 == pytest.approx(0.5, abs=1e-8)
    for p in br.points[::4]:
        o = prob.orbit(p.u)
        r2 = o.amplitude ** 2
        assert o.period == pytest.approx(2 * math.pi, abs=1e-10)
        assert o.multipliers[~o.trivial][0].real == pytest.approx(math.exp(4 * math.pi * r2 * (1 - 2 * r2)), rel=1e-7)
    flags = [prob.orbit(p.u).stability for p in (br.points[1], br.points[-1])]
    assert flags == [dy.STABILITY["unstable"], dy.STABILITY["stable"]]  # the fold joins the two cycles


# ----------------------------------------------------------------------------- period doubling, NS, homoclinic


@pytest.fixture(scope="module")
def roessler():
    system = dy.textbook_system("roessler")
    x0, T0 = dy.simulation_guess(system, [1.0, 1.0, 0.0], index=1, level=0.0, transient=200.0)
    orbit = dy.find_orbit(system, x0, T0)
    br, prob = dy.continue_orbits(orbit, "c", bounds={"c": (2.5, 3.2)})
    return br, prob


def _return_map(flow, pars, x, T):
    """Next crossing of y = 0 (upward) from x on it, near time T."""
    t = T
    for _ in range(30):
        z = flow.advance(x, t, pars)
        dt = -z[1] / flow.rhs(z, pars)[1]
        t += dt
        if abs(dt) < 1e-14:
            break
    return flow.advance(x, t, pars)


def test_roessler_period_doubling_cross_checked_by_a_finite_difference_return_map(roessler):
    br, prob = roessler
    pd = [sp for sp in br.special_points if sp.kind == "period_doubling"]
    assert [sp.label for sp in pd] == ["PD1"]
    c_pd = pd[0].u[-1]
    assert c_pd == pytest.approx(2.8324, abs=1e-3)  # the known first doubling of a = b = 0.2
    assert pd[0].data["multiplier_real"] == pytest.approx(-1.0, abs=1e-9)
    # independent: the return map to y = 0 (x, z on the section), central differences, no variational equations
    X, T, _c = prob.split(pd[0].u)
    pars = prob.runtime(pd[0].u)
    flow = dy.Flow(prob.system)
    x0 = _return_map(flow, pars, X[0], T)  # a point of the orbit on the section
    h, D = 1e-5, np.empty((2, 2))
    for j, k in enumerate((0, 2)):
        e = np.zeros(3)
        e[k] = h
        D[:, j] = (_return_map(flow, pars, x0 + e, T) - _return_map(flow, pars, x0 - e, T))[[0, 2]] / (2 * h)
    assert np.min(np.abs(np.linalg.eigvals(D) + 1.0)) < 1e-6


def test_switching_at_the_period_doubling_gives_the_doubled_orbit_seen_in_simulation(roessler):
    br, prob = roessler
    options = co.Options(ds=0.02, ds_max=0.2, max_points=25)
    doubled, dprob = dy.switch_period_doubling(prob, br, "PD1", options=options)
    c_pd = [sp.u[-1] for sp in br.special_points if sp.kind == "period_doubling"][0]
    point = next(p for p in doubled.points if p.u[-1] > c_pd + 0.02)
    X, T2, c = dprob.split(point.u)
    T1 = br.points[np.argmin([abs(p.u[-1] - c) for p in br.points])].u[-2]
    assert T2 == pytest.approx(2 * T1, rel=0.01)
    assert np.linalg.norm(X[0] - X[len(X) // 2]) > 1e-2  # the two halves differ: not the old orbit twice
    assert dprob.orbit(point.u).stability == dy.STABILITY["stable"]
    # simulation at that c: the section points alternate between two values, those of the doubled orbit
    system = prob.system
    pars = system.with_pars(c=c)
    flow = dy.Flow(system)
    x = flow.advance(np.array([1.0, 1.0, 0.0]), 1500.0, pars)
    cr = _crossings(flow, x, pars, 60.0, index=1)
    sim = sorted(s[0] for _t, s in cr[-2:])
    on_section = _crossings(flow, X[0], pars, T2, index=1)
    assert len(on_section) == 2
    assert sorted(s[0] for _t, s in on_section) == pytest.approx(sim, abs=1e-4)  # the run converges slowly


def test_neimark_sacker_point_of_a_cycle_times_a_hopf_normal_form():
    system = dy.textbook_system("torus")
    orbit = dy.find_orbit(system, [1.0, 0.0, 0.0, 0.0], 2 * math.pi)
    mu = np.sort_complex(orbit.multipliers[~orbit.trivial])
    pair = np.exp(2 * math.pi * (-0.1 + np.array([1j, -1j]) * math.sqrt(2)))
    exact = np.sort_complex([math.exp(-4 * math.pi), *pair])
    assert np.abs(mu - exact).max() < 1e-9
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-0.1, 0.1)})
    ns = [sp for sp in br.special_points if sp.kind == "neimark_sacker"]
    assert [sp.label for sp in ns] == ["NS1"]
    assert abs(ns[0].u[-1]) < 1e-9
    assert ns[0].data["angle"] == pytest.approx((2 * math.pi * math.sqrt(2)) % (2 * math.pi), abs=1e-8)
    assert not [sp for sp in br.special_points if sp.kind in ("period_doubling", "fold", "branch_point")]


def test_period_grows_without_bound_at_a_homoclinic_orbit():
    """Level sets H = c of a Hamiltonian loop: Hopf at c = -1/6, homoclinic at c = 0, saddle eigenvalue 1."""
    system = dy.textbook_system("homoclinic")
    orbit, g = dy.orbit_from_hopf(system, "c", -1.0 / 6.0, [1.0, 0.0], radius=0.05)
    assert orbit.status == "converged"
    # the period equals the Hamiltonian one at H = c: T = 2 int dx / sqrt(2 (c + x^2/2 - x^3/3))
    c = g.value
    roots = np.sort(np.roots([-1 / 3, 1 / 2, 0.0, c]).real)
    a, b, e = roots[1], roots[2], roots[0]
    period = 2 * quad(lambda x: 1 / math.sqrt(2 / 3 * (x - e)), a, b, weight="alg", wvar=(-0.5, -0.5))[0]
    assert orbit.period == pytest.approx(period, rel=1e-9)
    br, prob = dy.continue_orbits(orbit, "c", bounds={"c": (-0.2, 0.1)}, period_max=30.0, segments=4,
                                  options=co.Options(ds=0.02, ds_max=0.2, max_points=200))
    hc = br.special_points[-1]
    assert hc.kind == "homoclinic" and hc.label == "HC1" and hc.data["period"] == pytest.approx(30.0)
    assert abs(hc.data["limit"]) < 1e-8 and hc.data["rate"] == pytest.approx(1.0, rel=0.02)
    ds = dy.branch_dataset(prob, br, {"source": "hopf"})
    assert ds.attrs["labels"] == "HC1" and "homoclinic" in ds.attrs["message"]


def test_branch_dataset_round_trip(tmp_path):
    system = dy.textbook_system("bautin")
    orbit, _g = dy.orbit_from_hopf(system, "beta", 0.0, [0.0, 0.0], radius=0.3)
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-0.3, 0.0)}, direction=-1,
                                  options=co.Options(ds=0.05, ds_max=0.1, max_points=12))
    ds = dy.branch_dataset(prob, br, {"source": "test"})
    assert ds.attrs["kind"] == "periodic_orbits" and set(ds.dims) >= {"point", "floquet", "sample", "state"}
    path = td.save(ds, tmp_path / "po.nc")
    back = td.load(path)
    import xarray as xr

    xr.testing.assert_identical(back, ds)
    assert (back.multiplier_trivial.sum("floquet") == 1).all()


# ----------------------------------------------------------------------------- the tippedisk


@pytest.fixture(scope="module")
def inverted_branch():
    return td.load(td.__file__.rsplit("src", 1)[0] + "data/continuation/continuation_inverted.nc")


def test_tippedisk_newton_from_the_hopf_point_finds_no_orbit(inverted_branch):
    ds = orbits.tippedisk_orbits_from_hopf(inverted_branch, "HOPF1", amplitudes=(1e-3, 1e-2), max_iter=6)
    assert ds.attrs["status"] == "no_orbit" and ds.attrs["n_orbits"] == 0
    assert not (ds.orbit_status == dy.STATUS["converged"]).any()
    assert (ds.energy_change < 0).all()  # every trial period loses energy
    res = ds.residual.values  # the mismatch after one trial period shrinks like r^2 (r' = k r^2): no orbit at any r
    assert res[1] / res[0] == pytest.approx(100, rel=0.5)
    with pytest.raises(ParameterError, match="Hopf point"):
        orbits.tippedisk_orbits_from_hopf(inverted_branch, "BP1")


def test_tippedisk_equilibrium_is_reported_as_such():
    from tippedisk_analysis.analysis import stationary

    setup = td.Setup(friction=td.Friction(eps=0.25))
    system = orbits.tippedisk_system(setup)
    x = stationary.stationary_state("inverted", [31.63])[:, 0]
    orbit = dy.find_orbit(system, x + 1e-9 * np.array([1, 1, 0, 0, 0, 1, 1]), 0.2288, max_iter=8)
    assert orbit.status == "equilibrium" and not orbit.converged
    assert orbit.trivial.sum() == 2  # the flow direction and the spin family


def test_tippedisk_runs_lose_energy_at_every_return():
    run = td.simulate("ode-euler", 6.0, setup=td.Setup(friction=td.Friction(eps=0.25)), dt_output=0.01)
    ds = orbits.tippedisk_orbits_from_run(run, max_iter=6)
    assert ds.attrs["status"] == "no_orbit" and int(ds.orbit_status[0]) != dy.STATUS["converged"]
    dE = ds.return_energy_change.values[:-1]
    assert (dE < 0).all()
    np.testing.assert_allclose(dE, ds.return_friction_work.values[:-1], rtol=1e-6, atol=1e-12)  # energy balance
    with pytest.raises(ParameterError, match="kind"):
        orbits.tippedisk_orbits_from_run(inverted_branch_like())


def inverted_branch_like():
    import xarray as xr

    return xr.Dataset(attrs={"kind": "continuation", "config": "{}"})


# ----------------------------------------------------------------------------- CLI and figures


def test_cli_textbook_branch_and_tippedisk_no_orbit(tmp_path, capsys, inverted_branch):
    from tippedisk_analysis.cli import main

    out = tmp_path / "bautin.nc"
    assert main(["periodic-orbits", "--system", "bautin", "--to", "-0.3", "-o", str(out)]) == 0
    ds = td.load(out)
    assert ds.attrs["labels"] == "LP1" and "LP1 at beta = -0.25" in capsys.readouterr().out
    assert main(["plot", str(out)]) == 0 and out.with_suffix(".png").stat().st_size > 10_000
    source = tmp_path / "c.nc"
    td.save(inverted_branch, source)
    out = tmp_path / "hopf.nc"
    code = main(["periodic-orbits", "--from-hopf", f"{source}:HOPF1", "--amplitudes", "0.001", "--max-iter", "3",
                 "-o", str(out)])
    assert code == 3 and td.load(out).attrs["status"] == "no_orbit"  # documented: no periodic orbit, dataset written
    assert "no periodic orbit" in capsys.readouterr().out
    assert main(["plot", str(out)]) == 0


def test_cli_textbook_hopf_branch_starts_along_the_hopf_tangent_as_auto07p(tmp_path, capsys):
    """'ab' from its Hopf point (D = 0.13090004) to the homoclinic limit AUTO-07p finds, D = 0.10550707."""
    from tippedisk_analysis.cli import main

    out = tmp_path / "ab.nc"
    assert main(["periodic-orbits", "--system", "ab", "--to", "0.1", "--period-max", "50", "--max-points", "400",
                 "-o", str(out)]) == 0
    ds = td.load(out)
    assert ds.attrs["labels"] == "HC1" and "homoclinic orbit at D ~ 0.10550707" in capsys.readouterr().out
    assert float(ds.D[0]) == pytest.approx(0.13090004482, abs=1e-4) and float(ds.period[0]) == pytest.approx(
        1.5677491465, rel=1e-3)  # the first orbit is next to the Hopf point, with its period 2 pi / omega
    assert np.all(ds.stability.values == 0)


@pytest.mark.parametrize("args, fragment", [
    ([], "exactly one of"),
    (["--system", "bautin", "--from-run", "x.nc"], "exactly one of"),
    (["--from-hopf", "nolabel"], "FILE:LABEL"),
    (["--from-hopf", "missing.nc:HOPF1"], "does not exist"),
    (["--system", "lorenz"], "unknown system"),
    (["--system", "bautin", "--hopf-radius", "-1"], "--hopf-radius -1 must be positive"),
    (["--system", "bautin", "--radius", "0.05"], "the orbit radius of a Hopf start is --hopf-radius"),
    (["--from-hopf", "c.nc:HOPF1", "--mass", "0.5"], "the disk options belong to --frictionless"),
])
def test_cli_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, args, fragment):
    from tippedisk_analysis.cli import main

    out = tmp_path / "po.nc"
    assert main(["periodic-orbits", *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1 and not out.exists()


def test_branch_continues_from_a_stored_orbit(tmp_path, capsys):
    from tippedisk_analysis.cli import main

    first = tmp_path / "b.nc"
    assert main(["periodic-orbits", "--system", "bautin", "--to", "-0.3", "--segments", "2", "-o", str(first)]) == 0
    ds = td.load(first)
    orbit = orbits.orbit_from_dataset(ds, 3)
    assert orbit.converged and len(orbit.states) == 2 and orbit.parameter == "beta"
    assert orbit.period == pytest.approx(float(ds.period[3]), abs=1e-12)
    out = tmp_path / "more.nc"  # from the small (unstable) cycle towards beta > 0: it shrinks into the Hopf point
    assert main(["periodic-orbits", "--from-orbit", f"{first}:3", "--to", "0.1", "-o", str(out)]) == 0
    assert td.load(out).attrs["labels"] == "HOPF1"
    last = ds.sizes["point"] - 1  # from the large (stable) cycle: on to beta = 0.1
    assert main(["periodic-orbits", "--from-orbit", f"{first}:{last}", "--to", "0.1", "-o", str(out)]) == 2
    assert "exists; give --overwrite" in capsys.readouterr().err  # like every command that writes a file
    assert main(["periodic-orbits", "--from-orbit", f"{first}:{last}", "--to", "0.1", "-o", str(out),
                 "--overwrite"]) == 0
    more = td.load(out)
    assert float(more.beta[-1]) == pytest.approx(0.1) and (more.stability == 0).all()
    capsys.readouterr()
    assert main(["periodic-orbits", "--from-orbit", f"{first}:99", "-o", str(tmp_path / "x.nc")]) == 2
    assert "does not exist" in capsys.readouterr().err


# ----------------------------------------------------------------------------- conservative systems


def test_conservative_family_in_the_energy_level_matches_quadrature():
    """Duffing x'' + x + x^3 = 0: orbits come in a family (two trivial multipliers); pinning the energy makes
    the shooting system consistent and overdetermined; the period along the family equals the quadrature."""
    system = dy.textbook_system("duffing")
    orbit = dy.find_orbit(system, [1.0, 0.0], 5.0)
    assert orbit.converged and orbit.trivial.sum() == 2 and orbit.stability == dy.STABILITY["marginal"]

    def period(E):
        a2 = -1 + math.sqrt(1 + 4 * E)
        return 4 * quad(lambda x: 1 / math.sqrt(2 * (math.sqrt(a2) + x) * (0.5 + (a2 + x * x) / 4)), 0,
                        math.sqrt(a2), weight="alg", wvar=(0, -0.5))[0]

    br, prob = dy.continue_orbits(orbit, "E", bounds={"E": (0.1, 3.0)}, both_ways=True,
                                  options=co.Options(ds=0.05, ds_max=0.2, max_points=30))
    assert br.status == "completed" and not br.special_points
    for p in br.points[::3]:
        assert p.u[-2] == pytest.approx(period(p.u[-1]), rel=1e-12)


def test_frictionless_tippedisk_orbit_checked_with_ode_model_1():
    """mu = 0: the only periodic orbits of the tippedisk (Lyapunov centre family at a saddle-centre spin)."""
    setup = td.Setup(friction=td.Friction(mu=0.0))
    orbit = orbits.tippedisk_lyapunov_orbit(setup, "inverted", 40.0, radius=1e-3)
    assert orbit.converged and orbit.trivial.sum() == 3  # flow, energy, vertical angular momentum
    mu = orbit.multipliers[~orbit.trivial]
    saddle = np.sort(np.abs(mu[np.abs(mu.imag) < 1e-9]))
    assert saddle[0] * saddle[1] == pytest.approx(1.0, rel=1e-8)  # a reciprocal pair: conservative
    pair = mu[np.abs(mu.imag) > 1e-9]
    assert np.abs(np.abs(pair) - 1).max() < 1e-8  # S's horizontal velocity turning: on the unit circle
    check = orbits.tippedisk_full_model_check(orbit, setup)
    assert check["return_error"] < 1e-8  # ODE Model 1 (13 states) closes the orbit
    assert check["section_period"] == pytest.approx(orbit.period, abs=1e-9)  # Poincare return time (events)
    br, prob = orbits.tippedisk_lyapunov_family(setup, "inverted", 40.0, energy_max=0.41,
                                                options=co.Options(ds=0.05, ds_max=0.2, max_points=8))
    levels = [dy.integral_levels(prob.system, prob.split(p.u)[0][0]) for p in br.points]
    assert np.ptp([lv["L_z"] for lv in levels]) < 1e-12 and np.all(np.diff([lv["E_tot"] for lv in levels]) > 0)
    with pytest.raises(ParameterError, match="without friction"):
        orbits.tippedisk_lyapunov_orbit(td.Setup(), "inverted", 40.0)

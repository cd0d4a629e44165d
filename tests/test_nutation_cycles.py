"""The held model's nutation cycles (analysis/nutation_cycles.py): the family of the rolling held model checked
against its own flow and the rolling frequencies (C2), the Melnikov drift against the closed form (C3), and the
unstable cycle it predicts against the held model's periodic orbit (shooting at eps > 0) and against runs."""

from __future__ import annotations

import copy
import math
from types import SimpleNamespace

import numpy as np
import pytest

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import nutation_cycles as nc
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.parameters import Disk, Setup


@pytest.fixture(scope="module")
def family_31():
    return nc.family(31.0, max_amplitude=2.6)


@pytest.fixture(scope="module")
def drift_30_5():
    return nc.drift(30.5, max_amplitude=2.6)


@pytest.mark.parametrize("flip", [(-1.0, 1.0, 1.0, -1.0), (1.0, -1.0, -1.0, 1.0)])
def test_the_rolling_held_model_is_reversible_and_friction_breaks_it(flip):
    """f(Rx) = -R f(x) for R: (beta, gamma, rates) -> (pi - beta, gamma, beta_dot, -gamma_dot) and
    (beta, pi - gamma, -beta_dot, gamma_dot): what makes the shot orbits periodic."""
    R = np.diag(flip)
    shift = np.array([math.pi if flip[0] < 0 else 0.0, math.pi if flip[1] < 0 else 0.0, 0.0, 0.0])
    rng = np.random.default_rng(7)
    states = np.column_stack([0.5 * math.pi + 0.4 * rng.standard_normal(50), rng.uniform(-3, 3, 50),
                              3 * rng.standard_normal(50), 5 * rng.standard_normal(50)])
    for system, eps, holds in ((held_spin.rolling_system(), 0.0, True), (held_spin.system(), 0.01, False)):
        pars = nc._pars(30.5, None, eps)
        error = max(np.abs(system.f(shift + R @ x, pars) + R @ system.f(x, pars)).max()
                    / max(1.0, np.abs(system.f(x, pars)).max()) for x in states)
        assert (error < 1e-12) == holds


def test_every_member_closes_under_the_rolling_flow_and_the_smallest_has_the_rolling_frequency(family_31):
    rolling = held_spin.rolling_system()
    pars = nc._pars(31.0, None)
    picks = np.linspace(0, family_31.sizes["orbit"] - 1, 6).astype(int)
    for k in picks:
        ta = copy.deepcopy(rolling.taylor(1e-13))
        ta.time, ta.state[:], ta.pars[:] = 0.0, family_31.start.values[k], pars[: len(ta.pars)]
        ta.propagate_until(float(family_31.period.values[k]))
        assert np.abs(ta.state - family_31.start.values[k]).max() < 1e-8
    nu = cs.rates(31.0)["nu_nutation"]
    assert family_31.period.values[0] == pytest.approx(2 * math.pi / nu, rel=1e-3)
    assert family_31.attrs["status"] == "completed"
    amplitude = nc.amplitude_of(family_31)
    folds = amplitude[family_31.fold.values == 1]
    assert folds.size == 1 and 2.3 < folds[0] < 2.5  # the family's largest amplitude, located by the core


@pytest.mark.parametrize("spin", [29.5, 31.0, 33.0])
def test_small_nutations_drift_at_the_closed_form_rate(spin):
    """-d a / d(eps t) / a -> Re lambda / eps of the nutation (C3) as a -> 0 (a cubic in a fitted: the friction
    law holds |lambda_T|, which grows like |a|, so the drift is not odd in a)."""
    ds = nc.drift(spin, max_amplitude=0.6, max_points=30)
    a, rate = nc.amplitude_of(ds), ds.amplitude_rate.values
    use = ds.drift_valid.values.astype(bool) & (a < 0.5)
    intercept = np.polyfit(a[use], rate[use] / a[use], 3)[-1]
    assert intercept == pytest.approx(cs.rates(spin)["rate_nutation"], rel=2e-3)


@pytest.mark.slow
def test_the_hopf_point_is_supercritical_and_a_fold_of_cycles_follows_it_closely():
    """Below omega_c the nutation grows at every amplitude (30.0 rad/s) until, 0.004 rad/s below omega_c, an
    attracting and a repelling cycle appear together; the attracting one shrinks into the spin at omega_c, the
    repelling one goes on above it. Both are the held model's own periodic orbits (eps = 1e-3 m/s): the
    multiplier along the family is below 1 on the first and above 1 on the second. Just below omega_c the
    attracting cycle lies below the family's first member, and the spin's own eigenvalues find it."""
    assert nc.cycles(nc.drift(30.0, max_amplitude=1.0, max_points=40))["status"] == "none_decays"
    fold = nc.fold_of_cycles()
    omega_c = cs.omega_critical().omega_critical
    assert fold["status"] == "completed" and omega_c - 0.01 < fold["spin"] < omega_c
    spin = 30.229
    ds = nc.drift(spin, max_amplitude=0.6, max_points=40)
    found = nc.cycles(ds)["cycles"]
    assert [c["kind"] for c in found] == ["attracting", "repelling"]
    a = nc.amplitude_of(ds)
    for cycle, side in zip(found, (-1.0, 1.0)):
        k = int(np.argmin(np.abs(a - cycle["amplitude"])))
        orbit = dy.find_orbit(held_spin.system(), ds.start.values[k], float(ds.period.values[k]),
                              nc._pars(spin, None, 1e-3))
        assert orbit.converged, orbit.message
        assert nc.orbit_amplitude(orbit.samples) == pytest.approx(cycle["amplitude"], abs=3e-3)
        real = orbit.multipliers[np.abs(orbit.multipliers.imag) < 1e-9].real
        family = real[np.argsort(np.abs(real - 1))[1]]  # the nontrivial real multiplier next to the flow's 1
        assert np.sign(family - 1.0) == side
    above = nc.cycles(nc.drift(30.5, max_amplitude=2.6))["cycles"]
    assert [c["kind"] for c in above] == ["repelling"]
    short = nc.cycles(nc.drift(30.5, max_amplitude=1.6, max_points=20))  # ends at a = 1.1 rad, below the cycle
    assert short["status"] == "incomplete" and "max_points" in short["message"]
    tiny = nc.cycles(nc.drift(30.232, max_amplitude=0.6, max_points=40))["cycles"]
    assert [c["kind"] for c in tiny] == ["attracting", "repelling"] and tiny[0]["amplitude"] < 0.02


def test_the_repelling_cycle_is_the_held_models_own_periodic_orbit(drift_30_5):
    """Shooting at eps > 0 finds a periodic orbit at a* + O(eps), whose multiplier along the family is
    exp(eps T d(rate)/da) > 1: the cycle repels in the amplitude."""
    star = nc.repelling_cycle(drift_30_5)
    a, rate = nc.amplitude_of(drift_30_5), drift_30_5.amplitude_rate.values
    k = int(np.argmin(np.abs(a - star["amplitude"])))
    slope = (rate[k + 1] - rate[k - 1]) / (a[k + 1] - a[k - 1])
    errors = []
    for eps in (0.005, 0.0025):
        orbit = dy.find_orbit(held_spin.system(), drift_30_5.start.values[k], float(drift_30_5.period.values[k]),
                              nc._pars(30.5, None, eps))
        assert orbit.converged, orbit.message
        assert orbit.period == pytest.approx(star["period"], rel=1e-3)
        errors.append(abs(nc.orbit_amplitude(orbit.samples) - star["amplitude"]))
        real = orbit.multipliers[np.abs(orbit.multipliers.imag) < 1e-9].real
        family = real[np.argsort(np.abs(real - 1))[1]]
        assert math.log(family) / (eps * orbit.period) == pytest.approx(slope, rel=0.05)
    assert errors[1] < 2e-3 and errors[1] < errors[0]


def test_the_fold_of_the_drift_checks_itself_and_refuses_a_jump(monkeypatch):
    """repelling_cycle_end roots the drift's peak between two cycles. A peak that falls through zero smoothly is
    a fold; one that jumps (another member of the family takes over, as next to members whose drift fails its
    checks) has a sign change and no fold, and must not be reported as completed."""
    monkeypatch.setattr(nc, "drift", lambda spin, setup, max_amplitude: spin)
    monkeypatch.setattr(nc, "_peak_rate", lambda spin: (-6.0 * (spin - 30.95), 2.3 + 0.1 * (spin - 30.95), True))
    smooth = nc.repelling_cycle_end(bracket=(30.9, 31.0))
    assert smooth["status"] == "completed" and smooth["spin"] == pytest.approx(30.95, abs=1e-5)
    monkeypatch.setattr(nc, "_peak_rate", lambda spin: (5.4, 2.33, True) if spin < 30.95 else (-0.35, 1.99, False))
    jump = nc.repelling_cycle_end(bracket=(30.9, 31.0))
    assert jump["status"] == "not_verified" and math.isnan(jump["spin"]) and "jump" in jump["message"]


def test_the_held_fold_refuses_an_orbit_shooting_found_off_the_cycle(drift_30_5, monkeypatch):
    """If shooting from the family member next to a* converges to another orbit, the branch continued from it is
    not the repelling cycle's: status off_cycle, no fold reported."""
    star = nc.repelling_cycle(drift_30_5)["amplitude"]
    monkeypatch.setattr(nc, "drift", lambda spin, setup, max_amplitude: drift_30_5)
    off = np.tile([0.5 * math.pi, 0.5 * math.pi - star - 0.1, 0.0, 0.0], (10, 1))
    monkeypatch.setattr(nc, "find_orbit", lambda *args: SimpleNamespace(converged=True, samples=off))
    found = nc.held_fold_of_cycles(30.5, 0.005)
    assert found["status"] == "off_cycle" and math.isnan(found["spin"])
    assert found["start_amplitude"] == pytest.approx(star + 0.1)


@pytest.mark.slow
def test_the_repelling_cycle_ends_in_a_fold_of_cycles_the_held_model_reaches_at_order_eps_squared():
    """Above omega_c an attracting cycle comes in near the family's fold (2.39 rad) and meets the repelling one:
    both vanish at one held spin (the drift's peak between them falls through zero). The held model's own
    periodic orbit, continued in the held spin by shooting, turns at a fold of cycles there, closer by about 4
    per halving of eps: two independent computations, the Melnikov drift (eps -> 0) and shooting at eps > 0."""
    end = nc.repelling_cycle_end()
    assert end["status"] == "completed" and 30.95 < end["spin"] < 30.96
    below = nc.cycles(nc.drift(30.94, max_amplitude=3.1))
    assert [c["kind"] for c in below["cycles"]] == ["repelling", "attracting"]
    assert below["cycles"][0]["amplitude"] < end["amplitude"] < below["cycles"][1]["amplitude"] < 2.39
    assert nc.cycles(nc.drift(30.96, max_amplitude=3.1))["status"] == "all_decay"
    distances = []
    for eps in (0.01, 0.005, 0.0025):
        held = nc.held_fold_of_cycles(30.9, eps)
        assert held["status"] == "completed", held["message"]
        assert held["amplitude"] == pytest.approx(end["amplitude"], abs=0.02)
        distances.append(held["spin"] - end["spin"])
    assert distances[0] > 3 * distances[1] > 9 * distances[2] > 0 and distances[2] < 1e-4
    assert nc.held_fold_of_cycles(30.0, 0.005)["status"] == "no_cycle"  # every nutation grows at 30 rad/s
    assert nc.repelling_cycle_end(bracket=(31.0, 31.5))["status"] == "no_fold"
    for call in (lambda: nc.held_fold_of_cycles(30.9, 0.0), lambda: nc.repelling_cycle_end(bracket=(31.0,)),
                 lambda: nc.repelling_cycle_end(xtol=1.0)):
        with pytest.raises(ParameterError):
            call()


@pytest.mark.slow
def test_the_averaged_drift_follows_the_held_model(drift_30_5):
    """Runs of the held model (eps 0.01 m/s, 20 s) inside and outside the repelling cycle: the nutation decays and grows
    as d a / d(eps t) = drift(a) says, turning point by turning point."""
    ds = drift_30_5
    a = nc.amplitude_of(ds)
    star = nc.repelling_cycle(ds)["amplitude"]
    eps = 0.01
    for offset, sign in ((-0.3, -1.0), (0.3, 1.0)):
        k = int(np.argmin(np.abs(a - (star + offset))))
        ta = copy.deepcopy(held_spin.system().taylor(1e-12))
        ta.time, ta.state[:] = 0.0, ds.start.values[k]
        ta.pars[:] = nc._pars(30.5, None, eps)[: len(ta.pars)]
        times = np.linspace(0.0, 20.0, 20001)
        states = ta.propagate_grid(times)[-1]
        turns = np.flatnonzero((states[:-1, 3] < 0) & (states[1:, 3] >= 0))
        measured = 0.5 * math.pi - states[turns, 1]
        expected = nc.averaged_amplitude(ds, a[k], eps * times[turns])
        assert np.sign(measured[-1] - measured[0]) == sign
        assert np.abs(measured - expected).max() < 0.01


@pytest.mark.slow
def test_a_disk_it_was_not_built_on_has_a_repelling_cycle_above_its_own_omega_c():
    """The drilled disk with e = 3.5 mm: no cycle 0.2 rad/s below its own omega_c, one 0.3 rad/s above it, and
    that one is the held model's periodic orbit at eps = 0.005 m/s."""
    disk = Disk.from_geometry().with_eccentricity(3.5e-3)
    setup = Setup(disk=disk)
    omega_c = cs.omega_critical(disk).omega_critical
    assert nc.cycles(nc.drift(omega_c - 0.2, setup, max_amplitude=1.5, max_points=40))["status"] == "none_decays"
    ds = nc.drift(omega_c + 0.3, setup, max_amplitude=2.0, max_points=60)
    star = nc.repelling_cycle(ds)
    assert star["kind"] == "repelling"
    k = int(np.argmin(np.abs(nc.amplitude_of(ds) - star["amplitude"])))
    orbit = dy.find_orbit(held_spin.system(), ds.start.values[k], float(ds.period.values[k]),
                          nc._pars(omega_c + 0.3, setup, 0.005))
    assert orbit.converged, orbit.message
    assert nc.orbit_amplitude(orbit.samples) == pytest.approx(star["amplitude"], abs=3e-3)
    assert orbit.period == pytest.approx(star["period"], rel=1e-3)


def test_the_lower_spins_homoclinic_orbit_returns_to_it():
    """The unstable manifold of the lower spin reaches the reversor's plane at one held spin and so comes back:
    checked by running it on, and independent of how far from the spin the manifold is started."""
    found = nc.homoclinic_spin()
    assert found["status"] == "completed" and found["return_distance"] < nc.RETURN_TOL
    other = nc._top_of_unstable_manifold(found["spin"], None, offset=1e-9)[0]
    assert abs(other[2]) < 1e-6  # beta_dot at the top: the same orbit from a start ten times closer
    assert nc.homoclinic_spin(bracket=(30.0, 31.0))["status"] == "no_crossing"


def test_the_generic_homoclinic_method_finds_the_reversors_orbit_at_eps_0():
    """dy.homoclinic_point (the unstable manifold's return to the lower spin, gamma once round) and the reversor
    condition (beta_dot = 0 at the top) are two different conditions; at eps = 0 both give the same spin. The
    lower spin is a saddle-centre there, so the generic method says not_hyperbolic."""
    found = dy.homoclinic_point(held_spin.rolling_system(), held_spin.spin_state("lower"), "spin", (33.4, 33.5),
                                nc._pars(33.4, None), branch="+gamma", shift=(0.0, 2.0 * math.pi, 0.0, 0.0))
    assert found["status"] == "not_hyperbolic"
    assert found["value"] == pytest.approx(nc.homoclinic_spin()["spin"], abs=1e-8)


def test_with_friction_the_lower_spin_has_one_homoclinic_orbit():
    """eps = 0.005 m/s: the lower spin's stable manifold is one-dimensional (its precession grows), and followed
    backwards it comes back to the lower spin at one held spin only, a checked homoclinic orbit."""
    w = np.linalg.eigvals(held_spin.system().jacobian(held_spin.spin_state("lower"), nc._pars(30.8, None, 0.005)))
    assert np.sum(w.real < 0) == 1 and np.sum((w.real > 0) & (np.abs(w.imag) > 1)) == 2
    scan = nc.lower_spin_scan(0.005, spins=(30.5, 30.75, 31.0, 32.0, 34.0))
    assert list(scan.side.values) == [-1, -1, 1, 1, 1]
    assert list(scan.crossing_status.values) == ["completed"] and scan.attrs["homoclinic_orbits"] == 1
    assert scan.crossing_value.values[0] == pytest.approx(30.81545, abs=1e-4)
    with pytest.raises(ParameterError, match="homoclinic_spin"):
        nc.lower_spin_scan(0.0)


def test_on_the_r60_disk_the_hopf_point_is_subcritical():
    """The drilled disk with r = 60 mm has no cycle just below its omega_c, and its repelling cycle grows out of the
    spin above it like the square root of the distance to omega_c (a subcritical Hopf point)."""
    disk = Disk.from_geometry(r=0.06)
    setup = Setup(disk=disk)
    omega_c = cs.omega_critical(disk).omega_critical
    assert nc.cycles(nc.drift(omega_c - 0.002, setup, max_amplitude=0.5, max_points=40))["status"] == "none_decays"
    sizes = []
    for d in (0.0005, 0.002):
        found = nc.cycles(nc.drift(omega_c + d, setup, max_amplitude=0.5, max_points=40))["cycles"]
        assert [c["kind"] for c in found] == ["repelling"]
        sizes.append(found[0]["amplitude"] / math.sqrt(d))
    assert sizes[1] == pytest.approx(sizes[0], rel=0.1)  # a* ~ sqrt(Omega - omega_c)


def test_bad_spins_are_refused_in_one_line():
    with pytest.raises(ParameterError, match="held spin"):
        nc.family(-3.0)
    with pytest.raises(ParameterError, match="no centre of two pairs"):
        nc.family(10.0)
    with pytest.raises(ParameterError, match="max_amplitude"):
        nc.family(31.0, max_amplitude=4.0)
    with pytest.raises(ParameterError, match="nutation_cycles.drift"):
        nc.cycles(nc.family(31.0, max_amplitude=0.5, max_points=10))  # a family without its drift
    assert nc.family(np.float32(31.0), max_amplitude=0.3, max_points=5).sizes["orbit"] > 1
    for call in (lambda: nc.family(30.5, "disk"), lambda: nc.family(30.5, max_amplitude="1"),
                 lambda: nc.homoclinic_spin(bracket=(30,)), lambda: nc.homoclinic_spin(bracket=("30", "36")),
                 lambda: nc.fold_of_cycles(bracket=(30.2, 30.25), xtol=0.0),
                 lambda: nc.fold_of_cycles(bracket=(30.2, 30.25), xtol=math.nan)):
        with pytest.raises(ParameterError):
            call()

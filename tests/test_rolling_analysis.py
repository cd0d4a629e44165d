"""The rolling tippedisk as a dynamical system (analysis/rolling.py): pinned orbit families on a textbook
centre, the stationary spins against the smooth model's eps -> 0 limit and against the growth of a
perturbation, the post-inversion torus and its central orbit (rotation numbers of small tori against the
Floquet angle), the family's end at a spin, sections of the hybrid model, and the CLI."""

from __future__ import annotations

import math
from pathlib import Path

import heyoka as hy
import numpy as np
import pytest

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import rolling as ar
from tippedisk_analysis.analysis import stability
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis.models import ode
from tippedisk_analysis.parameters import Friction, Setup

# a point near the centre of the post-inversion torus of the Table 3 run (a Newton guess, not a result)
CENTRE_GUESS = np.array([1.9457, 0.5 * math.pi, 38.297, 0.0, -1.1612])


def centre_system() -> dy.System:
    """x'' = -w^2 x without a declared integral: a family of orbits of one period 2 pi / w in the amplitude."""
    x, v = hy.make_vars("x", "v")
    return dy.System("centre", (x, v), (v, -hy.par[0] ** 2 * x), {"w": 2.0})


def test_a_pin_picks_one_orbit_of_a_family_and_continues_in_it():
    system = centre_system()
    orbit = dy.find_orbit(system, (0.7, 0.05), 3.0, pinned=("x",))
    assert orbit.converged
    assert orbit.period == pytest.approx(math.pi, rel=1e-10)
    assert orbit.states[0][0] == pytest.approx(0.7, abs=1e-12)
    assert orbit.amplitude > 0
    br, _prob = dy.continue_orbits(orbit, "x", bounds={"x": (0.5, 1.5)}, pinned=("x",),
                                   options=dy.Options(ds=0.05, ds_max=0.2, max_points=30))
    x0 = np.array([p.u[-1] for p in br.points])
    periods = np.array([p.u[-2] for p in br.points])
    assert x0.max() > 1.4
    np.testing.assert_allclose(periods, math.pi, rtol=1e-9)


def test_the_rolling_spin_is_the_smooth_spin_as_eps_goes_to_zero():
    """The slow eigenvalues of the smooth model's spin tend to the rolling spin's as eps -> 0; their real
    parts vanish like eps (friction damps one mode and feeds the other), the fast ones go like -1/eps."""
    omega = 40.0
    rolling_ev = ar.spin_eigenvalues("inverted", omega)[0]
    freqs = np.sort(np.abs(rolling_ev.imag))[::2][1:]  # the two pairs +-i w1, +-i w2 (and the zero)
    assert np.max(np.abs(rolling_ev.real)) < 1e-9
    damping = []
    for eps in (1e-3, 1e-4):
        pars = ode.parameter_vector(Setup(friction=Friction(eps=eps)))
        ev = stability.spectrum("inverted", omega, pars).eigenvalues[0]
        slow = ev[np.abs(ev) < 100]
        slow_freqs = np.sort(np.abs(slow.imag[slow.imag > 0]))
        np.testing.assert_allclose(slow_freqs, freqs, rtol=20 * eps**2)  # O(eps^2): 1.56e-5, 1.56e-7 measured
        damping.append(np.max(np.abs(slow.real)) / eps)
        fast = ev[np.abs(ev) >= 100]
        assert len(fast) == 2 and np.all(fast.real < -5.0 / eps)
    assert damping[0] == pytest.approx(damping[1], rel=1e-4)  # real parts exactly O(eps): 18.097 eps


def test_the_growth_of_a_perturbation_of_an_unstable_spin_is_its_eigenvalue():
    """At Omega = 10 rad/s the inverted rolling spin has a complex quartet: a perturbation's coordinate on the
    unstable mode a + i b (eigenbasis of the Jacobian) grows like exp(a t) in the nonlinear simulation."""
    system = ar.reduced_system()
    x_star = ar.spin_state("inverted", 10.0)
    ev, V = np.linalg.eig(system.jacobian(x_star))
    k = int(np.argmax(ev.real))
    assert ev[k].real > 1.0 and abs(ev[k].imag) > 1.0
    x0 = x_star + 1e-10 * np.array([1.0, 0.3, 0.0, 0.2, 0.1])
    times = np.array([0.0, 0.5, 1.5])
    X = dy.Flow(system).trajectory(x0, times, system.pars)
    c = np.abs(np.linalg.solve(V, (X - x_star).T)[k])
    measured = math.log(c[2] / c[1]) / (times[2] - times[1])
    assert measured == pytest.approx(ev[k].real, rel=1e-4)


@pytest.fixture(scope="module")
def central():
    orbit = dy.find_orbit(ar.reduced_system(), CENTRE_GUESS, 0.888, pinned=("omega_x",))
    assert orbit.converged
    return orbit


def test_the_central_orbit_is_elliptic_with_a_family_multiplier(central):
    mu = central.multipliers
    assert np.sum(np.abs(mu - 1.0) < 1e-5) == 3  # the flow, the energy and the family at one energy
    theta = ar.floquet_angle(central)
    assert 0.4 < theta < 0.45
    assert central.period == pytest.approx(0.888, abs=2e-3)
    c = ar.consistency(central)
    assert c["min_cone_margin"] > 0.2 and c["min_lambda_N"] > 4.0


def test_small_tori_turn_at_the_floquet_angle(central):
    """Returns from the central orbit displaced by a along the real part of its elliptic monodromy eigenvector
    (finite differences of the flow): closed curves whose rotation number tends to the Floquet angle as a^2
    (the twist of the tori)."""
    from tippedisk_analysis.dynamics.orbits import monodromy_fd

    system = ar.reduced_system()
    theta = ar.floquet_angle(central)
    x0 = central.states[0]
    ev, V = np.linalg.eig(monodromy_fd(system, x0, central.period, central.pars))
    k = int(np.argmax(ev.imag))
    assert abs(np.angle(ev[k])) / (2 * math.pi) == pytest.approx(theta, abs=1e-7)
    v = V[:, k].real / np.linalg.norm(V[:, k].real / system.state_scale)
    gaps = []
    for a in (3e-3, 1e-3):
        motion = ar.identify(ar.section(x0 + a * v, t_end=300.0))
        assert motion.kind == "torus", motion.message
        gaps.append(abs(motion.rotation_number - theta))
    assert gaps[1] < 1e-6
    assert gaps[1] < 0.2 * gaps[0]


def test_an_orbit_is_told_from_a_torus(central):
    motion = ar.identify(ar.section(central.states[0], t_end=40.0))
    assert motion.kind == "periodic orbit", motion.message
    assert motion.mean_return == pytest.approx(central.period, rel=1e-9)
    few = ar.identify(ar.section(central.states[0], t_end=5.0))
    assert few.kind == "unresolved"
    with pytest.raises(ParameterError, match="longer run"):
        ar.central_orbit(ar.section(central.states[0], t_end=5.0))


@pytest.mark.slow
def test_the_family_over_the_energy_ends_at_the_spin(central):
    """Upwards in the energy at fixed omega_x the orbits shrink onto the inverted spin at that rate: the
    last period is 2 pi over the spin's slow frequency."""
    top = ar.reduced_system().observe(ar.spin_state("inverted", central.states[0][2])[:, None])["E_tot"][0]
    br, _prob = dy.continue_orbits(central, "E_tot", bounds={"E_tot": (0.3, 0.5)}, pinned=("omega_x",),
                                   options=dy.Options(ds=0.02, ds_max=0.2, max_points=40))
    assert br.status == "completed"
    e_end, t_end = br.points[-1].u[-1], br.points[-1].u[-2]
    assert e_end == pytest.approx(top, abs=1e-3), e_end - top
    ev = ar.spin_eigenvalues("inverted", central.states[0][2])[0]
    slow = np.min(np.abs(ev.imag[ev.imag > 1e-6]))
    assert t_end == pytest.approx(2 * math.pi / slow, rel=1e-2)


def test_hybrid_sections_are_located_in_either_mode():
    """gamma = 0 upwards is crossed while the disk slides (0.29 .. 0.43 s of the Table 3 run): the crossing is
    in the sliding mode and lies where a fine output grid of the run changes sign."""
    import tippedisk_analysis as td
    from tippedisk_analysis.analysis.poincare import poincare_section

    sec = poincare_section("gamma=0", model="h1", t_end=0.5)
    run = td.simulate(model="h1", t_end=0.5, dt_output=1e-5)
    g, t = run["gamma"].values, run["time"].values
    k = np.where((g[:-1] < 0) & (g[1:] >= 0))[0]
    np.testing.assert_allclose(sec["time"].values, t[k], atol=1e-5)
    assert sec["mode"].values.tolist() == run["mode"].values[k].tolist()
    assert 1 in sec["mode"].values
    np.testing.assert_allclose(sec["gamma"].values, 0.0, atol=1e-12)


def test_cli_rolling_orbit_from_a_hybrid_run(tmp_path):
    from tippedisk_analysis import results
    from tippedisk_analysis.cli import main

    run = tmp_path / "h1.nc"
    assert main(["simulate", "--model", "h1", "--t-end", "3", "-o", str(run)]) == 0
    out = tmp_path / "po.nc"
    assert main(["periodic-orbits", "--from-run", str(run), "--returns-time", "100", "-o", str(out)]) == 0
    ds = results.load(out)
    assert ds.attrs["status"] == "completed"
    assert "torus" in ds.attrs["message"]
    assert 0.4 < float(ds["rotation_number"]) < 0.45
    assert float(ds["orbit_min_cone_margin"][0]) > 0.2
    assert main(["periodic-orbits", "--from-run", str(run), "--section", "gamma=0", "-o",
                 str(tmp_path / "x.nc")]) == 2


def test_cli_a_rolling_analysis_of_a_smooth_run_is_refused(tmp_path, capsys):
    from tippedisk_analysis.cli import main

    run = tmp_path / "ode.nc"
    assert main(["simulate", "--model", "ode1", "--t-end", "0.1", "-o", str(run)]) == 0
    out = tmp_path / "po.nc"
    assert main(["periodic-orbits", "--from-run", str(run), "--returns-time", "50", "-o", str(out)]) == 2
    assert "does not roll" in capsys.readouterr().err
    assert not out.exists()
    with pytest.raises(ParameterError, match="does not roll without slip"):
        ar.rolling_start(__import__("tippedisk_analysis").results.load(run))


CROSSINGS_ENERGY = (0.3582974020, 0.3602209415, 0.3668421464)  # J: docs/rolling.md
CROSSING_SPIN = 38.74328985  # rad/s


def test_every_zero_crossing_of_the_cone_margin_is_a_boundary():
    """Along the energy family rolling is inconsistent below 0.36684 J but consistent again on [0.3583,
    0.3602] J: all three crossings are reported, not only the first on each side."""
    data = Path(__file__).resolve().parents[1] / "data" / "rolling"
    energy = td.load(data / "rolling_family_energy.nc")
    np.testing.assert_allclose(ar.consistency_boundary(energy), CROSSINGS_ENERGY, atol=1e-9)
    margin = energy.min_cone_margin.values
    between = (energy.E_tot.values > CROSSINGS_ENERGY[0]) & (energy.E_tot.values < CROSSINGS_ENERGY[1])
    assert between.any() and np.all(margin[between] > 0)
    np.testing.assert_allclose(ar.consistency_boundary(td.load(data / "rolling_family_spin.nc")), [CROSSING_SPIN],
                               atol=1e-7)


@pytest.mark.slow
def test_the_family_and_its_boundaries_from_a_fresh_continuation(central):
    """rolling.family recomputed now: the energy family's crossings of the cone margin equal the documented
    ones, and every orbit's Floquet angle is an angle in (0, 1/2] or the flag of an orbit off the circle."""
    ds = ar.family(central, "E_tot", (0.30, 0.50), max_points=40)  # the study's budget: it ends max_points
    assert ds.attrs["status"] in ("completed", "max_points")
    # the fixture's central orbit comes from a shorter section than the study's: 2.3e-6 J apart at the lowest
    np.testing.assert_allclose(ar.consistency_boundary(ds), CROSSINGS_ENERGY, atol=5e-6)
    angle = ds.floquet_angle.values
    assert np.all(((angle > 0) & (angle <= 0.5)) | (angle == ar.NO_ANGLE))


@pytest.mark.slow
@pytest.mark.parametrize("dt, rotation", [(1e-4, 0.3819650088), (1e-5, 0.4156252833)])
def test_the_moreau_torus_moves_with_the_time_step(dt, rotation):
    """docs/rolling.md: Model 1 over 8 s at dt = 1e-4 s and 1e-5 s ends on different neighbouring tori (the h1
    torus: 0.4196767125); the rotation numbers of their returns, to 1e-9."""
    ds = ar.orbits_from_run(td.simulate("m1", 8.0, dt=dt))
    assert float(ds.rotation_number) == pytest.approx(rotation, abs=1e-9)

"""The critical spin in closed form (analysis/critical_spin.py, docs/inversion.md): the algebra on textbook
cases, the closed form against the package's slow flow (sympy and heyoka), omega_c against the full smooth
model's eigenvalues, the predicted initial spin against the full model's threshold, the command."""

from __future__ import annotations

import copy
import dataclasses
import json
import math

import numpy as np
import pytest

from tippedisk_analysis import errors as td_errors
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.analysis.rolling import spin_eigenvalues, spin_state
from tippedisk_analysis.cli import main
from tippedisk_analysis.models import reduced, slow_flow
from tippedisk_analysis.parameters import Disk, Friction, InitialState, Setup

OTHER_DISKS = {"table 2": Disk(), "drilled, e 1.5 mm": Disk.from_geometry().with_eccentricity(1.5e-3),
               "drilled, r 40 mm": Disk.from_geometry(r=0.040), "table 2, e 10 mm": Disk().with_eccentricity(0.01)}


def disk_args(disk: Disk, Omega, mu=0.3, g=9.81):
    return dict(Omega=Omega, m=disk.m, e=disk.e, r=disk.r, A=disk.A, B=disk.B, C=disk.C, g=g, mu=mu)


def test_characteristic_is_numpys_polynomial_to_first_order():
    rng = np.random.default_rng(7)
    eps = 1e-7
    for _ in range(5):
        K0, K1 = np.zeros((4, 4)), np.zeros((4, 4))
        for i, j in ((0, 1), (0, 2), (1, 0), (1, 3), (2, 0), (2, 3), (3, 1), (3, 2)):
            K0[i, j] = rng.normal()
        for i, j in ((2, 1), (2, 2), (3, 0), (3, 3)):
            K1[i, j] = rng.normal()
        c2, c0, a3, a1 = cs.characteristic(K0.tolist(), K1.tolist())
        np.testing.assert_allclose(np.poly(K0 + eps * K1), [1, eps * a3, c2, eps * a1, c0], atol=1e-12)


def test_first_order_pairs_on_two_weakly_damped_oscillators():
    """(lambda^2 + eps d1 lambda + w1^2)(lambda^2 + eps d2 lambda + w2^2): Re lambda = -eps d_k / 2 exactly."""
    w1, w2, d1, d2 = 1.3, 4.1, 0.7, -2.5
    c2, c0, a3, a1 = w1**2 + w2**2, w1**2 * w2**2, d1 + d2, d1 * w2**2 + d2 * w1**2
    (nu1, r1), (nu2, r2) = cs.first_order_pairs(c2, c0, a3, a1)
    assert (nu1, nu2) == pytest.approx((w1, w2), rel=1e-14)
    assert (r1, r2) == pytest.approx((-d1 / 2, -d2 / 2), rel=1e-13)


@pytest.mark.parametrize("name", list(OTHER_DISKS))
def test_closed_form_is_heyokas_jacobian_of_the_slow_flow(name):
    """K0 + eps K1 written out equals the slow flow's Jacobian (heyoka's derivatives) at the inverted spin."""
    disk, system = OTHER_DISKS[name], slow_flow.system()
    for Omega in (15.0, 33.0, 70.0):
        for eps in (1e-3, 0.05):
            pars = inversion.parameters("slow", inversion.with_eps(Setup(disk=disk), eps))
            J = system.jacobian(spin_state("inverted", Omega), pars)[np.ix_((0, 1, 3, 4), (0, 1, 3, 4))]
            K0, K1 = cs.spin_matrices(**disk_args(disk, Omega))
            K = np.array(K0, dtype=float) + eps * np.array(K1, dtype=float)
            np.testing.assert_allclose(J, K, rtol=1e-9, atol=1e-9 * np.abs(J).max())


@pytest.mark.slow
def test_closed_form_is_sympys_derivation_from_the_slow_flow():
    import sympy as sp

    S, K0, K1, K2 = cs.derive()
    M0, M1 = cs.spin_matrices(S["Omega"], S["m"], S["e"], S["r"], S["A"], S["B"], S["C"], S["gravity"], S["mu"])
    assert K2 == sp.zeros(4, 4)  # the Jacobian is linear in eps
    for i in range(4):
        for j in range(4):
            assert sp.simplify(K0[i, j] - M0[i][j]) == 0, (i, j)
            assert sp.simplify(K1[i, j] - M1[i][j]) == 0, (i, j)


def test_rolling_frequencies_are_the_rolling_models():
    for Omega in (20.0, 40.0):
        c2, c0, a3, a1 = cs.coefficients(**disk_args(Disk(), Omega))
        (nu1, _), (nu2, _) = cs.first_order_pairs(c2, c0, a3, a1)
        ev = spin_eigenvalues("inverted", [Omega])[0]
        assert sorted(np.abs(ev.imag[ev.imag > 1e-9])) == pytest.approx([nu1, nu2], rel=1e-10)


def full_model_nutation_rate(Omega, eps, disk):
    """Re lambda / eps of the nutation pair of ODE Model 1 (reduced, with the slip as states) at the spin."""
    setup = inversion.with_eps(Setup(disk=disk), eps)
    x = slow_flow.smooth_state(spin_state("inverted", Omega), inversion.parameters("slow", setup))
    ev = np.linalg.eigvals(reduced.system().jacobian(x, inversion.parameters("smooth", setup)))
    oscillating = ev[np.abs(ev.imag) > 1e-6]
    return oscillating[np.argmin(np.abs(oscillating.imag))].real / eps


@pytest.mark.parametrize("name", list(OTHER_DISKS))
def test_critical_spin_is_where_the_full_models_nutation_turns(name):
    """omega_c from (C4) is where the nutation of ODE Model 1's inverted spin turns, to O(eps^2)."""
    from scipy.optimize import brentq

    disk = OTHER_DISKS[name]
    found = cs.omega_critical(disk)
    assert found.status == "completed"
    w = found.omega_critical
    assert full_model_nutation_rate(w - 0.5, 1e-3, disk) > 0 > full_model_nutation_rate(w + 0.5, 1e-3, disk)
    error = [abs(brentq(lambda x: full_model_nutation_rate(x, eps, disk), w - 1, w + 1, xtol=1e-12) - w)
             for eps in (1e-2, 1e-3)]
    assert error[1] < 1e-3
    assert 50 < error[0] / error[1] < 200  # O(eps^2): eps / 10 -> error / 100
    assert abs(cs.check_against_jacobian(w, Setup(disk=disk))) < 1e-6  # of the real part 1 rad/s higher


def test_critical_spin_does_not_depend_on_mu():
    assert cs.omega_critical(mu=0.1).omega_critical == pytest.approx(cs.omega_critical(mu=0.6).omega_critical,
                                                                     rel=1e-12)
    # ... while the rates scale with 1/mu
    assert cs.rates(35.0, mu=0.1)["rate_nutation"] == pytest.approx(6 * cs.rates(35.0, mu=0.6)["rate_nutation"])


def test_a_nearly_symmetric_disk_has_no_critical_spin_and_says_why():
    found = cs.omega_critical(Disk().with_eccentricity(1e-4))
    assert found.status == "not_elliptic" and math.isnan(found.omega_critical)
    assert "real eigenvalues" in found.message


def test_c0_is_the_quadratic_in_omega_squared_of_c6():
    """(C6) written out against the product of the matrices' entries (characteristic), in sympy."""
    import sympy as sp

    m, e, r, A, B, C, g, mu, W = sp.symbols("m e r A B C g mu Omega", positive=True)
    c0 = cs.coefficients(W, m, e, r, A, B, C, g, mu)[1]
    P, Q, R = cs.stiffness_coefficients(m, e, r, A, B, C, g)
    assert sp.expand(sp.together(c0 - (P * W**4 + Q * W**2 + R))) == 0


@pytest.mark.parametrize("e", [0.85e-3, 0.9e-3, 1.0e-3])
def test_below_the_balance_eccentricity_the_damped_window_ends_where_the_nutation_stops(e):
    """With e < (A - B) / (m r) (1.124 mm for Table 2's A, B) c0 turns negative at one spin: there the nutation
    frequency (C2) falls to zero, and above it the rolling inverted spin is a saddle (a real pair in numpy's
    eigenvalues of K0)."""
    disk = Disk(e=e)
    (w_s,) = cs.saddle_spins(disk)
    nu = [cs.rates(w_s - dw, disk)["nu_nutation"] for dw in (1e-2, 1e-4)]
    assert nu[1] / nu[0] == pytest.approx(0.1, rel=1e-2) and nu[0] < 0.1  # nu_1 ~ sqrt(w_s - Omega) -> 0
    K0, _ = cs.spin_matrices(**disk_args(disk, w_s + 0.1))
    ev = np.linalg.eigvals(np.array(K0, dtype=float))
    assert (np.abs(ev.imag) < 1e-9).sum() == 2 and ev.real.max() > 0
    found = cs.omega_critical(disk)
    if found.status == "completed":  # above the Bogdanov-Takens point (e = 0.8905 mm): a window
        assert found.omega_critical < w_s and f"up to {w_s:.4f} rad/s" in found.message
    else:
        assert f"saddle above {w_s:.4f} rad/s" in found.message


def test_a_balanced_disk_is_refused_with_one_line(capsys):
    assert main(["critical-spin", "--e", "0"]) == 2
    assert "a balanced disk (S at G) has no inversion to predict" in capsys.readouterr().err


def test_a_window_narrower_than_the_scan_is_found():
    """Just above the Bogdanov-Takens point the damped window is 0.04 rad/s wide, below the scan's 0.5 rad/s step:
    the nutation rate (C3) is positive just below omega_c and negative inside the window."""
    disk = Disk(e=0.891e-3)
    found = cs.omega_critical(disk)
    (w_s,) = found.saddle_spins
    assert found.status == "completed" and 0.0 < w_s - found.omega_critical < 0.05
    assert cs.rates(found.omega_critical - 1e-3, disk)["rate_nutation"] > 0
    assert cs.rates(0.5 * (found.omega_critical + w_s), disk)["rate_nutation"] < 0


def test_the_command_names_the_window_and_the_start_spin_at_its_top(capsys):
    assert main(["critical-spin", "--json", "--e", "0.0009"]) == 0
    out = json.loads(capsys.readouterr().out)
    (w_s,) = out["saddle_spins"]
    assert out["omega_critical"] < out["check_spin"] < w_s  # the check measures inside the window
    assert out["initial_spin_at_window_top"] > out["initial_spin_threshold"]
    assert abs(out["check_relative_nutation_rate"]) < 1e-6


def test_ode_model_1s_branch_point_of_a_nearly_balanced_disk_tends_to_the_saddle_spin_as_eps_squared():
    """The full model (slip as states), another formulation than (C6): its zero eigenvalue on the inverted spin's
    family at e = 0.9 mm (measured 29.4077 and 29.5536 rad/s at eps 0.01, 0.005 against 29.6033)."""
    from tippedisk_analysis.analysis import spin_continuation as sc

    disk = Disk(e=0.9e-3)
    (w_s,) = cs.saddle_spins(disk)
    errors = []
    for eps in (0.01, 0.005):
        setup = Setup(disk=disk, friction=dataclasses.replace(Friction(), eps=eps))
        ds = sc.continue_branch("inverted", "omega", 20.0, 40.0, setup=setup)
        labels = [str(label) for label in ds.special_label.values]
        errors.append(float(ds.omega.values[ds.special_index.values[labels.index("BP1")]]) - w_s)
    assert 3.5 < errors[0] / errors[1] < 4.5 and abs(errors[1]) < 0.06


def test_above_the_balance_eccentricity_the_rolling_inverted_spin_never_turns_into_a_saddle():
    disk = Disk()
    balance = (disk.A - disk.B) / (disk.m * disk.r)
    assert cs.saddle_spins(Disk(e=0.99 * balance)) and not cs.saddle_spins(Disk(e=1.01 * balance))
    assert cs.saddle_spins(disk) == () and cs.omega_critical(disk).message.endswith("damped above 30.2325 rad/s")


def test_threshold_is_the_energy_of_the_inverted_spin():
    """(C5): at the predicted initial spin the start's rolling energy equals the inverted spin's at omega_c,
    E = A omega_c^2 / 2 + m g (r + e) (written out here, not from the code)."""
    disk, g = Disk(), 9.81
    w_c = cs.omega_critical(disk).omega_critical
    w_0 = cs.initial_spin_threshold(w_c)
    d0 = InitialState().gamma + 0.5 * math.pi  # S is d0 off straight below G; the spin axis is in the disk plane
    start = 0.5 * (disk.A * math.cos(d0) ** 2 + disk.B * math.sin(d0) ** 2) * w_0**2 + disk.m * g * (
        disk.r - disk.e * math.cos(d0))
    assert start == pytest.approx(0.5 * disk.A * w_c**2 + disk.m * g * (disk.r + disk.e), rel=1e-12)


@pytest.mark.slow
def test_prediction_bounds_the_full_models_threshold_at_two_mu():
    """ODE Model 1 from Table 3 at eps 0.1: the threshold lies above the prediction (friction dissipates on the
    way up) by less than 3 %, whatever mu (omega_c does not depend on it); and the spin with which the disk
    passes the criterion is omega_c within 3 % (the mechanism: it arrives where the nutation is damped)."""
    predicted = cs.initial_spin_threshold(cs.omega_critical().omega_critical)
    found, setups = [], []
    for mu in (0.15, 0.5):
        setup = dataclasses.replace(Setup(), friction=dataclasses.replace(Setup().friction, mu=mu))
        th = inversion.spin_threshold(setup=setup, bracket=(32.0, 36.0), scan=5, xtol=0.01)
        assert th.status == "completed"
        assert predicted < th.spin < 1.03 * predicted
        found.append(th.spin)
        setups.append(setup)
    assert abs(found[0] - found[1]) < 0.1
    system = inversion.system("smooth")
    ta = copy.deepcopy(system.taylor(inversion.TOL, events=True))
    ta.time = 0.0
    ta.state[:] = inversion.start_state("smooth", found[1] + 0.02, setups[1], InitialState().gamma)
    pars = inversion.parameters("smooth", setups[1])
    ta.pars[:] = pars[: len(ta.pars)]
    ta.propagate_until(inversion.horizon(0.1))
    assert system.observe(ta.state.copy(), pars)["z_S"] == pytest.approx(Disk().r + 0.8 * Disk().e, rel=1e-9)
    spin = float(system.observe(ta.state.copy(), pars)["alpha_dot"])
    assert spin == pytest.approx(cs.omega_critical().omega_critical, rel=0.03)


def test_command_prints_both_and_json(capsys):
    assert main(["critical-spin", "--json", "--e", "0.0035"]) == 0
    out = json.loads(capsys.readouterr().out)
    disk = Disk().with_eccentricity(0.0035)
    w_c = cs.omega_critical(disk).omega_critical
    assert out["omega_critical"] == pytest.approx(w_c, rel=1e-12)
    assert out["initial_spin_threshold"] == pytest.approx(cs.initial_spin_threshold(w_c, Setup(disk=disk)), rel=1e-12)
    assert main(["critical-spin"]) == 0
    text = capsys.readouterr().out
    assert "omega_c = 30.23" in text and "initial spin threshold (C5) = 32.95" in text


def test_simulate_says_how_high_the_prediction_gets_and_whether_the_start_slides(capsys):
    """--simulate: the full model's threshold, S's highest point at (C5) (below the criterion), and the slow flow
    against ODE Model 1 at the threshold: it holds for Tables 1-2; Table 2's disk with e = 3.5 mm slides in its
    first swing (the slow flow ends at the friction cone within a second)."""
    assert main(["critical-spin", "--simulate", "--json", "--e", "0.0035"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["full_model_threshold"] > out["initial_spin_threshold"] and out["height_at_prediction"] < 0.8
    check = out["reduction_check"]
    assert out["reduction_holds"] is False and check["spin"] >= out["full_model_threshold"]
    assert check["slow_flow_ending"] in ("cone", "lift_off") and check["slow_flow_end_time"] < 1.0
    assert check["full_model_height"] > 0.5 > check["slow_flow_height"]  # the full model slides and still rises
    assert main(["critical-spin", "--simulate"]) == 0
    text = capsys.readouterr().out
    assert "at the predicted spin S gets to r + 0.6" in text and "the reduction holds" in text


@pytest.mark.parametrize("argv, status, words", [
    (["--e", "0.05"], 2, "not smaller than the radius"),
    (["--eps", "0"], 2, "eps > 0"),
    (["--radius", "-0.01"], 2, "radius"),
    (["--e", "1e-4"], 1, "real eigenvalues"),
])
def test_command_bad_input_and_no_answer(capsys, argv, status, words):
    assert main(["critical-spin", *argv]) == status
    captured = capsys.readouterr()
    assert words in captured.err + captured.out
    assert len((captured.err + captured.out).strip().splitlines()) == 1


@pytest.mark.slow
def test_the_full_models_hopf_curves_end_at_the_closed_form():
    """The dynamics layer continues ODE Model 1's Hopf points of the inverted spin from eps = 0.25 m/s down to
    eps = 0.005 m/s: HOPF1 (the nutation) tends to omega_c and HOPF2 (the precession) to the spin where (C3)
    turns the precession growing, both with a distance proportional to eps^2."""
    import tippedisk_analysis as td
    from tippedisk_analysis.analysis import spin_continuation as sc

    found = cs.omega_critical()
    branch = sc.continue_branch("inverted", "omega", 0.0, 100.0, setup=td.Setup(friction=td.Friction(eps=0.25)))
    for label, limit in (("HOPF1", found.omega_critical), ("HOPF2", found.omega_precession)):
        curve = sc.continue_curve(branch, label, ("omega", "eps"), bounds={"eps": (0.005, 0.4)})
        assert curve.attrs["status"] == "completed"
        eps, omega = curve.eps.values, curve.omega.values
        small = eps < 0.03
        assert small.sum() >= 3 and eps.min() == pytest.approx(0.005)
        coefficient = (omega[small] - limit) / eps[small] ** 2
        assert np.ptp(coefficient) < 0.15 * np.abs(coefficient).mean(), coefficient  # O(eps^2), one coefficient
        assert abs(omega[np.argmin(eps)] - limit) < 2e-4 * limit


def test_radius_and_eccentricity_options_are_checked_together(capsys):
    """--radius is not checked against the default e before --e applies (e = 1 mm on a 2 mm disk is a disk)."""
    status = main(["critical-spin", "--e", "0.001", "--radius", "0.002"])
    assert "0.0025" not in capsys.readouterr().err and status in (0, 1)


@pytest.mark.parametrize("argv, words", [
    (["--mu", "0"], "needs mu > 0"),
    (["--gamma0", "1.4"], "already above the criterion"),
    (["--gamma0", "4"], "in [-pi, pi]"),
])
def test_command_refuses_what_has_no_critical_spin_question(capsys, argv, words):
    assert main(["critical-spin", *argv]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1


def test_the_full_models_threshold_is_printed_even_without_omega_c():
    from tippedisk_analysis.cli.critical_spin import _text

    out = {"omega_critical": None, "initial_spin_threshold": None, "message": "no nutation to damp", "mu": 0.3,
           "eps": 0.1, "full_model_status": "completed", "full_model_threshold": 29.55, "full_model_message": ""}
    assert "inverts above 29.5500 rad/s" in _text(out)


def test_prediction_map_builds_small_drilled_disks_and_refuses_bad_grids():
    ds = cs.prediction_map([1.5e-3], [0.03, 0.045])  # r = 30 mm: the hole moved to b = 4.5 mm
    assert list(ds.status.values[0]) == [cs.MAP_FLAGS["completed"]] * 2
    drilled = Disk.from_geometry(r=0.03, b=1.5e-3 * (0.03**2 - 0.015**2) / 0.015**2)
    assert ds.omega_critical.values[0, 0] == pytest.approx(cs.omega_critical(drilled).omega_critical, rel=1e-12)
    for e, r in (([np.nan], [0.04]), ([], [0.04]), ([1e-3], [-0.04])):
        with pytest.raises(td_errors.ParameterError):
            cs.prediction_map(e, r)


def test_spin_threshold_refuses_a_fractional_scan():
    with pytest.raises(td_errors.ParameterError, match="integer scan"):
        inversion.spin_threshold(scan=2.7)


def test_critical_spin_needs_friction_and_gravity():
    for bad in ({"mu": 0.0}, {"mu": -1.0}, {"gravity": 0.0}, {"mu": math.nan}):
        with pytest.raises(td_errors.ParameterError, match="needs"):
            cs.omega_critical(**bad)


@pytest.mark.slow
def test_the_energy_bound_holds_for_starts_with_S_below_G_only():
    """(C5) bounds ODE Model 1's threshold from below while S starts below G (delta_0 = 1.0 rad: +5 %); a start
    with S above G (delta_0 = 2.2 rad) passes the criterion in one swing, below the prediction (-3.4 %)."""
    w_c = cs.omega_critical().omega_critical
    for delta, above in ((1.0, True), (2.2, False)):
        gamma0 = -0.5 * math.pi + delta
        predicted = cs.initial_spin_threshold(w_c, gamma0=gamma0)
        th = inversion.spin_threshold(gamma0=gamma0, bracket=(0.9 * predicted, 1.1 * predicted), scan=5, xtol=0.01)
        assert th.status == "completed"
        assert (th.spin > predicted) == above and abs(th.spin / predicted - 1) > 0.02, (delta, th.spin, predicted)

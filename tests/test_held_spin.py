"""The held-spin model (models/held_spin.py): the slow flow with the spin about the vertical held by a torque.
Checked by its power balance (exact at eps = 0, second order in eps as the slow flow's), by its linearisation
against the closed form of analysis/critical_spin.py (another formulation: the slow flow in body rates), by
its Hopf points against omega_c and the precession onset, and by what it does from Table 3's start."""

import copy
import dataclasses
import math

import heyoka as hy
import numpy as np
import pytest
from scipy.optimize import fsolve

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin, inversion
from tippedisk_analysis.dynamics.continuation import Options, continue_branch
from tippedisk_analysis.dynamics.equilibria import EquilibriumProblem, Parameter
from tippedisk_analysis.dynamics.switching import switch_branch
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.parameters import Disk

START = np.array([0.5 * math.pi, -0.5 * math.pi + 0.3, 1.0, -2.0])  # tilted, turned, rates: well off the spins


def balance_error(spin, eps, t_end=1.0):
    """max |E(t) - E(0) - W(t)| over a run, W the work of friction and of the holding torque (quadratures in the
    integrator), and the total work |W(t_end)|."""
    system = held_spin.system()
    pars = system.with_pars(spin=spin, eps=eps)
    work = hy.make_vars("work")
    power = system.observables["friction_power"][0] + system.observables["holding_power"][0]
    ta = copy.deepcopy(system.taylor(1e-14, extra=[(work, power)]))
    ta.state[:] = [*START, 0.0]
    ta.pars[:] = pars[: len(ta.pars)]
    xs = ta.propagate_grid(np.linspace(0.0, t_end, 101))[-1]
    energy = system.observe(xs[:, :4].T.copy(), pars)["E_tot"]
    assert system.observe(xs[:, :4].T.copy(), pars)["lambda_N"].min() > 0  # a valid contact throughout
    return np.abs(energy - energy[0] - xs[:, 4]).max(), abs(xs[-1, 4])


def test_the_holding_torque_supplies_exactly_the_energy_rolling_gains():
    """At eps = 0 (rolling) the only work is the holding torque's: E(t) - E(0) = W(t) to rounding. A wrong
    torque or a wrong conversion of the angular acceleration to (beta_ddot, gamma_ddot) breaks this."""
    error, work = balance_error(32.0, 0.0)
    assert work > 5e-4 and error < 1e-10 * work


def test_with_friction_the_power_balance_holds_to_second_order_in_eps():
    """The slow flow's balance holds to O(eps^2) (first-order reduction); the held model's must do the same."""
    errors = [balance_error(32.0, eps)[0] for eps in (2e-3, 1e-3, 5e-4)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.5) & (ratios < 4.5)), (errors, ratios)


@pytest.mark.parametrize("disk", [Disk(), Disk(e=0.0035), Disk(r=0.05)], ids=["tables", "e3.5mm", "r50mm"])
def test_the_linearisation_at_the_inverted_spin_is_the_closed_forms(disk):
    """The Jacobian on (beta, gamma, beta_dot, gamma_dot) has the eigenvalues of K0 + eps K1 (slow flow, body
    rates): the holding torque does not enter at first order."""
    system = held_spin.system()
    for spin in (20.0, 30.0, 45.0):
        for eps in (0.1, 0.01):
            pars = system.with_pars(spin=spin, eps=eps, m=disk.m, e=disk.e, r=disk.r, A=disk.A, B=disk.B, C=disk.C)
            state = held_spin.spin_state("inverted")
            assert np.abs(system.f(state, pars)).max() < 1e-10
            K0, K1 = critical_spin.spin_matrices(spin, disk.m, disk.e, disk.r, disk.A, disk.B, disk.C, 9.81, 0.3)
            closed = np.sort_complex(np.linalg.eigvals(np.array(K0, float) + eps * np.array(K1, float)))
            held = np.sort_complex(np.linalg.eigvals(system.jacobian(state, pars)))
            assert np.abs(held - closed).max() < 1e-9 * np.abs(closed).max()


def hopf_points(eps):
    system = held_spin.system()
    branch = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                                   pars=system.with_pars(spin=20.0, eps=eps), ds_max=1.0)
    labels = [str(label) for label in branch.special_label.values]
    assert labels == ["HOPF1", "HOPF2"] and branch.attrs["status"] == "completed"
    return branch.spin.values[branch.special_index.values]


def test_the_hopf_points_of_the_inverted_spin_tend_to_the_closed_form_as_eps_squared():
    """The precession turns growing at HOPF1, the nutation turns damped at HOPF2 = omega_c (C4)."""
    closed = critical_spin.omega_critical()
    limits = np.array([closed.omega_precession, closed.omega_critical])
    errors = np.array([np.abs(hopf_points(eps) - limits) for eps in (0.02, 0.01, 0.005)])
    ratios = errors[:-1] / errors[1:]
    assert np.all((ratios > 3.5) & (ratios < 4.5)), (errors, ratios)
    assert errors[-1].max() < 5e-3


def test_from_table_3_the_held_disk_inverts_above_its_threshold_and_rolls_off_below():
    """eps = 0.01 m/s: held at 32.5 rad/s the start inverts; held at 30.0 rad/s (below omega_c) S never rises
    and the disk lifts off (docs/inversion.md: the held threshold lies near 31.5 rad/s)."""
    setup = inversion.with_eps(None, 0.01)
    above = inversion.outcome(32.5, model="held", setup=setup)
    below = inversion.outcome(30.0, model="held", setup=setup)
    assert above.status == "inverted" and below.status == "lift_off", (above, below)


def test_the_hopf_points_say_the_field_is_not_twice_differentiable_at_the_spin():
    """The slow flow holds |lambda_T| (smoothed at 1e-12 N), which vanishes at the spin: the field is C^1 there,
    so l1 does not apply (without the check it came out as -6e5 and -1.2e6, numbers of the smoothing)."""
    br = inverted_branch()
    assert list(br.special_label.values) == ["HOPF1", "HOPF2"]
    assert list(br.special_smooth.values) == [0, 0] and list(br.special_l1.values) == [0.0, 0.0]


def test_an_unknown_spin_is_refused_by_name():
    with pytest.raises(ParameterError, match="unknown spin 'upright'; choose one of inverted, lower"):
        held_spin.spin_state("upright")


def inverted_branch(eps=0.005):
    system = held_spin.system()
    return dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                                 pars=system.with_pars(spin=20.0, eps=eps), ds_max=1.0)


@pytest.mark.parametrize("name, bounds, scale", [("e", (2.0e-3, 3.0e-3), 1e-3), ("r", (0.042, 0.048), 0.01)])
def test_the_critical_spin_continued_in_e_and_r_lies_on_the_closed_form(name, bounds, scale):
    """HOPF2 continued in (spin, e) and (spin, r): another route to omega_c(e), omega_c(r) than (C4)."""
    curve = dy.special_point_curve(held_spin.system(), inverted_branch(), "HOPF2", ("spin", name),
                                   bounds={name: bounds, "spin": (20.0, 40.0)}, scales={name: scale, "spin": 1.0})
    assert curve.attrs["status"] == "completed" and curve.sizes["point"] > 5
    values = curve[name].values
    assert values.min() < bounds[0] + 1e-6 and values.max() > bounds[1] - 1e-6  # it spans the bounds
    for k in np.linspace(0, len(values) - 1, 5).astype(int):
        closed = critical_spin.omega_critical(dataclasses.replace(Disk(), **{name: float(values[k])}))
        assert abs(curve.spin.values[k] - closed.omega_critical) < 2e-4  # O(eps^2) at eps = 0.005


@pytest.mark.slow
def test_the_critical_spin_ends_at_a_bogdanov_takens_point_where_the_nutation_frequency_vanishes():
    """Towards small e the curve of HOPF2 meets a double zero eigenvalue (BT): in the closed form where the
    rolling nutation's frequency vanishes (c0 = 0 of (C1)) and its damping does (a1 = 0), solved here."""
    curve = dy.special_point_curve(held_spin.system(), inverted_branch(), "HOPF2", ("spin", "e"),
                                   bounds={"e": (0.7e-3, 2.5e-3), "spin": (20.0, 40.0)},
                                   scales={"e": 1e-3, "spin": 1.0})
    labels = [str(label) for label in curve.special_label.values]
    assert "BT1" in labels, curve.attrs["message"]
    i = curve.special_index.values[labels.index("BT1")]

    def conditions(x):
        disk = Disk(e=x[1] * 1e-3)
        _c2, c0, _a3, a1 = critical_spin.coefficients(x[0], disk.m, disk.e, disk.r, disk.A, disk.B, disk.C, 9.81, 0.3)
        return [c0 / 1e4, a1 / 1e3]

    spin, e_mm = fsolve(conditions, [curve.spin.values[i], curve.e.values[i] * 1e3])
    assert abs(curve.spin.values[i] - spin) < 3e-3 and abs(curve.e.values[i] * 1e3 - e_mm) < 3e-3


def test_the_critical_spin_does_not_depend_on_mu():
    """(C4) is homogeneous in the friction coefficients: HOPF2 continued in (spin, mu) stays at omega_c."""
    curve = dy.special_point_curve(held_spin.system(), inverted_branch(), "HOPF2", ("spin", "mu"),
                                   bounds={"mu": (0.2, 0.6), "spin": (20.0, 40.0)}, scales={"mu": 0.1, "spin": 1.0})
    assert curve.mu.values.min() < 0.2 + 1e-6 and curve.mu.values.max() > 0.6 - 1e-6
    assert np.abs(curve.spin.values - critical_spin.omega_critical().omega_critical).max() < 1e-4


def test_the_held_model_needs_the_spin_it_holds():
    with pytest.raises(ParameterError, match="the held model needs the spin it holds"):
        inversion.parameters("held", inversion.with_eps(None, 0.01))


def branch_point(e, eps):
    """The inverted spin of the held model continued in the spin at ``e``, ``eps``: its problem, branch and BP1."""
    system = held_spin.system()
    prob = EquilibriumProblem(system, [Parameter.of(system, "spin", 1.0)],
                              pars=system.with_pars(spin=20.0, eps=eps, e=e), bounds={0: (20.0, 40.0)})
    br = continue_branch(prob, np.append(held_spin.spin_state("inverted"), 20.0), Options(ds_max=0.5))
    (k,) = [k for k, sp in enumerate(br.special_points) if sp.kind == "branch_point"]
    return prob, br, k


def test_the_branch_point_of_a_nearly_balanced_disk_tends_to_the_closed_form_saddle_spin_as_eps_squared():
    """e = 0.9 mm < (A - B) / (m r): the held model's zero eigenvalue, continued, against c0 = 0 of (C6)."""
    (closed,) = critical_spin.saddle_spins(Disk(e=0.9e-3))
    errors = [branch_point(0.9e-3, eps)[1].special_points[branch_point(0.9e-3, eps)[2]].u[-1] - closed
              for eps in (0.01, 0.005)]
    assert 3.5 < errors[0] / errors[1] < 4.5 and abs(errors[1]) < 0.1  # measured 0.2457, 0.0627 rad/s


def test_at_the_branch_point_two_mirror_spins_turned_in_the_disks_plane_branch_off():
    """A pitchfork: the two new branches are images under (beta, gamma) -> (pi - beta, pi - gamma), exist above
    the branch point (where the inverted spin is a saddle) and are equilibria of the model (f = 0)."""
    prob, br, k = branch_point(0.9e-3, 0.005)
    new = switch_branch(prob, br, k)
    assert len(new) == 2
    ends = [b.points[-1].u for b in new]
    assert np.allclose([e[-1] for e in ends], 40.0)  # both run up to the bound: above the branch point, 29.54
    assert np.allclose(ends[0][:2] + ends[1][:2], math.pi, atol=1e-3)  # mirror images
    assert min(abs(e[1] - 0.5 * math.pi) for e in ends) > 0.25  # turned well away from S above G
    system = held_spin.system()
    for u in ends:
        assert np.abs(system.f(u[:4], system.with_pars(spin=u[-1], eps=0.005, e=0.9e-3))).max() < 1e-8


def test_the_pitchfork_curve_lies_on_c0_zero_and_meets_the_hopf_curve_at_the_same_bt_point():
    """BP1 and HOPF2 of a nearly balanced disk, each continued in (spin, e) from its own start: both end in one
    Bogdanov-Takens point, with no cusp on the pitchfork curve (its fold coefficient is undefined at a C^1
    spin), and the pitchfork curve lies on c0 = 0 of (C6) to O(eps^2)."""
    system = held_spin.system()
    br = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                               pars=system.with_pars(spin=20.0, eps=0.005, e=0.9e-3), ds_max=0.5)
    bt = {}
    for label in ("BP1", "HOPF2"):
        curve = dy.special_point_curve(system, br, label, ("spin", "e"), bounds={"e": (0.85e-3, 0.95e-3),
                                       "spin": (20.0, 40.0)}, scales={"e": 1e-3, "spin": 1.0})
        labels = [str(lab) for lab in curve.special_label.values]
        assert "BT1" in labels and not any(lab.startswith("CP") for lab in labels), (label, labels)
        k = curve.special_index.values[labels.index("BT1")]
        bt[label] = np.array([curve.spin.values[k], curve.e.values[k] * 1e3])
        if label == "BP1":
            closed = [critical_spin.saddle_spins(Disk(e=float(e)))[0] for e in curve.e.values]
            assert np.abs(curve.spin.values - closed).max() < 0.15  # 0.067 rad/s at 30 rad/s, eps = 0.005
    assert np.abs(bt["BP1"] - bt["HOPF2"]).max() < 1e-4

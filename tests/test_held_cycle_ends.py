"""Where branches of periodic orbits end and which turns are folds of cycles (dynamics/orbit_base.py), on textbook
cases with closed forms, then on the held-spin model's HOPF1 branch (eps = 0.01 m/s, Tables 1-2 disk) against a
multiple-shooting referee (scipy DOP853 at 1e-13, tippedisk_analysis.testing) and a run of the model itself."""

import copy
import math

import heyoka as hy
import numpy as np
import pytest

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics.collocation_floquet import CollocationFloquet
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.testing import product_multipliers, shooting_referee


def bautin_branch():
    """r' = r (beta + r^2 - r^4), theta' = 1: the Hopf branch turns at the fold of cycles beta = -1/4 (r^2 = 1/2,
    T = 2 pi), where the nontrivial multiplier exp(2 pi d(r g)/dr) passes 1."""
    return dy.hopf_branch(dy.textbook_system("bautin"), [0.0, 0.0], {"beta": 0.0, "l": 1.0}, "beta",
                          bounds=(-0.5, 0.1))


def resolved_to(monkeypatch, offset):
    """The multipliers as a discretisation that resolves them only roughly (as on the disk's orbits with
    multipliers of 1e60 and more, where the critical one was off by 0.14 and the flow direction's by 0.008): every
    nontrivial one moved by ``offset``, the flow direction's off 1 by 0.01."""
    exact, flow_error = CollocationFloquet.state_eigenvalues, CollocationFloquet.flow_multiplier_error
    monkeypatch.setattr(CollocationFloquet, "state_eigenvalues", lambda self, u: exact(self, u) + offset)
    monkeypatch.setattr(CollocationFloquet, "flow_multiplier_error", lambda self, u: max(flow_error(self, u), 0.01))


def test_a_fold_whose_multiplier_is_resolved_to_five_percent_is_found_by_the_crossing(monkeypatch):
    """Before: rejected as a numerical turn (its multiplier 1.05, not within 1e-3 of 1). The number of multipliers
    outside the unit circle changes across the turn (1 on the unstable inner cycles, 0 on the outer): a fold."""
    resolved_to(monkeypatch, 0.05)
    po = bautin_branch()
    labels = [str(label) for label in po.special_label.values]
    assert "LP1" in labels, po.attrs["unlocated"]
    k = int(po.special_index.values[labels.index("LP1")])
    assert abs(float(po.beta[k]) + 0.25) < 1e-8 and abs(float(po.period[k]) - 2 * math.pi) < 1e-8


def test_a_turn_without_a_crossing_stays_a_numerical_turn(monkeypatch):
    """Every multiplier moved by 3: none crosses the unit circle at the turn, so it is not a fold of cycles."""
    resolved_to(monkeypatch, 3.0)
    po = bautin_branch()
    assert "LP1" not in [str(label) for label in po.special_label.values]
    assert "outside the unit circle on both sides" in po.attrs["unlocated"]


def test_a_branch_ends_where_its_orbits_reach_a_terminal_event():
    """r' = r (beta - r^2), theta' = 1 with the event r = R (a model's edge, direction negative): the orbits
    r = sqrt(beta) reach it at beta = R^2, marked EVENT1; with end_at_events the branch ends there (status
    completed), its orbits kept, and its message names the event. Before: no such point, the branch ran on."""
    x, y = hy.make_vars("x", "y")
    beta, radius = hy.par[0], hy.par[1]
    r2 = x * x + y * y
    system = dy.System("hopf_with_edge", [x, y], [beta * x - y - x * r2, x + beta * y - y * r2],
                       {"beta": 0.0, "R": 0.5}, events=[dy.Event("edge", radius * radius - r2)])
    marked = dy.hopf_branch(system, [0.0, 0.0], {"beta": 0.0, "R": 0.5}, "beta", bounds=(-0.1, 1.0))
    assert [str(label) for label in marked.special_label.values] == ["EVENT1"]  # by default marked, not an end
    assert float(marked.beta.max()) == 1.0 and abs(float(marked.beta[int(marked.special_index[0])]) - 0.25) < 1e-8
    po = dy.hopf_branch(system, [0.0, 0.0], {"beta": 0.0, "R": 0.5}, "beta", bounds=(-0.1, 1.0), end_at_events=True)
    assert po.attrs["status"] == "completed"
    assert [str(label) for label in po.special_label.values] == ["EVENT1"]
    k = int(po.special_index.values[0])
    assert k == po.sizes["point"] - 1 and abs(float(po.beta[k]) - 0.25) < 1e-8
    assert abs(float(po.period[k]) - 2 * math.pi) < 1e-8 and float(po.beta.values[:-1].max()) < 0.25
    assert "event edge" in po.attrs["message"] and len(po.attrs["message"].splitlines()) == 1


EPS = 0.01


@pytest.fixture(scope="module")
def hopf1():
    system = held_spin.system()
    eq = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                               pars=system.with_pars(spin=20.0, eps=EPS), ds_max=1.0)
    return system, dy.orbit_branch(system, eq, "HOPF1", bounds=(20.0, 40.0), error_tol=1e-8, end_at_events=True)


def referee_multipliers(system, po, k, segments=64):
    samples = po.orbit[k].values
    period, jacobians = shooting_referee(system, po.runtime_parameters[k].values,
                                         samples[:: len(samples) // segments][:segments], float(po.period[k]))
    return period, [complex(z) for z in product_multipliers(jacobians)]


@pytest.mark.slow
def test_held_hopf1_branch_folds_at_35_3088_and_ends_where_its_orbits_reach_the_cone(hopf1):
    """Branch points BP1, BP2 (referee 28.7097628, 31.6715191), the fold of cycles LP1 near 35.3088 rad/s (before:
    rejected, its multiplier resolved only to 0.14 on orbits with multipliers of 1e62-1e72); then the branch ends at
    the model's cone event (|lambda_T| = 0.95 mu lambda_N of the rolling forces: the slow manifold's edge) near
    34.613 rad/s. The referee puts a nontrivial multiplier above 1 on the orbit before LP1 and below 1 after it
    (two, then one, outside the unit circle). Runs of the model (heyoka at 1e-14) along the last two orbits where
    they come nearest the cone follow them, and the last one touches the cone event (g = 0), the one before not."""
    system, po = hopf1
    assert po.attrs["status"] == "completed", po.attrs["message"]
    labels = [str(label) for label in po.special_label.values]
    assert labels == ["BP1", "BP2", "LP1", "EVENT1"], labels
    spins = po.spin.values[po.special_index.values]
    assert abs(spins[0] - 28.7097628) < 2e-6 and abs(spins[1] - 31.6715191) < 2e-5
    assert abs(spins[2] - 35.3088) < 1e-3 and abs(spins[3] - 34.613) < 1e-3
    assert "event cone" in po.attrs["message"]
    k = int(po.special_index.values[2])
    sides = []
    for j in (k - 1, k + 1):
        period, exact = referee_multipliers(system, po, j)
        assert abs(period / float(po.period[j]) - 1) < 1e-5
        trivial = min(range(len(exact)), key=lambda i: abs(exact[i] - 1))
        sides.append([z for i, z in enumerate(exact) if i != trivial])
    assert sum(abs(z) > 1 for z in sides[0]) == 2 and sum(abs(z) > 1 for z in sides[1]) == 1
    assert 1.1 < min(abs(z) for z in sides[0] if abs(z) > 1) < 2 and 0.5 < sorted(map(abs, sides[1]))[-2] < 0.9
    cone = system.function("cone", [e.expression for e in system.events if e.name == "cone"])
    end, before = po.sizes["point"] - 1, po.sizes["point"] - 2
    touch = []
    for j in (end, before):  # a run of the model over 6 samples around the orbit's nearest approach to the cone
        samples, pars = po.orbit[j].values, po.runtime_parameters[j].values
        k0 = int(np.argmin(system.evaluate(cone, samples.T.copy(), pars)[0])) - 3
        dt = float(po.sample_time[j, 1] - po.sample_time[j, 0])
        ta = copy.deepcopy(system.taylor(1e-14))
        ta.state[:] = samples[k0 % len(samples)]
        ta.pars[:] = pars[: len(ta.pars)]
        run = ta.propagate_grid(np.linspace(0.0, 6 * dt, 601))[-1]
        closest = samples[(k0 + 6) % len(samples)]
        assert np.max(np.abs(run[-1] - closest) / system.state_scale) < 1e-5  # the run follows the orbit
        g = system.evaluate(cone, run.T.copy(), pars)[0]
        touch.append(g.min() / np.abs(g).max())
    assert abs(touch[0]) < 2e-3 and touch[1] > touch[0], touch  # the end orbit touches the cone, the one before not

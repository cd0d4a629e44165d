"""The held-spin model's cycles from HOPF1 of the inverted spin (eps = 0.01 m/s, Tables 1-2 disk) by collocation:
the branch runs to its end without an exception, and its violently unstable orbits' multipliers, computed from the
condensed collocation blocks, agree with a multiple-shooting referee (scipy's DOP853 at rtol 1e-13 on
the variational equations over several segments, its own Newton iteration, the product of the segments'
monodromies and its eigenvalues in 100-digit arithmetic: tippedisk_analysis.testing)."""

import numpy as np
import pytest

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics.continuation import STATUSES
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.testing import product_multipliers, shooting_referee

EPS = 0.01
SAMPLE_SPINS = (28.0, 31.0, 32.5, 34.0, 35.0)


def inverted_spin():
    system = held_spin.system()
    return system, dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                                         pars=system.with_pars(spin=20.0, eps=EPS), ds_max=1.0)


@pytest.fixture(scope="module")
def hopf1_branch():
    """With the defaults, to the end."""
    system, eq = inverted_spin()
    return system, dy.orbit_branch(system, eq, "HOPF1", bounds=(20.0, 40.0))


@pytest.fixture(scope="module")
def accurate_branch():
    """With error_tol = 1e-8, to spin 35."""
    system, eq = inverted_spin()
    return system, dy.orbit_branch(system, eq, "HOPF1", bounds=(20.0, 35.0), error_tol=1e-8)


@pytest.mark.slow
def test_hopf1_branch_runs_to_its_end_without_an_exception(hopf1_branch):
    """Before: numpy.linalg.LinAlgError at spin 35.24414 (the monodromy formed by a dense solve), nothing
    returned. Now a dataset with a status and a one-line message, its orbits kept, every multiplier computed."""
    _system, po = hopf1_branch
    assert po.attrs["status"] in STATUSES
    assert len(po.attrs["message"].splitlines()) == 1
    assert po.sizes["point"] > 50 and float(po.spin.max()) > 35.0
    assert np.all(np.isfinite(po.multiplier_real.values))
    assert np.all(po.multiplier_source.values == 0)  # from the collocation blocks, none by shooting


@pytest.mark.slow
def test_both_branch_points_lie_where_the_referee_puts_them(accurate_branch):
    """The referee (multiple shooting at 1e-14) has the branch points of cycles at 28.7097628 and 31.6715191 rad/s;
    before, the second was missed (the multipliers of these orbits, up to 5e6, were wrong)."""
    _system, po = accurate_branch
    assert po.attrs["status"] == "completed", po.attrs["message"]
    labels = [str(label) for label in po.special_label.values]
    assert labels == ["BP1", "BP2"], labels
    spins = po.spin.values[po.special_index.values]
    assert abs(spins[0] - 28.7097628) < 2e-6 and abs(spins[1] - 31.6715191) < 2e-5, spins


@pytest.mark.slow
@pytest.mark.parametrize("spin", SAMPLE_SPINS)
def test_period_and_largest_multiplier_agree_with_a_multiple_shooting_referee(accurate_branch, spin):
    """At error_tol = 1e-8 the periods agree with the referee's to 1e-7 and the largest multiplier (up to 3e34 at
    spin 35) to 1e-3; the count of multipliers outside the unit circle is the referee's."""
    system, po = accurate_branch
    first_turn = int(np.argmax(np.diff(po.spin.values) < 0)) or po.sizes["point"]
    k = int(np.argmin(np.abs(po.spin.values[:first_turn] - spin)))
    samples = po.orbit[k].values
    segments = 32
    period, jacobians = shooting_referee(system, po.runtime_parameters[k].values,
                                         samples[:: len(samples) // segments][:segments], float(po.period[k]))
    exact = product_multipliers(jacobians)
    largest = float(abs(exact[0]))
    mine = float(np.max(np.hypot(po.multiplier_real[k].values, po.multiplier_imag[k].values)))
    assert abs(float(po.period[k]) / period - 1.0) < 1e-7
    assert abs(mine / largest - 1.0) < 1e-3
    trivial = min(range(len(exact)), key=lambda i: abs(exact[i] - 1))
    assert int(po.n_unstable[k]) == sum(abs(z) > 1 + 1e-3 for i, z in enumerate(exact) if i != trivial)

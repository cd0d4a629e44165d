"""Whether the Table 3 start inverts, and the initial spin above which it does (analysis/inversion.py):
runs checked against the unreduced ODE Model 1, thresholds by the runs that bracket them, the slow flow's
threshold against the smooth model's, and the set-valued limit that never lifts S above G."""

import math

import numpy as np
import pytest

import tippedisk_analysis as td
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.parameters import InitialState

DISK = td.Disk()
HEIGHT = DISK.r + inversion.INVERSION_HEIGHT * DISK.e


def test_a_run_ends_when_S_rises_and_ODE_model_1_sees_it_rise_then():
    run = inversion.outcome(40.0)
    assert run.inverted and run.status == "inverted" and 0.1 < run.time < 1.0
    full = td.simulate("ode-euler", 1.0, initial=InitialState(alpha_dot=40.0), dt_output=1e-4)  # not reduced
    first = float(full.time[np.argmax(full.z_S.values > HEIGHT)])
    assert abs(first - run.time) <= 1e-4
    low = inversion.outcome(30.0)
    assert low.status == "horizon" and low.inverted is False and low.time == inversion.horizon(0.1) == 150.0
    fell = inversion.outcome(30.0, setup=inversion.with_eps(None, 0.02))
    assert fell.status == "fell" and fell.inverted is False and fell.time < inversion.horizon(0.02) == 750.0


def test_the_threshold_is_bracketed_by_two_runs_that_differ():
    th = inversion.spin_threshold(bracket=(30.0, 36.0), scan=4, xtol=1e-2)
    assert th.status == "completed", th.message
    assert 0 < th.high - th.low <= 1e-2 and th.low < th.spin < th.high and len(th.crossings) == 1
    by_spin = {r.spin: r for r in th.runs}
    assert by_spin[th.low].inverted is False and by_spin[th.high].inverted is True
    assert inversion.outcome(th.low).inverted is False and inversion.outcome(th.high).inverted is True  # rerun


def test_the_highest_point_is_the_largest_sample_of_the_unreduced_ODE_model_1():
    """heyoka's events at the maxima of z_S against 1-ms samples of ODE Model 1 in its own (unreduced) state."""
    best = inversion.highest_point(33.0, horizon_s=8.0)
    assert best.status == "horizon" and 5.0 < best.time < 8.0  # S highest at a late top crossing, not the start
    full = td.simulate("ode-euler", 8.0, initial=InitialState(alpha_dot=33.0), dt_output=1e-3)
    k = int(np.argmax(full.z_S.values))
    sampled = (float(full.z_S[k]) - DISK.r) / DISK.e
    assert 0 <= best.height - sampled < 1e-4  # samples miss the peak by (dt * omega)^2 at most
    assert abs(best.time - float(full.time[k])) <= 1e-3
    assert best.energy_lost == pytest.approx(float(full.E_tot[0] - full.E_tot[k]), rel=1e-3)


def test_the_highest_point_passes_the_criterion_exactly_above_the_threshold():
    """Two code paths (a terminal event at r + 0.8 e; the maxima of z_S) agree on each side of the threshold."""
    th = inversion.spin_threshold(bracket=(33.0, 34.5), scan=3, xtol=2e-2)
    assert th.status == "completed", th.message
    below, above = inversion.highest_point(th.low), inversion.highest_point(th.high)
    assert below.height < inversion.INVERSION_HEIGHT < above.height
    assert above.height - below.height < 0.02  # a smooth curve: no jump at the threshold


def test_inside_the_friction_cone_the_slow_flow_gets_S_as_high_as_the_full_model():
    """The reduction against the full model: at eps = 0.01 m/s the slow flow's highest point equals ODE Model 1's
    to 0.01 e over the spins around the threshold (measured 0.003-0.006). Where the start slides (a drilled disk
    with e = 3.5 mm at its (C5) spin) the slow flow leaves the friction cone in the first swing instead."""
    setup = inversion.with_eps(None, 0.01)
    for spin in (32.5, 33.5, 34.1):
        slow, full = (inversion.highest_point(spin, model=m, setup=setup) for m in ("slow", "smooth"))
        assert 0.4 < full.height < 0.95 and abs(slow.height - full.height) < 0.01, (spin, slow, full)
    disk = td.Disk.from_geometry().with_eccentricity(3.5e-3)
    sliding = inversion.with_eps(td.Setup(disk=disk), 0.01)
    slow = inversion.highest_point(35.04, model="slow", setup=sliding)
    assert slow.status == "cone" and slow.time == 0.0  # ends at the cone before S rises at all
    curve = inversion.highest_points([35.04], model="slow", setup=sliding)
    assert curve.attrs["status"] == "partial" and "friction cone" in curve.attrs["message"]  # not "completed"
    assert inversion.highest_point(35.04, setup=sliding).height > 0.2  # the full model slides and rises


@pytest.mark.slow
def test_the_slow_flow_has_the_smooth_models_threshold():
    """The threshold is a property of the first-order slow flow: at eps = 5e-3 m/s (the inversion takes ~75 s,
    hundreds of wobbles) the two models' thresholds agree to 0.02 rad/s (measured 0.003)."""
    setup = inversion.with_eps(None, 5e-3)
    smooth = inversion.spin_threshold(model="smooth", setup=setup, bracket=(32.0, 36.0), scan=5, xtol=2e-3)
    slow = inversion.spin_threshold(model="slow", setup=setup, bracket=(32.0, 36.0), scan=5, xtol=2e-3)
    assert smooth.status == slow.status == "completed", (smooth.message, slow.message)
    assert abs(smooth.spin - slow.spin) < 0.02
    high = [r for r in smooth.runs if r.spin == smooth.high][0]
    assert high.time > 50.0  # a slow drift, not the first swing


def test_above_the_cone_the_slow_flow_ends_and_the_crossing_is_reported_as_a_second_one():
    th = inversion.spin_threshold(model="slow", setup=inversion.with_eps(None, 0.01), bracket=(32.0, 40.0), scan=5,
                                  xtol=0.05)
    assert th.status == "several_crossings" and len(th.crossings) == 2, th.message
    upper = [r for r in th.runs if r.spin >= th.crossings[1][1]]
    assert upper and all(r.status == "cone" and r.time < 1.0 for r in upper)  # slides during the first swing


def test_the_set_valued_limit_never_lifts_S_above_G():
    """The event-driven model (set-valued Coulomb friction) from Table 3 at 36 and 40 rad/s: after its last
    stick it rolls, and rolling conserves energy; S stays below G for 150 s."""
    for spin in (36.0, 40.0):
        run = td.simulate("h1", 150.0, initial=InitialState(alpha_dot=spin), dt_output=1e-3)
        assert run.attrs["status"] == "completed"
        assert float(run.z_S.max()) < DISK.r
        late = run.E_tot.values[run.time.values > 1.0]
        assert np.ptp(late) < 1e-9


@pytest.mark.slow
def test_moreau_model_1_never_lifts_S_above_G_and_its_energy_loss_is_the_time_steps():
    """Moreau Model 1 from Table 3 at 36 rad/s for 150 s at two time steps: S stays below G; the energy it loses
    after 1 s falls with dt (time-stepping dissipation, not friction's slow drift), and S's highest point falls
    with it towards the event-driven model's r - 0.994 e."""
    lost, highest = [], []
    for dt in (2e-5, 1e-5):
        run = td.simulate("m1", 150.0, initial=InitialState(alpha_dot=36.0), dt=dt, store_every=int(round(1e-3 / dt)),
                          progress=False)
        assert run.attrs["status"] == "completed"
        time, energy = run.time.values, run.E_tot.values
        lost.append(energy[np.searchsorted(time, 1.0)] - energy[-1])
        highest.append(float(run.z_S.max()))
        assert highest[-1] < DISK.r
    assert lost[0] > 1.2 * lost[1] > 0  # about first order in dt
    assert highest[1] < highest[0]


@pytest.mark.parametrize("call, fragment", [
    (lambda: inversion.outcome(40.0, model="moreau"), "unknown model 'moreau'"),
    (lambda: inversion.spin_threshold(bracket=(40.0, 30.0)), "give two spins 0 < low < high"),
    (lambda: inversion.spin_threshold(bracket=(30.0, math.inf)), "give two spins 0 < low < high"),
    (lambda: inversion.spin_threshold(scan=1), "give an integer scan >= 2"),
    (lambda: inversion.outcome(40.0, gamma0=1.4), "already above the criterion"),
    (lambda: inversion.outcome(40.0, horizon_s=-1.0), "must be positive"),
    (lambda: inversion.highest_point(40.0, horizon_s=math.nan), "horizon_s = nan: give a finite number"),
    (lambda: inversion.highest_point(40.0, model="h1"), "unknown model 'h1'"),
    (lambda: inversion.highest_points([33.0, -1.0]), "give a list of positive initial spins"),
    (lambda: inversion.highest_points([33.0, "abc"]), "give a list of positive initial spins"),
    (lambda: inversion.highest_point(-5.0), "give a positive initial spin"),
    (lambda: inversion.highest_point(33.0, gamma0="x"), "gamma0 = 'x': give a finite number"),
    (lambda: inversion.outcome(33.0, setup=td.Disk()), "setup is a Disk; give a Setup"),
])
def test_bad_input_is_one_line_naming_the_fix(call, fragment):
    with pytest.raises(td.ParameterError, match=fragment) as info:
        call()
    assert "\n" not in str(info.value)


def test_a_bracket_without_a_crossing_says_so():
    th = inversion.spin_threshold(bracket=(20.0, 30.0), scan=3)
    assert th.status == "no_crossing" and math.isnan(th.spin) and "widen the bracket" in th.message
    assert len(th.runs) == 3 and all(r.status == "horizon" for r in th.runs)

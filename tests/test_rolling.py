"""The rolling model (models/rolling.py) and the event-driven model of set-valued Coulomb friction
(solvers/hybrid.py, ``hybrid-euler``), checked against physics: Newton-Euler from the trajectory, energy,
and Moreau Model 1 (an independent, time-stepping formulation of the same law) converging to them."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import tippedisk_analysis as td
from tippedisk_analysis import kinematics as kin
from tippedisk_analysis.errors import ParameterError
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.models import event_driven, ode, rolling, sliding

SLIP_ONSET = 0.2889  # [s] the Table 3 start rolls until its contact force reaches the cone (measured below)


@pytest.fixture(scope="module")
def rolling_run():
    """The rolling System from the Table 3 start (the contact at rest) over its rolling phase, 0.1-ms samples."""
    system = rolling.as_system()
    ta = copy.copy(system.taylor(1e-14))
    ta.state[:], ta.pars[:], ta.time = rolling.initial_state_vector(td.InitialState()), system.pars[: len(ta.pars)], 0
    grid = np.linspace(0.0, 0.28, 2801)
    states = ta.propagate_grid(grid)[-1]
    return system, grid, states, system.observe(states.T)


def test_rolling_conserves_energy_and_its_force_is_newton_euler_of_the_motion(rolling_run):
    """The contact force the model returns equals m (a_S + g e_z) and the moment about S equals dL_S/dt, both
    measured by central differences of the trajectory (kinematics in numpy, independent of the model)."""
    system, t, x, obs = rolling_run
    E = obs["E_kin"] + obs["E_pot"]
    assert np.ptp(E) < 1e-13 * E[0]
    d = td.Disk()
    m, e, r, g = d.m, d.e, d.r, 9.81
    theta = np.diag([d.A, d.B - m * e * e, d.C - m * e * e])
    alpha, beta, gamma, omega = x[:, 2], x[:, 3], x[:, 4], x[:, 5:8]
    R = np.array([kin.rotation_from_euler(*a) for a in zip(alpha, beta, gamma)])
    r_GS = np.einsum("nij,j->ni", R, [e, 0.0, 0.0])
    Omega = np.einsum("nij,nj->ni", R, omega)
    v_G = np.stack([obs["x_dot"], obs["y_dot"], obs["z_dot"]], axis=1)
    v_S = v_G + np.cross(Omega, r_GS)
    L_S = np.einsum("nij,jk,nk->ni", R, theta, omega)
    h = t[1] - t[0]

    def rate(y):  # fourth-order central differences (error ~ h^4: 1e-9 N here)
        return (-y[4:] + 8 * y[3:-1] - 8 * y[1:-3] + y[:-4]) / (12 * h)

    F = m * (rate(v_S) + [0.0, 0.0, g])
    F_model = np.stack([obs["lambda_Tx"], obs["lambda_Ty"], obs["lambda_N"]], axis=1)[2:-2]
    np.testing.assert_allclose(F, F_model, atol=1e-8)
    r_GC = -r * np.array([kin.euler_floating_frame_ey_entries(a, b) for a, b in zip(alpha, beta)])
    np.testing.assert_allclose(rate(L_S), np.cross((r_GC - r_GS)[2:-2], F_model), atol=1e-10)
    v_C = v_G + np.cross(Omega, r_GC)  # the contact point at rest
    assert np.abs(v_C).max() < 1e-15


def test_moreau_model_1_converges_to_rolling_at_first_order(rolling_run):
    """From the Table 3 start the contact sticks until 0.289 s: Moreau Model 1's gamma approaches the rolling
    model's as dt (1.2e-3 rad at dt = 1e-4 s, measured 1.23e-3 / 1.23e-4 / 1.23e-5 for dt = 1e-4, 1e-5, 1e-6)."""
    _system, t, x, _obs = rolling_run
    errors = []
    for dt in (1e-4, 1e-5):
        run = td.simulate("m1", 0.25, dt=dt)
        errors.append(float(np.abs(run.gamma.values - np.interp(run.time.values, t, x[:, 4])).max()))
    assert errors[1] < 2e-4 and 8 < errors[0] / errors[1] < 12, errors


@pytest.fixture(scope="module")
def hybrid_run():
    return td.simulate("hybrid-euler", 8.0)


def test_hybrid_run_on_the_generic_layer_keeps_the_former_event_loop_results(hybrid_run):
    """Issue 31 moved hybrid-euler onto dynamics.hybrid (its modes and rules declared in models/event_driven.py).
    The run of the former hand-written event loop (solvers/hybrid.py before that change) stays to 1e-9."""
    ds = hybrid_run
    assert abs(float(ds.gamma.sel(time=8.0)) - 1.370928945584069) < 1e-9
    assert abs(float(ds.E_tot.sel(time=8.0)) - 0.3721948940514572) < 1e-9
    np.testing.assert_allclose(ds.switch_time.values[1:], [0.28891781720413595, 0.42827936187968546], rtol=0,
                               atol=1e-9)


def test_hybrid_rolls_slides_through_the_inversion_then_rolls_at_constant_energy(hybrid_run):
    ds = hybrid_run
    assert ds.attrs["status"] == "completed" and list(ds.switch_mode.values) == [0, 1, 0]
    t_onset, t_stick = ds.switch_time.values[1:]
    assert t_onset == pytest.approx(SLIP_ONSET, abs=1e-4) and 0.42 < t_stick < 0.44
    E, W = ds.E_tot.values, ds.W_friction.values
    assert np.abs(E - W - E[0]).max() < 5e-12  # the energy balance: only sliding friction works
    late = ds.time.values >= 2.0
    assert np.ptp(E[late]) / E[late].mean() < 1e-8
    assert np.all(ds.cone_margin.values[ds.mode.values == 0] > -1e-12)  # rolling only inside the cone
    assert np.all(ds.lambda_N.values > 0)
    slipping = ds.mode.values == 1
    assert np.all(np.hypot(ds.slip_x, ds.slip_y).values[~slipping] == 0)
    assert np.all(ds.P_friction.values[slipping] <= 1e-15) and np.all(ds.P_friction.values[~slipping] == 0)


def test_moreau_model_1_converges_to_the_hybrid_model_through_the_inversion(hybrid_run):
    """gamma on [0, 1] s (onset, slip, stick, rolling): measured 3.05e-3, 3.01e-4, 3.01e-5 rad for dt = 1e-4,
    1e-5, 1e-6 s; the energy after the inversion ends 5.1e-6 J apart at dt = 1e-5 s."""
    errors = []
    for dt in (1e-4, 1e-5):
        run = td.simulate("m1", 1.0, dt=dt)
        h = np.interp(run.time.values, hybrid_run.time.values, hybrid_run.gamma.values)
        errors.append(float(np.abs(run.gamma.values - h).max()))
    assert errors[0] < 1e-2 and 8 < errors[0] / errors[1] < 12, errors
    assert abs(float(run.E_tot[-1]) - float(hybrid_run.E_tot.sel(time=1.0, method="nearest"))) < 1e-5  # 5.1e-6 J


def test_slip_onset_keeps_the_contact_force_continuous():
    """The onset rule: sliding friction -mu lambda_N t with t = -lambda_T/|lambda_T| is the force rolling
    needed at the cone; lambda_N is the same in both modes there."""
    system = event_driven.hybrid_system()
    pars = ode.parameter_vector()
    x0 = np.append(rolling.initial_state_vector(td.InitialState()), 0.0)
    run = dy.simulate_hybrid(system, "rolling", x0, 1.0, pars=pars, max_switches=1)
    onset = run.switches[0]
    assert (onset.guard, onset.target) == ("slip_onset", "sliding")
    assert onset.time == pytest.approx(SLIP_ONSET, abs=1e-4)  # the cone
    o_roll = system.modes["rolling"].observe(onset.before, pars)
    phi = onset.after[sliding.STATE_NAMES.index("slip_angle")]
    at_rest = np.concatenate([onset.before[:8], [0.0, phi, 0.0]])  # the slip starting from 0 in its direction
    o_slide = system.modes["sliding"].observe(at_rest, pars)
    mu = td.Friction().mu
    assert o_slide["lambda_N"] == pytest.approx(o_roll["lambda_N"], rel=1e-12)
    np.testing.assert_allclose(-mu * o_slide["lambda_N"] * np.array([math.cos(phi), math.sin(phi)]),
                               [o_roll["lambda_Tx"], o_roll["lambda_Ty"]], rtol=1e-10)


def test_hybrid_runs_end_with_a_status_where_the_model_ends():
    fast = td.simulate("h1", 1.0, initial=td.InitialState(alpha_dot=200.0))
    assert fast.attrs["status"] == "lift_off" and "lambda_N fell through 0" in fast.attrs["message"]
    assert float(fast.lambda_N[-1]) == pytest.approx(0.0, abs=1e-9) and fast.time.values[-1] < 1.0
    zeno = td.simulate("h1", 1.0, max_switches=1)
    assert zeno.attrs["status"] == "zeno" and "more than 1 mode switches" in zeno.attrs["message"]
    with pytest.raises(ParameterError, match="max_switches"):
        td.simulate("h1", 1.0, max_switches=0)


def test_cli_simulates_and_plots_the_hybrid_model(tmp_path, capsys):
    from tippedisk_analysis.cli import main

    out = tmp_path / "h1.nc"
    assert main(["simulate", "--model", "h1", "--t-end", "0.6", "-o", str(out)]) == 0
    out_text = capsys.readouterr().out
    assert "started rolling, then 2 mode switch(es) that held longer than round-off, 1 to sliding" in out_text
    ds = td.load(out)
    assert ds.mode.attrs["flag_meanings"] == "rolling sliding" and ds.sizes["switch"] == 3
    assert main(["plot", str(out)]) == 0 and out.with_suffix(".png").stat().st_size > 10_000

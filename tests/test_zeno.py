"""Hybrid runs never pass through a guard, and switch times that accumulate end a run with status zeno: a ball
bouncing on a floor against the closed form (impacts t_k = t1 (1 + 2 e (1 - e^(k-1)) / (1 - e)), accumulating at
t_z = t1 (1 + 2 e / (1 - e)), t1 = sqrt(2 h0 / g)), an elastic ball hopping a micrometre (every flight shorter
than the blind stretch a jump used to skip), a hop below round-off, and the disk's hybrid-euler."""

from __future__ import annotations

import math
import subprocess
import sys

import heyoka as hy
import numpy as np
import pytest

from tippedisk_analysis import dynamics as dy

G = 9.81


def ball(restitution: float) -> dy.HybridSystem:
    """z'' = -g above the floor z = 0; an impact sets v -> -e v."""
    z, v = hy.make_vars("z", "v")
    g, e = hy.par[0], hy.par[1]
    flight = dy.System("flight", [z, v], [v, -g + 0.0 * z], {"g": G, "e": restitution}, strict_parameters=False)
    return dy.HybridSystem("ball", {"flight": flight}, [dy.Guard("impact", "flight", z, dy.Jump("flight", {"v": -e * v}))])


def impact_times(h0: float, e: float, count: int) -> np.ndarray:
    t1 = math.sqrt(2 * h0 / G)
    k = np.arange(1, count + 1)
    return t1 * (1 + 2 * e * (1 - e ** (k - 1)) / (1 - e)) if e != 1 else t1 * (2 * k - 1)


def samples(run) -> tuple[np.ndarray, np.ndarray]:
    return (np.concatenate([s.time for s in run.segments]), np.vstack([s.states for s in run.segments]))


def test_a_bouncing_ball_ends_zeno_at_the_accumulation_time():
    e, h0 = 0.8, 1.0
    t_z = math.sqrt(2 * h0 / G) * (1 + 2 * e / (1 - e))  # 4.0637 s
    run = dy.simulate_hybrid(ball(e), "flight", np.array([h0, 0.0]), 20.0, grid=np.linspace(0.0, 20.0, 2001))
    assert run.status == "zeno", run.message
    assert abs(run.accumulation - t_z) < 1e-6 * t_z and run.t_final < t_z
    assert f"{run.accumulation:.6g}" in run.message
    times = np.array([s.time for s in run.switches])
    assert np.abs(times[:20] - impact_times(h0, e, 20)).max() < 1e-10
    assert run.switches[-1].time == run.t_final  # the run ends after the last impact it resolved, before t_z
    _t, x = samples(run)
    assert x[:, 0].min() > -1e-12  # never below the floor


def test_an_elastic_ball_hopping_a_micrometre_bounces_to_the_end():
    """Each flight (0.9 ms) is shorter than the 1e-3 time units a jump used to skip blind: no impact is missed,
    the energy g z + v^2 / 2 stays g h0."""
    h0 = 1e-6
    run = dy.simulate_hybrid(ball(1.0), "flight", np.array([h0, 0.0]), 0.2)  # segments: their start and end
    assert run.status == "completed" and run.t_final == 0.2, run.message
    expected = impact_times(h0, 1.0, 500)
    expected = expected[expected < 0.2]
    times = np.array([s.time for s in run.switches])
    assert len(times) == len(expected) == 221 and np.abs(times - expected).max() < 1e-14  # 1.4e-16 s
    _t, x = samples(run)
    assert x[:, 0].min() > -1e-18
    assert np.abs(G * x[:, 0] + x[:, 1] ** 2 / 2 - G * h0).max() < 1e-13 * G * h0  # 2.6e-15 relative


def test_a_hop_below_round_off_is_not_a_fall_through_the_floor():
    """A jump to v = 1e-7 m/s rises 5e-16 m, under the guard's round-off: the ball stays on the floor and the run
    says so (zeno at once), never falling below it."""
    run = dy.simulate_hybrid(ball(1.0), "flight", np.array([0.0, 1e-7]), 1.0, grid=np.linspace(0.0, 1.0, 11))
    assert run.status == "zeno" and "round-off" in run.message, run.message
    assert run.accumulation == pytest.approx(0.0, abs=1e-9)
    _t, x = samples(run)
    assert x[:, 0].min() > -1e-12


def test_a_mode_without_events_runs_to_the_end():
    x = hy.make_vars("x")
    decay = dy.System("decay", [x], [-x])
    run = dy.simulate_hybrid(dy.HybridSystem("decay", {"only": decay}, []), "only", np.array([1.0]), 2.0)
    assert run.status == "completed" and run.segments[-1].states[-1, 0] == pytest.approx(math.exp(-2.0), rel=1e-12)


def test_overflowing_hybrid_runs_say_nonfinite_without_heyoka_log_lines(tmp_path):
    """heyoka logs 'event detection skipped due to an invalid timestep value of nan' (to the C stdout, flushed
    at exit: hence a process of its own) where a step's Taylor coefficients overflow; a run reads them off an
    event-free step first and ends nonfinite in the package's one line."""
    script = "; ".join([
        "import sys", "from tippedisk_analysis.cli import main",
        f"codes = [main(a + ['-o', r'{tmp_path}/' + str(i) + '.nc']) for i, a in enumerate({RUNS!r})]",
        "sys.exit(0 if codes == [1, 1] else 3)"])
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "heyoka" not in done.stdout + done.stderr
    assert done.stdout.count("non-finite") == 2 and not done.stderr.strip()


RUNS = [["simulate", "--model", "h1", "--t-end", "0.1", "--mu", "1e300"],
        ["poincare", "--model", "h1", "--omega", "1e150"]]


def test_the_disk_entered_rolling_on_the_cone_starts_sliding_at_once():
    """hybrid-euler from the state where the Table 3 run reaches the friction cone, in mode rolling: the cone
    guard is at zero and the force leaves the cone, so the slip starts at t = 0 (the former blind stretch let the
    disk roll on outside the cone, at a margin down to -0.43 N); the stick follows as in the uninterrupted run."""
    from tippedisk_analysis.models import event_driven, ode, rolling

    import tippedisk_analysis as td

    system, pars = event_driven.hybrid_system(), ode.parameter_vector()
    x0 = np.append(rolling.initial_state_vector(td.InitialState()), 0.0)
    onset = dy.simulate_hybrid(system, "rolling", x0, 1.0, pars=pars, max_switches=1).switches[0]
    run = dy.simulate_hybrid(system, "rolling", onset.before, 0.2, pars=pars, grid=np.linspace(0.0, 0.2, 201))
    assert run.status == "completed"
    assert [(s.guard, s.target) for s in run.switches] == [("slip_onset", "sliding"), ("stick", "rolling")]
    assert run.switches[0].time == 0.0
    assert onset.time + run.switches[1].time == pytest.approx(0.42827936187968546, abs=1e-9)
    for seg in run.segments:
        if seg.mode == "rolling":
            assert system.modes["rolling"].observe(seg.states.T, pars)["cone_margin"].min() > -1e-12


def thermostat(filippov: bool) -> dy.HybridSystem:
    """T' = -k (T - T_out) + P u, the heater on (u = 1) below T_set: two modes switching at T = T_set (a relay
    without hysteresis), or the Filippov system of the same two fields (its sliding mode holds T = T_set)."""
    T = hy.make_vars("T")
    k, t_out, power, t_set = (hy.par[i] for i in range(4))
    pars = {"k": 0.1, "T_out": 5.0, "P": 3.0, "T_set": 20.0}
    on = dy.System("on", [T], [-k * (T - t_out) + power], pars, strict_parameters=False)
    off = dy.System("off", [T], [-k * (T - t_out)], pars, strict_parameters=False)
    if filippov:
        return dy.filippov_system("thermostat", on, off, T - t_set)
    return dy.HybridSystem("thermostat", {"on": on, "off": off},
                           [dy.Guard("warm", "on", T - t_set, dy.Jump("off"), direction="positive"),
                            dy.Guard("cold", "off", T - t_set, dy.Jump("on"), direction="negative")])


def test_a_thermostat_without_a_sliding_mode_chatters_and_says_so():
    """Heated from 10 to 20 (T = 35 - 25 exp(-t / 10): at t = 10 ln(5/3)), the switched-off room cools below
    T_set at once, the heater starts at once: the switches accumulate there (zeno, never a room cooling to T_out
    unseen). The Filippov system of the same fields slides on T = T_set to the end."""
    t_reach = 10 * math.log(25 / 15)
    run = dy.simulate_hybrid(thermostat(False), "on", np.array([10.0]), 100.0, grid=np.linspace(0, 100, 101))
    assert run.status == "zeno" and "filippov_system" in run.message
    assert run.accumulation == pytest.approx(t_reach, abs=1e-12) and run.t_final == pytest.approx(t_reach, abs=1e-12)
    assert np.vstack([s.states for s in run.segments])[:, 0].max() < 20.0 + 1e-12
    sliding = dy.simulate_hybrid(thermostat(True), "minus", np.array([10.0]), 100.0, grid=np.linspace(0, 100, 101))
    assert sliding.status == "completed" and [s.target for s in sliding.switches] == ["sliding"]
    assert sliding.switches[0].time == pytest.approx(t_reach, abs=1e-12)
    assert abs(sliding.segments[-1].states[-1, 0] - 20.0) < 1e-12


def test_a_guard_resting_on_its_zero_neither_fires_nor_hides_another():
    """x stays 0 (its guard rests on its zero) while y = exp(-t) falls through 1/2 at t = ln 2."""
    x, y = hy.make_vars("x", "y")
    decay = dy.System("decay", [x, y], [0.0 * x, -y])
    system = dy.HybridSystem("rest", {"a": decay, "b": decay},
                             [dy.Guard("rest", "a", x, dy.Jump("b"), direction="any"),
                              dy.Guard("half", "a", y - 0.5, dy.Jump("b"), direction="negative")])
    run = dy.simulate_hybrid(system, "a", np.array([0.0, 1.0]), 2.0, grid=np.linspace(0.0, 2.0, 21))
    assert run.status == "completed" and [(s.guard, s.target) for s in run.switches] == [("half", "b")]
    assert run.switches[0].time == pytest.approx(math.log(2.0), abs=1e-14)
    t, states = samples(run)
    assert np.abs(states[:, 1] - np.exp(-t)).max() < 1e-14 and np.all(np.diff(t) >= 0)


def test_a_large_unrelated_state_leaves_the_guard_resolution_alone():
    """The ball carried along x' = 1 from x = 1e8: the floor's round-off is that of z, not of x, so the run
    resolves the same 42 impacts and the same accumulation time."""
    z, v, x = hy.make_vars("z", "v", "x")
    g, e = hy.par[0], hy.par[1]
    flight = dy.System("flight", [z, v, x], [v, -g + 0.0 * z, 1.0 + 0.0 * x], {"g": G, "e": 0.8},
                       strict_parameters=False)
    carried = dy.HybridSystem("carried", {"flight": flight},
                              [dy.Guard("impact", "flight", z, dy.Jump("flight", {"v": -e * v}))])
    run = dy.simulate_hybrid(carried, "flight", np.array([1.0, 0.0, 1e8]), 20.0)
    t_z = math.sqrt(2 / G) * (1 + 2 * 0.8 / 0.2)
    assert run.status == "zeno" and len(run.switches) == 42 and abs(run.accumulation - t_z) < 1e-6 * t_z
    assert np.abs([s.time for s in run.switches][:20] - impact_times(1.0, 0.8, 20)).max() < 1e-10

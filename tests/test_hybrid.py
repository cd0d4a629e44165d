"""Hybrid (event-driven) and Filippov systems of the generic layer against textbook answers in closed form:
a ball bouncing on a vibrating table (period-1 orbits and their multipliers), a stick-slip oscillator on a
moving belt (stick and slip segments, the superstable multiplier 0) and a relay system with a sliding segment
(Coulomb friction on a belt with negative damping, a Filippov system)."""

from __future__ import annotations

import math

import heyoka as hy
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.errors import ParameterError

G, OMEGA, RESTITUTION = 9.81, 20.0, 0.5
PERIOD = 2 * math.pi / OMEGA


def bouncing_ball(amplitude: float) -> dy.HybridSystem:
    """A ball in free flight above a table at height A sin(theta), theta' = omega (the forcing phase as the
    oscillator (c, s) = (cos theta, sin theta), its radius a first integral); impacts with restitution e."""
    z, v, c, s = hy.make_vars("z", "v", "c", "s")
    g, A, w, e = (hy.par[i] for i in range(4))
    flight = dy.System("flight", [z, v, c, s], [v, -g, -w * s, w * c],
                       {"g": G, "A": amplitude, "omega": OMEGA, "e": RESTITUTION}, integrals={"radius": c * c + s * s},
                       observables={"gap": z - A * s}, n_trivial=2, strict_parameters=False)
    impact = dy.Guard("impact", "flight", z - A * s, dy.Jump("flight", {"v": -e * v + (1 + e) * A * w * c}))
    return dy.HybridSystem("bouncing_ball", {"flight": flight}, [impact])


def ball_closed_form(amplitude: float, sign: int) -> tuple[float, np.ndarray]:
    """Impact phase theta* of the period-1 orbit (one impact per forcing period T) and the multipliers of the
    impact map (theta, u) -> (theta', u') by implicit differentiation of the flight equation
    A sin(theta) + u tau - g tau^2 / 2 = A sin(theta + omega tau) at tau = T."""
    T, e = PERIOD, RESTITUTION
    theta = sign * math.acos(G * T * (1 - e) / (2 * (1 + e) * amplitude * OMEGA))
    F_tau = -G * T / 2 - amplitude * OMEGA * math.cos(theta)  # relative velocity before the impact
    tau_u = -T / F_tau
    J = np.array([[1.0, OMEGA * tau_u],
                  [-(1 + e) * amplitude * OMEGA * math.sin(theta),
                   -e * (1 - G * tau_u) - (1 + e) * amplitude * OMEGA**2 * math.sin(theta) * tau_u]])
    return theta, np.linalg.eigvals(J)


@pytest.mark.parametrize("amplitude, sign, stability", [(0.03, 1, "stable"), (0.03, -1, "unstable"),
                                                        (0.05, 1, "unstable")])
def test_bouncing_ball_period_one_orbit_and_multipliers(amplitude, sign, stability):
    ball = bouncing_ball(amplitude)
    theta, expected = ball_closed_form(amplitude, sign)
    exact = np.array([amplitude * math.sin(theta), G * PERIOD / 2, math.cos(theta), math.sin(theta)])
    guess = dy.Leg("flight", exact + [2e-3, 0.03, 0.0, 0.0], 0.97 * PERIOD, "impact")
    orbit = dy.find_hybrid_orbit(ball, [guess])
    assert orbit.status == "converged", orbit.message
    assert orbit.period == pytest.approx(PERIOD, rel=1e-12)
    assert np.abs(orbit.legs[0].state - exact).max() < 1e-10
    nontrivial = np.sort_complex(orbit.multipliers[~orbit.trivial])
    assert np.abs(nontrivial - np.sort_complex(expected.astype(complex))).max() < 1e-9
    assert abs(np.prod(nontrivial) - RESTITUTION**2) < 1e-10  # the impact map contracts areas by e^2
    assert orbit.stability == stability


def test_bouncing_ball_run_returns_and_a_section_across_impacts():
    ball = bouncing_ball(0.03)
    theta, _ = ball_closed_form(0.03, 1)
    x0 = np.array([0.03 * math.sin(theta), G * PERIOD / 2, math.cos(theta), math.sin(theta)])
    run = dy.simulate_hybrid(ball, "flight", x0, 5.5 * PERIOD, tol=1e-15,
                             section={"quantity": "v", "level": 0.0, "direction": "negative"})
    assert run.status == "completed" and len(run.switches) == 5
    assert np.allclose([s.time for s in run.switches], PERIOD * np.arange(1, 6), rtol=0, atol=1e-12)
    assert np.abs(run.switches[-1].after - x0).max() < 1e-11
    times, states = run.crossings["flight"]  # the apex of each flight: v = 0 at t = u / g after the impact
    assert np.allclose(times, PERIOD * np.arange(5) + PERIOD / 2, atol=1e-12)
    assert np.allclose(states[:, 0], x0[0] + (G * PERIOD / 2) ** 2 / (2 * G), atol=1e-12)


FS, FD, BELT = 1.0, 0.6, 0.5  # static and dynamic friction force (per unit mass), belt speed; k = m = 1


def stick_slip() -> dy.HybridSystem:
    """x'' + x = friction: slipping slower than the belt, +F_d; faster, -F_d; sticking (x' = belt speed) while
    |x| <= F_s."""
    x, v = hy.make_vars("x", "v")
    fs, fd, vb = (hy.par[i] for i in range(3))
    pars = {"F_s": FS, "F_d": FD, "v_belt": BELT}
    modes = {"slip_back": dy.System("slip_back", [x, v], [v, -x + fd], pars, strict_parameters=False),
             "slip_ahead": dy.System("slip_ahead", [x, v], [v, -x - fd], pars, strict_parameters=False),
             "stick": dy.System("stick", [x, v], [vb, 0.0 * x], pars, strict_parameters=False)}
    sticks = (dy.Jump("stick", {"v": vb}, when=fs * fs - x * x),)
    guards = [dy.Guard("belt_speed", "slip_back", v - vb, (*sticks, dy.Jump("slip_ahead")), direction="positive"),
              dy.Guard("belt_speed", "slip_ahead", v - vb, (*sticks, dy.Jump("slip_back")), direction="negative"),
              dy.Guard("break_back", "stick", x - fs, dy.Jump("slip_back"), direction="positive"),
              dy.Guard("break_ahead", "stick", x + fs, dy.Jump("slip_ahead"), direction="negative")]
    return dy.HybridSystem("stick_slip", modes, guards)


def test_stick_slip_segments_in_closed_form():
    """From rest on the belt at x = F_s: slip on the circle of radius sqrt((F_s - F_d)^2 + v_b^2) about F_d for
    pi + 2 atan(v_b / (F_s - F_d)), stick from x = 2 F_d - F_s to F_s for 2 (F_s - F_d) / v_b."""
    system = stick_slip()
    a = FS - FD
    t_slip, t_stick = math.pi + 2 * math.atan(BELT / a), 2 * a / BELT
    run = dy.simulate_hybrid(system, "slip_back", np.array([FS, BELT]), 3 * (t_slip + t_stick) - 0.1, tol=1e-15)
    assert [s.target for s in run.switches] == ["stick", "slip_back"] * 2 + ["stick"]
    times = np.array([s.time for s in run.switches])
    expected = np.cumsum([t_slip, t_stick] * 3)[:5]
    assert np.abs(times - expected).max() < 1e-12
    assert np.allclose([s.after[0] for s in run.switches], [2 * FD - FS, FS] * 2 + [2 * FD - FS], atol=1e-12)
    legs = dy.legs_from_run(run)  # the cycle found from the run: stick, then slip
    assert [leg.mode for leg in legs] == ["stick", "slip_back"]
    orbit = dy.find_hybrid_orbit(system, legs)
    assert orbit.status == "converged", orbit.message
    assert orbit.period == pytest.approx(t_slip + t_stick, rel=1e-13)
    # sticking forgets the velocity: the nontrivial multiplier is 0 (superstable)
    assert abs(orbit.multipliers[~orbit.trivial][0]) < 1e-12 and orbit.stability == "stable"


ZETA, F_RELAY = 0.1, 1.0


def relay() -> dy.HybridSystem:
    """x'' - 2 zeta x' + x = -F sign(x' - v_b): Coulomb friction on a belt (a relay in the relative velocity)
    with negative damping, as a Filippov system on h = x' - v_b; its sliding motion is sticking."""
    x, v = hy.make_vars("x", "v")
    zeta, force, vb = (hy.par[i] for i in range(3))
    pars = {"zeta": ZETA, "F": F_RELAY, "v_belt": BELT}
    minus = dy.System("slow", [x, v], [v, -x + 2 * zeta * v + force], pars, strict_parameters=False)
    plus = dy.System("fast", [x, v], [v, -x + 2 * zeta * v - force], pars, strict_parameters=False)
    return dy.filippov_system("relay", minus, plus, v - vb)


def relay_closed_form() -> tuple[float, float, float]:
    """(slip time, x where sticking starts, x where it ends): the slip from the sliding exit x_e = F + 2 zeta v_b
    solves u'' - 2 zeta u' + u = 0 (u = x - F) in closed form; it returns to v = v_b at the first root."""
    w = math.sqrt(1 - ZETA**2)
    a, b = 2 * ZETA * BELT, (BELT - 2 * ZETA**2 * BELT) / w

    def u(t):
        return math.exp(ZETA * t) * (a * math.cos(w * t) + b * math.sin(w * t))

    def du(t):
        return math.exp(ZETA * t) * ((ZETA * a + w * b) * math.cos(w * t) + (ZETA * b - w * a) * math.sin(w * t))

    t = np.linspace(0.1, 2 * math.pi, 2000)
    k = int(np.flatnonzero(np.diff(np.sign([du(s) - BELT for s in t])) > 0)[0])
    t_slip = brentq(lambda s: du(s) - BELT, t[k], t[k + 1], xtol=1e-15, rtol=1e-15)
    return t_slip, F_RELAY + u(t_slip), F_RELAY + 2 * ZETA * BELT


def test_relay_filippov_sliding_segment_and_orbit():
    system = relay()
    t_slip, x_return, x_exit = relay_closed_form()
    t_stick = (x_exit - x_return) / BELT
    run = dy.simulate_hybrid(system, "minus", np.array([0.0, 0.0]), 40.0, tol=1e-15)
    assert run.status == "completed"
    modes = [s.target for s in run.switches]
    assert "sliding" in modes and modes.count("plus") == 0
    exits = [s for s in run.switches if s.source == "sliding"]
    assert exits and np.allclose([s.before[0] for s in exits], x_exit, atol=1e-12)  # sigma_- = 0 in closed form
    assert np.allclose([s.before[1] for s in exits], BELT, atol=1e-12)  # the sliding motion stays on h = 0
    # the last cycle: slip t_slip, stick t_stick, against the closed form
    last = run.switches[-2:] if run.switches[-1].source == "sliding" else run.switches[-3:-1]
    entry, leave = (last[0], last[1]) if last[0].target == "sliding" else (last[1], None)
    assert leave is not None and leave.time - entry.time == pytest.approx(t_stick, rel=1e-10)
    assert entry.before[0] == pytest.approx(x_return, abs=1e-10)
    orbit = dy.find_hybrid_orbit(system, dy.legs_from_run(run))
    assert [leg.mode for leg in orbit.legs] in (["minus", "sliding"], ["sliding", "minus"])
    assert orbit.status == "converged", orbit.message
    assert orbit.period == pytest.approx(t_slip + t_stick, rel=1e-12)
    sliding_exit = [S for S, leg in zip(orbit.saltations, orbit.legs) if leg.mode == "sliding"]
    assert np.abs(sliding_exit[0] - np.eye(2)).max() < 1e-12  # leaving the surface: S = I
    assert abs(orbit.multipliers[~orbit.trivial][0]) < 1e-12  # sliding collapses the transversal direction


def test_relay_run_matches_an_independent_simulation():
    """Before it first reaches the surface the relay run is the smooth 'slow' field: scipy's DOP853 agrees."""
    system = relay()
    run = dy.simulate_hybrid(system, "minus", np.array([0.0, 0.0]), 40.0, tol=1e-15)
    first = run.switches[0]
    ref = solve_ivp(lambda t, y: [y[1], -y[0] + 2 * ZETA * y[1] + F_RELAY], (0, first.time), [0.0, 0.0],
                    method="DOP853", rtol=1e-13, atol=1e-13)
    assert np.abs(ref.y[:, -1] - first.before).max() < 1e-9


def test_a_run_without_a_closed_cycle_says_so():
    system = relay()
    run = dy.simulate_hybrid(system, "minus", np.array([0.0, 0.0]), 3.0, tol=1e-15)  # one jump in and out only
    with pytest.raises(ParameterError, match="no closed cycle"):
        dy.legs_from_run(run)


def test_declaration_errors_name_the_problem():
    x, v = hy.make_vars("x", "v")
    a = dy.System("a", [x, v], [v, -x])
    b = dy.System("b", [x, v], [v, -x - hy.par[0]], {"k": 1.0})
    with pytest.raises(ParameterError, match="every mode takes the same"):
        dy.HybridSystem("h", {"a": a, "b": b}, [])
    with pytest.raises(ParameterError, match="no target mode 'c'"):
        dy.HybridSystem("h", {"a": a}, [dy.Guard("g", "a", x, dy.Jump("c"))])
    y = hy.make_vars("y")
    c = dy.System("c", [y], [-y])
    with pytest.raises(ParameterError, match="give the state 'y' in reset"):
        dy.HybridSystem("h", {"a": a, "c": c}, [dy.Guard("g", "a", x, dy.Jump("c"))])
    with pytest.raises(ParameterError, match="direction"):
        dy.Guard("g", "a", x, dy.Jump("a"), direction="down")
    system = dy.HybridSystem("h", {"a": a}, [dy.Guard("g", "a", x, dy.Jump("a", when=-1.0 + 0.0 * x))])
    run = dy.simulate_hybrid(system, "a", np.array([1.0, 0.0]), 10.0)
    assert run.status == "no_jump" and "none of its jumps applies" in run.message

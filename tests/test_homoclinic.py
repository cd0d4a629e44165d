"""Homoclinic orbits by the side on which a one-dimensional manifold leaves its saddle again
(tippedisk_analysis.dynamics.homoclinic), on systems with known answers."""

import math

import heyoka as hy
import numpy as np
import pytest
from scipy.optimize import brentq

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics import homoclinic as hc
from tippedisk_analysis.errors import ParameterError


def _loop(shifted: bool = False) -> dy.System:
    """The catalogue's Hamiltonian loop with energy-selecting damping, y' = x - x^2 - y (H - c - d): the level
    H = c + d is invariant, so the saddle's loop H = 0 is a homoclinic orbit exactly on the line c = -d."""
    x, y = hy.make_vars("x", "y")
    H = y * y / 2 - x * x / 2 + x * x * x / 3
    return dy.System("loop_cd", (x, y), (y, x - x * x - y * (H - hy.par[0] - hy.par[1])), {"c": -0.1, "d": 0.0})


def test_the_loop_of_the_textbook_system_is_found_at_c_0():
    loop = dy.textbook_system("homoclinic")
    found = hc.homoclinic_point(loop, (0.0, 0.0), "c", (-0.05, 0.08))
    assert found["status"] == "completed", found["message"]
    assert abs(found["value"]) < 1e-9
    assert found["lambda_1"] == pytest.approx(1.0)
    assert found["stay"] > hc.STAY_FACTOR  # lambda_1 = 1
    # the other branch of the unstable manifold runs off to x -> -infinity on both sides of c = 0
    assert hc.homoclinic_point(loop, (0.0, 0.0), "c", (-0.05, 0.08), branch=-1)["status"] == "no_crossing"


def test_the_homoclinic_curve_of_a_two_parameter_loop_is_the_line_c_minus_d():
    ds = hc.homoclinic_curve(_loop(), (0.0, 0.0), "c", "d", np.linspace(0.0, 0.05, 4), (-0.02, 0.03))
    assert list(ds.status.values) == ["completed"] * 4
    np.testing.assert_allclose(ds.c.values, -ds.d.values, atol=1e-9)
    # steps in d far wider than the bracket: the bracket is widened until the side changes
    wide = hc.homoclinic_curve(_loop(), (0.0, 0.0), "c", "d", [0.0, 0.05, 0.1], (-0.01, 0.01))
    assert list(wide.status.values) == ["completed"] * 3
    np.testing.assert_allclose(wide.c.values, [0.0, -0.05, -0.1], atol=1e-9)


def _ab_saddle(D: float) -> tuple[float, float]:
    """The middle equilibrium (a saddle) of AUTO-07p's demo 'ab' (B = 14, beta = 2), from u2 alone."""
    def u1(u2):
        return D * math.exp(u2) / (1 + D * math.exp(u2))
    u2 = brentq(lambda u: -u + 14.0 * u1(u) - 2.0 * u, 1.5, 3.0)
    return u1(u2), u2


def test_the_homoclinic_limit_of_auto_demo_ab_is_auto07ps():
    """AUTO-07p's demo 'ab' continues its periodic orbits to a homoclinic limit at D = 0.10550707 (the period
    grows without bound); here the saddle's unstable manifold returns to it at the same D."""
    ab = dy.textbook_system("ab")
    found = hc.homoclinic_point(ab, _ab_saddle(0.104), "D", (0.100, 0.1057), ab.with_pars(D=0.104))
    assert found["status"] == "completed", found["message"]
    assert found["value"] == pytest.approx(0.10550707, abs=5e-9)


def test_the_lorenz_homoclinic_explosion_is_at_rho_13_9265574():
    """sigma = 10, beta = 8/3: the origin's unstable manifold returns to it at rho = 13.9265574 (literature);
    a scan over rho 5-20 finds that one crossing, and only it."""
    lorenz = dy.textbook_system("lorenz")
    found = hc.homoclinic_point(lorenz, (0.0, 0.0, 0.0), "rho", (10.0, 20.0), lorenz.with_pars(rho=10.0))
    assert found["status"] == "completed", found["message"]
    assert found["value"] == pytest.approx(13.9265574, abs=1e-6)
    scan = hc.homoclinic_scan(lorenz, (0.0, 0.0, 0.0), "rho", np.arange(5.0, 20.1, 1.0), lorenz.with_pars(rho=5.0))
    assert list(scan.crossing_status.values) == ["completed"]
    assert scan.crossing_value.values[0] == pytest.approx(found["value"], abs=1e-8)


def test_a_change_of_side_that_is_a_jump_is_refused():
    """In Lorenz's chaotic range (rho 24-28) the branch's side at its closest approach changes between scan values
    without the branch coming back to the origin: no homoclinic orbit, and the check says so at every change. Where
    the changes fall depends on round-off in the chaotic runs, so the scan finds them rather than a fixed bracket."""
    lorenz = dy.textbook_system("lorenz")
    scan = hc.homoclinic_scan(lorenz, (0.0, 0.0, 0.0), "rho", np.arange(24.0, 28.01, 1.0), lorenz.with_pars(rho=24.0))
    assert scan.sizes["crossing"] >= 1
    assert set(scan.crossing_status.values) == {"not_verified"}
    assert all("no_return" in str(m) and "not a homoclinic orbit" in str(m) for m in scan.crossing_message.values)


def _no_equilibrium() -> dy.System:
    x, y = hy.make_vars("x", "y")
    return dy.System("no_equilibrium", (x, y), (hy.par[0] + x * x, -y), {"a": 1.0})


def test_bad_input_is_refused_in_one_line():
    lorenz = dy.textbook_system("lorenz")
    origin = (0.0, 0.0, 0.0)
    calls = {"manifold": lambda: hc.manifold_return(lorenz, origin, manifold="sideways"),
             "branch": lambda: hc.manifold_return(lorenz, origin, branch="+w"),
             "pair": lambda: hc.homoclinic_point(lorenz, origin, "rho", (10.0,)),
             "low < high": lambda: hc.homoclinic_point(lorenz, origin, "rho", (20.0, 10.0)),
             "finite numbers": lambda: hc.homoclinic_scan(lorenz, origin, "rho", [10.0, math.nan]),
             "2-dimensional": lambda: hc.manifold_return(lorenz, origin, manifold="stable"),
             "no equilibrium": lambda: hc.manifold_return(_no_equilibrium(), (0.0, 0.0))}
    for words, call in calls.items():
        with pytest.raises(ParameterError, match=words):
            call()


def _pendulum() -> dy.System:
    """The damped pendulum with a constant torque, x'' + delta x' + sin x = tau: its saddle (pi - asin tau, 0)
    has a loop once round (x -> x + 2 pi) where tau / delta -> 4 / pi as delta -> 0 (Melnikov)."""
    x, y = hy.make_vars("x", "y")
    return dy.System("torque_pendulum", (x, y), (y, hy.par[0] - hy.sin(x) - hy.par[1] * y),
                     {"tau": 0.0, "delta": 0.1})


def test_the_torque_pendulums_loop_tends_to_melnikovs_ratio():
    """A system none of the code was tuned on: tau / delta at the loop approaches 4 / pi like delta^2."""
    pendulum = _pendulum()
    gaps = []
    for delta in (0.05, 0.025):
        found = hc.homoclinic_point(pendulum, (math.pi, 0.0), "tau", (0.5 * delta, 2.0 * delta),
                                    {"delta": delta, "tau": 0.5 * delta}, shift=(2 * math.pi, 0.0))
        assert found["status"] == "completed", found["message"]
        gaps.append(4 / math.pi - found["value"] / delta)
    assert 0 < gaps[1] < gaps[0] / 3.5  # O(delta^2)


def test_inputs_that_would_hang_or_be_misread_are_refused():
    pendulum = _pendulum()
    pars = {"tau": 0.1, "delta": 0.1}
    saddle = (math.pi, 0.0)
    calls = {"xtol": lambda: hc.homoclinic_point(pendulum, saddle, "tau", (0.1, 0.15), pars, xtol=0.0),
             "shift": lambda: hc.manifold_return(pendulum, saddle, pars, shift=2 * math.pi),
             "radius": lambda: hc.manifold_return(pendulum, saddle, pars, radius=0.0),
             "offset": lambda: hc.manifold_return(pendulum, saddle, pars, offset=-1e-7),
             "t_max": lambda: hc.manifold_return(pendulum, saddle, pars, t_max=math.inf),
             "branch": lambda: hc.manifold_return(pendulum, saddle, pars, branch=True),
             "state": lambda: hc.manifold_return(pendulum, ("pi", 0.0), pars),
             "another one": lambda: hc.homoclinic_curve(pendulum, saddle, "tau", "tau", [0.1], (0.1, 0.15), pars),
             "duration": lambda: hc.manifold_branch(pendulum, saddle, pars, duration=-5.0),
             "samples": lambda: hc.manifold_branch(pendulum, saddle, pars, samples=0),
             "shorter duration": lambda: hc.manifold_branch(dy.textbook_system("homoclinic"), (0.0, 0.0),
                                                            {"c": 0.05}, duration=60.0),
             "pair": lambda: hc.homoclinic_point(pendulum, saddle, "tau", "12", pars),
             "lost at tau": lambda: hc.homoclinic_point(pendulum, saddle, "tau", (0.1, 1.5), pars)}
    for words, call in calls.items():
        with pytest.raises(ParameterError, match=words):
            call()


def test_an_end_where_the_side_is_undefined_is_looked_inside():
    """Sandstede's three-dimensional system (AUTO-07p demo 'san'), with a = 0, b = 1, c = -2, beta = 1,
    gamma = mu = 0: x' = y + m x (2 - 3x), y' = x - 3/2 x^2 - 2 m y, z' = -2z + alpha (x^2 (1 - x) - y^2),
    m = mutilde - alpha z. At mutilde = 0, z = 0 and the loop y^2 = x^2 (1 - x) are invariant: a homoclinic orbit
    for every alpha. At alpha = 0 and mutilde = -0.1 the branch escapes without coming near the saddle, so that
    end of the bracket says nothing, and points inside it decide."""
    x, y, z = hy.make_vars("x", "y", "z")
    mutilde, alpha = hy.par[0], hy.par[1]
    m = mutilde - alpha * z
    san = dy.System("sandstede", (x, y, z), (y + m * x * (2 - 3 * x), x - 1.5 * x * x - 2 * m * y,
                                              -2 * z + alpha * (x * x * (1 - x) - y * y)),
                    {"mutilde": 0.0, "alpha": 0.0})
    for a in (0.0, 0.5, 1.0):
        found = hc.homoclinic_point(san, (0.0, 0.0, 0.0), "mutilde", (-0.1, 0.05), {"alpha": a})
        assert found["status"] == "completed", found["message"]
        assert abs(found["value"]) < 1e-9

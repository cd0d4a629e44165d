"""Families of symmetric periodic orbits and their Melnikov drift (dynamics.symmetric_families), proven on the
Duffing oscillator with van der Pol damping, x'' = x - x^3 + p (beta x^2 - alpha) x', whose answers are
quadratures along the exact orbits: at p = 0 the energy H = v^2/2 - x^2/2 + x^4/4 is conserved, the orbits about
x = 1 turn at x_min = a and x_max, and one revolution changes H by p (beta I2 - alpha I0), I_k = the loop integral
of x^k v dx (Guckenheimer & Holmes 4.5); the amplitude a = x_min then moves by dH / (dH/da). The drift vanishes
at beta / alpha = I0 / I2: 1 for small orbits (the Hopf point of x = 1) and 5/4 at the homoclinic loop a -> 0."""

from __future__ import annotations

import math

import heyoka as hy
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ellipk

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics.melnikov import family_drift
from tippedisk_analysis.dynamics.symmetric_families import Shooting, symmetric_family
from tippedisk_analysis.errors import ParameterError

x, v = hy.make_vars("x", "v")
SHOOTING = Shooting(fixed={"v": 0.0}, vary="x", section=dy.Event("turn", v, "negative"), period_factor=2.0)
AMPLITUDES = np.array([0.05, 0.2, 0.5, 0.8, 0.95])


def duffing_vdp(alpha: float = 1.0, beta: float = 1.1) -> dy.System:
    return dy.System("duffing_vdp_melnikov", [x, v], [v, x - x**3 + hy.par[0] * (hy.par[2] * x**2 - hy.par[1]) * v],
                     parameters={"p": 0.0, "alpha": alpha, "beta": beta})


def exact(a: float) -> dict:
    """Period, the loop integrals I0, I2 and dH/da of the orbit through x_min = a, by quadrature."""
    x_max = math.sqrt(2.0 - a**2)  # V(x) = -x^2/2 + x^4/4 = V(a) at x = a and x_max

    # x = a + (x_max - a) sin^2(theta/2): dx = k dtheta and v = k q with k = (x_max - a) sin(theta/2) cos(theta/2),
    # q = sqrt((x + a)(x_max + x) / 2) (v^2 = 2 (V(a) - V(x)) = (x^2 - a^2)(x_max^2 - x^2) / 2): no square root
    # vanishes at the turning points
    def through(m, n):  # the integral of x^m v^n dx from a to x_max
        def integrand(th):
            s = a + (x_max - a) * math.sin(0.5 * th) ** 2
            k = 0.5 * (x_max - a) * math.sin(th)
            return s**m * k ** (n + 1) * math.sqrt((s + a) * (x_max + s) / 2.0) ** n
        return quad(integrand, 0.0, math.pi, epsabs=1e-14, epsrel=1e-13, limit=400)[0]

    return {"period": 2.0 * through(0, -1), "I0": 2.0 * through(0, 1),
            "I2": 2.0 * through(2, 1), "dH_da": a**3 - a}


@pytest.fixture(scope="module")
def family():
    system = duffing_vdp()
    return system, symmetric_family(system, SHOOTING, (0.5, None), (0.0, 1.0), amplitudes=AMPLITUDES)


def test_the_periods_of_the_family_are_the_quadratures(family):
    _system, ds = family
    exact_periods = np.array([exact(a)["period"] for a in AMPLITUDES])
    assert ds.attrs["status"] == "completed"
    assert np.allclose(ds.period.values, exact_periods, rtol=1e-10)
    # the orbit closes: the section is the right turning point, where x = x_max and v = 0
    x_max = np.sqrt(2 - AMPLITUDES**2)
    assert np.allclose(ds.crossing.sel(state="x").values, x_max, atol=1e-10)


@pytest.mark.parametrize("beta", [0.9, 1.1, 1.3])
def test_the_drift_is_the_melnikov_integral(beta):
    system = duffing_vdp(beta=beta)
    amplitudes = np.array([0.04, 0.05, 0.06, 0.49, 0.5, 0.51, 0.89, 0.9, 0.91])
    ds = symmetric_family(system, SHOOTING, (0.5, None), (0.0, 1.0), amplitudes=amplitudes)
    drift = family_drift(system, ds, SHOOTING, "p")
    middle = [1, 4, 7]
    assert drift.drift_valid.values[middle].all()
    for k in middle:
        q = exact(amplitudes[k])
        melnikov = (beta * q["I2"] - 1.0 * q["I0"]) / q["dH_da"]
        assert drift.drift.values[k] == pytest.approx(melnikov, rel=2e-4, abs=1e-7)
        assert drift.drift_rate.values[k] == pytest.approx(melnikov / q["period"], rel=2e-4, abs=1e-7)


def test_the_drift_vanishes_between_the_hopf_point_and_the_homoclinic_loop():
    """beta/alpha = I0/I2 at the zero: 1 as a -> 1 (Hopf), 5/4 as a -> 0 (the loop)."""
    for a, limit in ((0.999, 1.0), (1e-4, 1.25)):
        q = exact(a)
        ratio = q["I0"] / q["I2"]
        assert ratio == pytest.approx(limit, abs=2e-3)
    a = 0.3
    ratio = exact(a)["I0"] / exact(a)["I2"]
    signs = []
    for beta in (ratio * (1 - 1e-3), ratio * (1 + 1e-3)):
        system = duffing_vdp(beta=beta)
        ds = symmetric_family(system, SHOOTING, (0.5, None), (0.0, 1.0), amplitudes=[a - 0.01, a, a + 0.01])
        signs.append(np.sign(family_drift(system, ds, SHOOTING, "p").drift.values[1]))
    assert signs == [1.0, -1.0]  # below the zero the orbit shrinks (x_min = a grows towards x = 1), above it grows


def test_bad_requests_are_refused_in_one_line(family):
    system, ds = family
    with pytest.raises(ParameterError, match="no state"):
        Shooting(fixed={"w": 0.0}, vary="x", section=SHOOTING.section).check(system)
    with pytest.raises(ParameterError, match="every state once"):
        Shooting(fixed={}, vary="x", section=SHOOTING.section).check(system)
    with pytest.raises(ParameterError, match="needs the amplitudes"):
        symmetric_family(system, SHOOTING, (0.5, None), (0.0, 1.0))
    with pytest.raises(ParameterError, match="compute it at 0"):
        family_drift(system, ds.assign_attrs(config=ds.attrs["config"].replace('"p": 0.0', '"p": 0.1')), SHOOTING, "p")
    with pytest.raises(ParameterError, match="symmetric_family"):
        family_drift(system, ds.assign_attrs(kind="continuation"), SHOOTING, "p")


# ---------------------------------------------------------------- a system it was not built on: the pendulum
PENDULUM = Shooting(fixed={"v": 0.0}, vary="x", section=dy.Event("turn", v, "positive"), period_factor=2.0)


def pendulum(alpha: float = 1.0, beta: float = 2.0) -> dy.System:
    """x'' = -sin x + p (beta cos x - alpha) x': at p = 0 the librations with amplitude a (turning at x = +-a)
    have the period 4 K(sin^2(a/2)); one revolution changes H = v^2/2 - cos x by p times the integral of
    (beta cos x - alpha) v dx, and H = -cos a moves a by dH / sin a."""
    return dy.System("pendulum_melnikov", [x, v], [v, -hy.sin(x) + hy.par[0] * (hy.par[2] * hy.cos(x) - hy.par[1]) * v],
                     parameters={"p": 0.0, "alpha": alpha, "beta": beta})


def pendulum_drift(a: float, alpha: float = 1.0, beta: float = 2.0) -> float:
    def integrand(phi):  # x = a sin(phi): no square root vanishes at the turning points
        s = a * math.sin(phi)
        return (beta * math.cos(s) - alpha) * math.sqrt(2 * (math.cos(s) - math.cos(a))) * a * math.cos(phi)
    return 2.0 * quad(integrand, -0.5 * math.pi, 0.5 * math.pi, epsabs=1e-13, epsrel=1e-12)[0] / math.sin(a)


def test_the_pendulum_periods_and_drift_on_a_coarse_grid():
    """Three members far apart, as a user might pick them: the drift of the middle one is the quadrature's (the
    family's tangent comes from re-shot members, not from the grid)."""
    system = pendulum()
    amplitudes = [0.8, 1.0, 1.5, 2.0, 2.8]
    ds = symmetric_family(system, PENDULUM, (1.0, None), (0.0, 3.0), amplitudes=amplitudes)
    assert np.allclose(ds.period.values, [4 * ellipk(math.sin(a / 2) ** 2) for a in amplitudes], rtol=1e-10)
    assert ds.closure_error.values.max() < 1e-9
    drift = family_drift(system, ds, PENDULUM, "p")
    assert drift.drift_valid.values[1:-1].all(), drift.attrs["message"]
    for k in (1, 2, 3):
        # the amplitude is x at the start, x = +a: the turning point moves by the quadrature's da
        assert drift.drift.values[k] == pytest.approx(pendulum_drift(amplitudes[k]), rel=1e-4)


def test_a_section_the_start_lies_on_or_a_wrong_period_factor_is_refused():
    system = pendulum()
    wrong_direction = Shooting(fixed={"v": 0.0}, vary="x", section=dy.Event("turn", v, "negative"), period_factor=2.0)
    with pytest.raises(ParameterError, match="closes after 1/2"):  # met after a whole period: T counted twice
        symmetric_family(system, wrong_direction, (1.0, None), (0.0, 3.0), amplitudes=[1.0])
    too_large = Shooting(fixed={"v": 0.0}, vary="x", section=dy.Event("turn", v, "any"), period_factor=4.0)
    with pytest.raises(ParameterError, match="closes after 1/2"):
        symmetric_family(system, too_large, (1.0, None), (0.0, 3.0), amplitudes=[1.0])
    odd = Shooting(fixed={"v": 0.0}, vary="x", section=dy.Event("turn", v, "any"), period_factor=6.0)
    with pytest.raises(ParameterError, match="closes after 1/3"):
        symmetric_family(system, odd, (1.0, None), (0.0, 3.0), amplitudes=[1.0])
    with pytest.raises(ParameterError, match="amplitude -1 closes after 1/2"):  # every member is checked: the
        symmetric_family(system, PENDULUM, (1.0, None), (-3.0, 3.0), amplitudes=[1.0, -1.0])  # start x < 0 lies
        # on the section's plane moving up, so its first crossing comes a whole period later
    too_small = Shooting(fixed={"v": 0.0}, vary="x", section=dy.Event("turn", v, "positive"), period_factor=1.0)
    with pytest.raises(ParameterError, match="does not close"):
        symmetric_family(system, too_small, (1.0, None), (0.0, 3.0), amplitudes=[1.0])
    with pytest.raises(ParameterError, match="leave the bounds"):
        symmetric_family(system, PENDULUM, (1.0, None), (0.0, 1.0), amplitudes=[0.5, 2.0])
    ds = symmetric_family(system, PENDULUM, (1.0, None), (0.0, 3.0), amplitudes=[0.9, 1.0, 1.1])
    with pytest.raises(ParameterError, match="computed on"):
        family_drift(duffing_vdp(), ds, PENDULUM, "p")
    with pytest.raises(ParameterError, match="two different small"):
        family_drift(system, ds, PENDULUM, "p", values=1e-5)
    with pytest.raises(ParameterError, match="another Shooting"):
        family_drift(system, ds, Shooting(fixed={"v": 0.1}, vary="x", section=PENDULUM.section, period_factor=2.0),
                     "p")
    for bad in (dict(t_max=math.inf), dict(period_factor="2"), dict(section="turn"), dict(fixed=["v"])):
        with pytest.raises(ParameterError):
            Shooting(**{"fixed": {"v": 0.0}, "vary": "x", "section": PENDULUM.section, **bad}).check(system)
    for kwargs in (dict(bounds=(3.0,)), dict(bounds=("0", "3")), dict(amplitudes=["a"]), dict(pars={"q": 0.0}),
                   dict(direction=0)):
        call = {"bounds": (0.0, 3.0), "amplitudes": [1.0], **kwargs}
        with pytest.raises(ParameterError):
            symmetric_family(system, PENDULUM, (1.0, None), call.pop("bounds"), **call)


def test_the_drift_of_a_family_of_families_is_the_averaged_flow():
    """x'' + w(z)^2 x = p (mu - x^2) x', z' = p (x^2 - z), w = 1 + z/2: at p = 0 every (A, z) is a circle of
    amplitude A at frequency w(z), a two-parameter family (reversors (x, v, z) -> (x, -v, z) and (-x, v, z)).
    Averaging (x = A cos th) gives dz/dt = p (A^2/2 - z) and dA/dt = p [A/2 (mu - A^2/4) - A w'/(2 w) (A^2/2 - z)
    + w' A^3 / (8 w)]: van der Pol's term; the adiabatic invariant A^2 w of the oscillator retuned by the mean
    drift of z; and the retuning within a revolution, z - <z> = p A^2 sin(2 th) / (4 w), whose force
    -2 w w' (z - <z>) x adds p w' A^3 / (8 w). A drift along a coordinate that is not a
    fixed start value is refused."""
    xs, vs, zs = hy.make_vars("x", "v", "z")
    freq = 1.0 + 0.5 * zs
    system = dy.System("retuned_vdp", [xs, vs, zs], [vs, -freq**2 * xs + hy.par[0] * (hy.par[1] - xs**2) * vs,
                                                       hy.par[0] * (xs**2 - zs)], parameters={"p": 0.0, "mu": 1.0})
    mu = 1.0
    for amplitude, z in ((1.5, 0.4), (0.6, -0.3), (2.2, 1.0)):
        shooting = Shooting(fixed={"v": 0.0, "z": z}, vary="x", section=dy.Event("crossed", xs, "negative"),
                            period_factor=4.0)
        found = dy.drift_at(system, shooting, amplitude, None, {"p": 0.0, "mu": mu}, "p", along=("z",))
        w = 1.0 + 0.5 * z
        rate_a = (amplitude / 2 * (mu - amplitude**2 / 4) - amplitude * 0.5 / (2 * w) * (amplitude**2 / 2 - z)
                  + 0.5 * amplitude**3 / (8 * w))
        rate_z = amplitude**2 / 2 - z
        assert found["valid"] and found["check"] < 1e-2
        assert found["period"] == pytest.approx(2 * math.pi / w, rel=1e-10)
        assert found["drift"] / found["period"] == pytest.approx(rate_a, rel=1e-4, abs=1e-6)
        assert found["along_drift"]["z"] / found["period"] == pytest.approx(rate_z, rel=1e-4, abs=1e-6)
    with pytest.raises(ParameterError, match="along"):
        dy.drift_at(system, shooting, 1.0, None, {"p": 0.0, "mu": mu}, "p", along=("x",))
    unlabelled = dy.drift_at(system, shooting, 1.0, None, {"p": 0.0, "mu": mu}, "p")  # z not named: two 1s
    assert not unlabelled["valid"] and "along" in unlabelled["reason"]
    twice = Shooting(fixed=shooting.fixed, vary="x", section=shooting.section, period_factor=8.0)
    with pytest.raises(ParameterError, match="1/2"):  # a wrong period_factor is refused as in symmetric_family
        dy.drift_at(system, twice, 1.0, None, {"p": 0.0, "mu": mu}, "p", along=("z",))


def test_the_transverse_drift_is_the_averaged_growth_of_the_oscillation_about_the_orbit():
    """x'' + x = p (1 - x^2) x' carries y'' + nu^2 y = p (c - x^2) y': about each orbit y = 0 of amplitude A the
    y-oscillation is transverse, with multipliers exp(+-2 pi i nu) at p = 0, and averaging gives it the growth rate
    p (c - A^2/2) / 2; the amplitude's drift is van der Pol's, p A/2 (1 - A^2/4)."""
    xs, vs, ys, ws = hy.make_vars("x", "v", "y", "w")
    nu, c = 1.37, 0.5
    system = dy.System("vdp_carrying", [xs, vs, ys, ws],
                       [vs, -xs + hy.par[0] * (1.0 - xs**2) * vs, ws, -nu**2 * ys + hy.par[0] * (c - xs**2) * ws],
                       parameters={"p": 0.0})
    shooting = Shooting(fixed={"v": 0.0, "w": 0.0}, vary="x", free="y", condition="y",
                        section=dy.Event("crossed", xs, "negative"), period_factor=4.0)
    for amplitude in (0.8, 1.5):
        found = dy.drift_at(system, shooting, amplitude, 0.0, {"p": 0.0}, "p", transverse=True)
        period = 2 * math.pi
        assert found["valid"] and found["period"] == pytest.approx(period, rel=1e-10)
        assert found["drift"] / period == pytest.approx(amplitude / 2 * (1 - amplitude**2 / 4), rel=1e-4)
        growth = np.array(found["transverse_drift"]) / period
        assert growth == pytest.approx([(c - amplitude**2 / 2) / 2] * 2, abs=1e-7)  # measured: 4e-9

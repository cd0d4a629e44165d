"""Projection properties of the prox operators of the Moreau scheme (4.4)-(4.7), and the Coulomb-Contensou
prox against the exact law of a Hertzian circular contact (pure sliding, pure pivoting, combined, limits)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tippedisk_analysis.models import prox

coord = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)
radius = st.one_of(st.just(0.0), st.floats(min_value=1e-12, max_value=5.0))
POLY = prox.contensou_polygon()


def contensou(v, rad):
    return np.array(prox.prox_contensou(v[0], v[1], v[2], rad, POLY))


def in_contensou_set(v, rad, slack=1e-9):
    """Inside the polygonal ball: below the boundary eta_bar(xi_bar) of the meridian section."""
    if rad == 0:  # the ball of radius 0 is the origin
        return bool(np.all(np.abs(v) <= (1e-12 if slack else 0.0)))
    a, b = math.hypot(v[0], v[1]) / rad, abs(v[2]) / rad
    if a > 1 + slack:
        return False
    return b <= np.interp(min(a, 1.0), POLY[:, 0], POLY[:, 1]) + slack


PROJECTIONS = {
    "nonneg": (lambda v, rad: np.array([prox.prox_nonneg(v[0])]), 1,
               lambda v, rad: v[0] >= 0),
    "interval": (lambda v, rad: np.array([prox.prox_interval(v[0], rad)]), 1,
                 lambda v, rad: abs(v[0]) <= rad * (1 + 1e-12)),
    "disk": (lambda v, rad: np.array(prox.prox_disk(v[0], v[1], rad)), 2,
             lambda v, rad: math.hypot(v[0], v[1]) <= rad * (1 + 1e-12) + 1e-300),
    "contensou": (contensou, 3, in_contensou_set),
}


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(sorted(PROJECTIONS)), st.lists(coord, min_size=6, max_size=6), radius)
def test_projection_properties(name, values, rad):
    prox, dim, inside = PROJECTIONS[name]
    x, y = np.array(values[:dim]), np.array(values[3:3 + dim])
    px, py = prox(x, rad), prox(y, rad)
    assert inside(px, rad)  # lands in the set
    np.testing.assert_allclose(prox(px, rad), px, rtol=1e-12, atol=1e-12)  # idempotent
    assert np.linalg.norm(px - py) <= np.linalg.norm(x - y) * (1 + 1e-9) + 1e-12  # non-expansive
    if inside(x, rad, *(() if name != "contensou" else (0.0,))):
        # fixed on the set: moved at most by the 1e-12 rad slack that ``inside`` allows beyond the boundary
        # (none for the Contensou ball, tested without slack)
        slack = 0.0 if name == "contensou" else 1e-12 * rad
        np.testing.assert_allclose(px, x, rtol=0, atol=slack + 1e-14)


@settings(max_examples=200, deadline=None)
@given(st.lists(coord, min_size=3, max_size=3), st.floats(min_value=0.1, max_value=5.0))
def test_contensou_variational_inequality(values, rad):
    """(x - P x) . (y - P x) <= 0 for every y of the (convex) friction ball: P is the projection."""
    x = np.array(values)
    px = contensou(x, rad)
    angles = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    for xi, eta in POLY[::8]:
        for phi in angles:
            for sign in (1, -1):
                y = rad * np.array([xi * np.cos(phi), xi * np.sin(phi), sign * eta])
                assert np.dot(x - px, y - px) <= 1e-9 * rad * (1 + np.linalg.norm(x))


def test_contensou_ball_shape():
    """B_F of (2.27): pure sliding reaches mu P_N, pure pivoting 3 pi / 16 mu P_N; the section is convex."""
    assert POLY[0, 0] == 0 and math.isclose(POLY[0, 1], 3 * math.pi / 16, rel_tol=1e-12)
    assert POLY[-1, 0] == 1 and POLY[-1, 1] < 1e-6
    slopes = np.diff(POLY[:, 1]) / np.diff(POLY[:, 0])
    assert np.all(np.diff(slopes) <= 1e-12)  # concave boundary: convex set
    # the boundary follows the first branch of (2.27) at small xi_bar
    xi = 0.3
    x = xi / prox.XI_STAR
    eta = prox.ETA_STAR * math.sqrt(64 / 9 * (1 - 9 / 8 * x**2 + 243 / 1024 * x**4))
    assert abs(np.interp(xi, POLY[:, 0], POLY[:, 1]) - eta) < 1e-4
    # radial projection of pure sliding beyond the ball lands on mu P_N
    np.testing.assert_allclose(prox.prox_contensou(3.0, 4.0, 0.0, 2.0, POLY), (1.2, 1.6, 0.0), atol=1e-6)
    np.testing.assert_allclose(prox.prox_contensou(0.0, 0.0, -5.0, 2.0, POLY), (0, 0, -2 * 3 * math.pi / 16),
                               atol=1e-12)


# ----------------------------------------------------------------- Coulomb-Contensou: known answers
# Reference: the exact Coulomb-Contensou law of a circular contact of radius eps_i (Leine & Glocker
# 2003, the paper's [17]) with Hertzian pressure p ~ sqrt(1 - rho^2 / eps_i^2) (the "parabolic"
# distribution of (2.27): it alone gives pure pivoting 3 pi / 16, the coefficient 5 of branch 2 and
# (xi*, eta*) of (2.26) as the point |gamma_T| = gamma_tau). Units: mu lambda_N = 1, eps_i = 1,
# omega_IB = 1, so gamma_tau = eps_i omega_IB = 1 and s = |gamma_T| / gamma_tau.


def hertz_law(s: float, n: int = 300) -> tuple[float, float]:
    """(xi_bar, eta_bar) = (|lambda_T|, torque / eps_i) / (mu lambda_N) for sliding s: the resultant of
    mu p dA opposite to the local slip velocity, polar midpoint rule (error ~1e-5 at n = 300)."""
    rho = (np.arange(n) + 0.5) / n
    th = (np.arange(2 * n) + 0.5) * np.pi / n
    r, t = np.meshgrid(rho, th, indexing="ij")
    x, y = r * np.cos(t), r * np.sin(t)
    weight = 3.0 / (2.0 * np.pi) * np.sqrt(1.0 - r**2) * r * (1.0 / n) * (np.pi / n)
    vx, vy = s - y, x  # slip of the contact point (x, y): sliding s along x plus spin 1 about z
    norm = np.hypot(vx, vy)
    weight /= np.sum(weight)  # the rule's error in the total normal force cancels
    return float(np.sum(weight * vx / norm)), float(np.sum(weight * (x * vy - y * vx) / norm))


def contensou_law(s: float, phi: float = 0.7, rad: float = 2.0):
    """Impulse (P_T, P_tau) of the prox law for the velocity gamma_F = (s cos phi, s sin phi, 1),
    as the step loop uses it (P = prox(P - r gamma)) with r so large that the start does not matter."""
    big = 1e9 * rad
    return np.array(prox.prox_contensou(-big * s * math.cos(phi), -big * s * math.sin(phi), -big, rad, POLY))


def test_hertz_reference_law():
    """The reference reproduces the constants of (2.26)-(2.27) and the limits of the ball."""
    assert hertz_law(0.0) == pytest.approx((0.0, 3 * math.pi / 16), abs=1e-4)  # pure pivoting
    assert hertz_law(1.0) == pytest.approx((prox.XI_STAR, prox.ETA_STAR), abs=1e-4)  # (2.26)
    xi, eta = hertz_law(0.01)
    assert xi == pytest.approx(3 * math.pi / 8 * 0.01, rel=1e-3)  # pivot-dominated: branch 1
    xi, eta = hertz_law(20.0)
    assert eta == pytest.approx(1 / (5 * 20.0), rel=1e-2)  # slide-dominated: branch 2, xi^2 + 5 eta^2 ~ 1
    assert xi**2 + 5 * eta**2 - 75 / 7 * eta**4 == pytest.approx(1.0, abs=2e-5)


@pytest.mark.parametrize("s", [3e-3, 0.01, 0.03, 0.1, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 30.0, 100.0])
def test_contensou_prox_gives_the_exact_law(s):
    """Combined sliding and pivoting: the prox law matches the exact Hertz law within 5 % in both
    components, from pivot-dominated (s << 1) to slide-dominated (s >> 1) contact; the impulse
    opposes the velocity."""
    rad, phi = 2.0, 0.7
    p = contensou_law(s, phi, rad)
    xi, eta = hertz_law(s)
    assert math.hypot(p[0], p[1]) / rad == pytest.approx(xi, rel=0.05)
    assert -p[2] / rad == pytest.approx(eta, rel=0.05)
    np.testing.assert_allclose(p[:2] / math.hypot(p[0], p[1]), [-math.cos(phi), -math.sin(phi)], atol=1e-12)


def test_contensou_limits_of_the_ball():
    """Pure sliding: |P_T| = mu P_N, no torque; pure pivoting: 3 pi / 16 mu P_N, no sliding force;
    a little spin during sliding gives a small torque (eta_bar ~ gamma_tau / (5 |gamma_T|)), a
    little slip during pivoting a small force (xi_bar ~ 3 pi / 8 |gamma_T| / gamma_tau)."""
    rad = 2.0
    np.testing.assert_allclose(prox.prox_contensou(-3e9, 4e9, 0.0, rad, POLY), (-1.2, 1.6, 0.0), atol=1e-12)
    np.testing.assert_allclose(prox.prox_contensou(0.0, 0.0, 7e9, rad, POLY), (0, 0, rad * 3 * math.pi / 16),
                               atol=1e-12)
    for s in (10.0, 30.0, 300.0):
        assert -contensou_law(s, rad=rad)[2] / rad == pytest.approx(1 / (5 * s), rel=0.05)
    for s in (3e-3, 0.01, 0.03):
        p = contensou_law(s, rad=rad)
        assert math.hypot(p[0], p[1]) / rad == pytest.approx(3 * math.pi / 8 * s, rel=0.05)


@pytest.mark.parametrize("s", [0.01, 0.5, 1.0, 3.0, 50.0])
def test_contensou_law_does_not_depend_on_r(s):
    """The normal-cone law (2.24): P = prox(P - r gamma) holds for every r > 0 at the solution, so one
    r_T for the whole (T, tau) triple is a valid choice (r changes iteration counts, not results)."""
    rad, phi = 0.7, 2.1
    gamma = np.array([s * math.cos(phi), s * math.sin(phi), 1.0])
    p = contensou_law(s, phi, rad)
    for r in (1e-4, 0.1, 1e3):
        np.testing.assert_allclose(prox.prox_contensou(*(p - r * gamma), rad, POLY), p, atol=1e-12 * rad)


def test_contensou_symmetries():
    """Homogeneous in (argument, mu P_N), isotropic in the tangent plane, odd in lambda_tau."""
    x = np.array([0.3, -0.8, 0.5])
    p = np.array(prox.prox_contensou(*x, 0.4, POLY))
    np.testing.assert_allclose(prox.prox_contensou(*(7.0 * x), 2.8, POLY), 7.0 * p, rtol=1e-12, atol=1e-15)
    c, s = math.cos(1.1), math.sin(1.1)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    np.testing.assert_allclose(prox.prox_contensou(*(rot @ x), 0.4, POLY), rot @ p, rtol=1e-12, atol=1e-15)
    flip = np.array([1.0, 1.0, -1.0])
    np.testing.assert_allclose(prox.prox_contensou(*(flip * x), 0.4, POLY), flip * p, rtol=1e-12, atol=1e-15)


def test_contensou_polygon_vertices_lie_on_2_27():
    """Away from the switch xi* (where the hull bridges the gap between the truncated branches) every
    vertex lies on the printed branch of (2.27)."""
    k = 75.0 / 7.0
    for xi, eta in POLY:
        if xi < prox.XI_STAR - 0.1:
            x = xi / prox.XI_STAR
            assert 9 / 64 * (eta / prox.ETA_STAR) ** 2 + 9 / 8 * x**2 - 243 / 1024 * x**4 == pytest.approx(1, abs=1e-9)
        elif xi > prox.XI_STAR + 0.02:
            assert xi**2 + 5 * eta**2 - k * eta**4 == pytest.approx(1, abs=1e-9)

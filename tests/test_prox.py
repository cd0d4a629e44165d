"""Projection properties of the prox operators of the Moreau scheme (4.4)-(4.7)."""

import math

import numpy as np
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
        np.testing.assert_allclose(px, x, rtol=0, atol=1e-14)  # fixed on the set


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

import dataclasses
import math

import numpy as np
import pytest

from tippedisk_analysis import Disk, Friction, InitialState, ParameterError, Setup


def test_table2_from_geometry_of_table1():
    """Sect. 5: the drilled steel disk of Table 1 has the mass properties of Table 2."""
    disk = Disk.from_geometry(rho=7700, r=0.045, a=0.015, b=0.02, h=0.01)
    assert disk.e == pytest.approx(2.5e-3, rel=1e-12)  # e = b a^2 / (r^2 - a^2), exact here
    assert disk.m == pytest.approx(0.435, abs=0.0005)  # Table 2 prints three digits
    assert disk.A == pytest.approx(0.249e-3, abs=0.0005e-3)
    assert disk.B == pytest.approx(0.227e-3, abs=0.0005e-3)
    assert disk.C == pytest.approx(0.468e-3, abs=0.0005e-3)


def _drilled_disk_by_quadrature(rho, r, a, b, h, n=200):
    """m, e, A, B, C of the drilled disk by direct integration over the material, in polar coordinates
    about G (x towards S, the hole centred at (-b, 0)), independent of the cylinder-minus-hole formulas.

    A point at radius s and angle phi lies in the hole iff s^2 + 2 b s cos(phi) + b^2 <= a^2, i.e.
    cos(phi) <= c(s) = (a^2 - b^2 - s^2) / (2 b s): the material of the ring s is |phi| < psi = arccos(c),
    whose angular integrals of 1, cos, cos^2, sin^2 are closed form. The radial integrals use
    Gauss-Legendre on pieces split where the ring meets the hole (s = |b - a|, b + a); the sqrt-type
    end points there limit the accuracy to about 1e-7 with 200 nodes. The thickness enters through
    the integral of z^2 over [-h/2, h/2], h^3/12.
    """
    breaks = sorted({0.0, r, *(x for x in (abs(b - a), b + a) if 0 < x < r)})
    nodes, weights = np.polynomial.legendre.leggauss(n)
    area = first = xx = yy = 0.0
    for lo, hi in zip(breaks[:-1], breaks[1:]):
        s = 0.5 * (hi - lo) * nodes + 0.5 * (hi + lo)
        w = 0.5 * (hi - lo) * weights
        psi = np.arccos(np.clip((a * a - b * b - s * s) / (2 * b * s), -1.0, 1.0))
        sc = np.sin(psi) * np.cos(psi)
        area += np.sum(w * 2 * psi * s)
        first += np.sum(w * 2 * np.sin(psi) * s**2)  # integral of x dA
        xx += np.sum(w * (psi + sc) * s**3)
        yy += np.sum(w * (psi - sc) * s**3)
    zz = h**3 / 12 * area
    return {"m": rho * h * area, "e": first / area, "A": rho * (h * yy + zz), "B": rho * (h * xx + zz),
            "C": rho * h * (xx + yy)}


@pytest.mark.parametrize("geometry", [
    {"rho": 2700.0, "r": 0.06, "a": 0.02, "b": 0.03, "h": 0.02},  # thick aluminium, hole half way out
    {"rho": 7700.0, "r": 0.045, "a": 0.02, "b": 0.025, "h": 0.005},  # hole touching the rim
    {"rho": 1200.0, "r": 0.05, "a": 0.02, "b": 0.008, "h": 0.03},  # hole covering G (b < a)
    {"rho": 7700.0, "r": 0.045, "a": 0.015, "b": 0.02, "h": 0.01},  # Table 1
], ids=["thick", "at-rim", "over-centre", "table1"])
def test_from_geometry_matches_integration_over_the_drilled_disk(geometry):
    """Sect. 5 (5.1)-(5.2) away from Table 1: mass, eccentricity (S on +e_x^B, away from the hole)
    and the principal inertia about G against quadrature over the material."""
    disk = Disk.from_geometry(**geometry)
    reference = _drilled_disk_by_quadrature(**geometry)
    for name, value in reference.items():
        assert getattr(disk, name) == pytest.approx(value, rel=1e-6), name
    assert disk.r == geometry["r"]


def test_default_disk_is_table2():
    assert Disk() == Disk(m=0.435, e=2.5e-3, r=0.045, A=0.249e-3, B=0.227e-3, C=0.468e-3)


def test_inertia_about_S_uses_parallel_axes():
    d = Disk()
    assert d.inertia_S == pytest.approx({"A_S": d.A, "B_S": d.B - d.m * d.e**2, "C_S": d.C - d.m * d.e**2})


@pytest.mark.parametrize(
    "changes, fragment",
    [
        ({"r": -0.045}, "radius"),
        ({"e": 0.045}, "not smaller than the radius"),
        ({"e": 0.05}, "not smaller than the radius"),
        ({"e": -1e-3}, "must not be negative"),
        ({"m": 0.0}, "mass"),
        ({"B": 1e-9}, "inertia"),
        ({"A": float("nan")}, "not finite"),
    ],
)
def test_disk_rejects_bad_values(changes, fragment):
    with pytest.raises(ParameterError, match=fragment):
        dataclasses.replace(Disk(), **changes)


@pytest.mark.parametrize(
    "changes, fragment",
    [({"eps": 0.0}, "eps"), ({"eps": -0.1}, "eps"), ({"mu": -0.3}, "mu"), ({"e_N": 1.5}, "e_N")],
)
def test_friction_rejects_bad_values(changes, fragment):
    with pytest.raises(ParameterError, match=fragment):
        dataclasses.replace(Friction(), **changes)


def test_geometry_rejects_hole_larger_than_disk():
    with pytest.raises(ParameterError, match="hole radius"):
        Disk.from_geometry(a=0.05)


def test_initial_state_defaults_are_table3():
    s = InitialState()
    assert (s.alpha, s.beta, s.gamma) == (0.0, 0.5 * math.pi, -0.5 * math.pi + 0.1)
    assert (s.alpha_dot, s.beta_dot) == (40.0, 0.0)
    assert s.gamma_dot_value == pytest.approx(-40.0 * math.cos(0.5 * math.pi))


@pytest.mark.parametrize("beta", [0.0, math.pi, -0.2])
def test_initial_state_rejects_flat_disk(beta):
    with pytest.raises(ParameterError, match="beta"):
        InitialState(beta=beta)


def test_setup_rejects_nonpositive_gravity():
    with pytest.raises(ParameterError, match="gravity"):
        Setup(gravity=0.0)

import dataclasses
import math

import numpy as np
import pytest

from tippedisk_analysis import Disk, Friction, InitialState, ParameterError, Setup
from tippedisk_analysis.parameters import DiskGeometry


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


@pytest.mark.parametrize("build, fragment", [
    (lambda: Friction(mu="0.3"), "Friction.mu = '0.3' is a str; give a number"),
    (lambda: Disk(m=None), "Disk.m = None is a NoneType"),
    (lambda: InitialState(alpha_dot=True), "InitialState.alpha_dot = True is a bool"),
    (lambda: Setup(disk={"m": 0.4}), "Setup.disk = {'m': 0.4} must be a Disk"),
    (lambda: Setup(gravity="9.81"), "gravity = '9.81' m/s^2 must be a positive number"),
])
def test_wrong_types_are_parameter_errors_naming_the_fix(build, fragment):
    with pytest.raises(ParameterError) as info:
        build()
    assert fragment in str(info.value) and "--" not in str(info.value)


def test_api_fronts_refuse_wrong_types_in_api_words(tmp_path):
    import tippedisk_analysis as td
    from tippedisk_analysis.analysis.outcome_map import outcome_map

    with pytest.raises(ParameterError, match=r"setup must be a Setup, not dict; give e.g. Setup\("):
        td.simulate(setup={"disk": {}})
    with pytest.raises(ParameterError, match="initial must be an InitialState"):
        td.simulate(initial={"alpha_dot": 40.0})
    with pytest.raises(td.DatasetError, match="save needs an xarray.Dataset"):
        td.save({"a": 1}, tmp_path / "a.nc")
    with pytest.raises(ParameterError, match="cannot sweep 'zeta'") as info:
        outcome_map({"omega": (10, 80, 4), "zeta": (0, 1, 2)})
    assert "--" not in str(info.value)
    with pytest.raises(ParameterError, match=r"ranges=\{'omega'") as info:
        outcome_map({"omega": (10, 80, 4)})
    assert "--" not in str(info.value) and info.value.cli_message().endswith("give --omega and --eps")
    assert list(tmp_path.iterdir()) == []


def test_the_geometry_travels_with_the_disk():
    disk = Disk.from_geometry()
    assert disk.geometry == DiskGeometry() and disk.source == "geometry" and Disk().source == "values"
    assert Disk(**dataclasses.asdict(disk)) == disk  # a stored configuration rebuilds it
    with pytest.raises(ParameterError, match="does not match its geometry"):
        dataclasses.replace(disk, e=3e-3)  # would silently contradict the hole


def test_eccentricity_of_a_drilled_disk_moves_the_hole():
    disk = Disk.from_geometry()
    moved = disk.with_eccentricity(3e-3)
    g = moved.geometry
    assert (g.rho, g.r, g.a, g.h) == (7700.0, 0.045, 0.015, 0.01)
    assert g.b == pytest.approx(3e-3 * (0.045**2 - 0.015**2) / 0.015**2)  # b = e (r^2 - a^2) / a^2
    assert moved.e == pytest.approx(3e-3) and moved == Disk.from_geometry(b=g.b)
    assert moved.m == pytest.approx(disk.m) and moved.A == pytest.approx(disk.A)  # the hole only moved
    assert moved.B < disk.B and moved.C < disk.C
    with pytest.raises(ParameterError, match="hole offset"):
        disk.with_eccentricity(0.01)  # b = 0.08 m: the hole would leave the disk


def test_eccentricity_of_a_disk_given_by_values_keeps_the_inertia_about_G():
    moved = Disk().with_eccentricity(3e-3)
    assert (moved.m, moved.A, moved.B, moved.C, moved.e) == (0.435, 0.249e-3, 0.227e-3, 0.468e-3, 3e-3)
    assert "inertia A, B, C about G held fixed" in Disk().eccentricity_rule
    assert "hole offset b moved" in Disk.from_geometry().eccentricity_rule


def test_mass_scales_the_inertia_consistently():
    heavy = Disk().with_mass(0.87)
    assert heavy.A == pytest.approx(2 * 0.249e-3) and heavy.C == pytest.approx(2 * 0.468e-3)
    for name, value in heavy.inertia_S.items():  # about S as well: the same shape, twice the density
        assert value == pytest.approx(2 * Disk().inertia_S[name])
    drilled = Disk.from_geometry()
    denser = drilled.with_mass(0.87)  # a drilled disk changes its density
    assert denser.m == pytest.approx(0.87) and denser.geometry.rho == pytest.approx(7700.0 * 0.87 / drilled.m)
    assert denser.e == pytest.approx(drilled.e)


def test_eccentricity_columns_match_single_disks():
    from tippedisk_analysis.parameters import eccentricity_columns

    disk = Disk.from_geometry()
    columns = eccentricity_columns(disk, [2e-3, 3e-3])
    for k, e in enumerate((2e-3, 3e-3)):
        single = disk.with_eccentricity(e)
        assert {name: columns[name][k] for name in columns} == pytest.approx(
            {name: getattr(single, name) for name in columns})


def test_stability_map_over_e_equals_maps_of_single_drilled_disks():
    from tippedisk_analysis.analysis import maps

    setup = Setup(disk=Disk.from_geometry())
    swept = maps.stability_map([30.0, 40.0], [0.1], e=[2e-3, 3e-3], setup=setup, critical=False, progress=False)
    assert "hole offset b moved" in swept["e"].attrs["comment"]
    for k, e in enumerate((2e-3, 3e-3)):
        single = maps.stability_map([30.0, 40.0], [0.1], setup=Setup(disk=setup.disk.with_eccentricity(e)),
                                    critical=False, progress=False)
        np.testing.assert_array_equal(swept["max_real_eig"].isel(e=k).values,
                                      single["max_real_eig"].values)

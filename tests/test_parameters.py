import dataclasses
import math

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

import numpy as np
import pytest

from tippedisk_analysis import Disk, InitialState
from tippedisk_analysis import kinematics as kin

rng = np.random.default_rng(7)
ANGLES = [(rng.uniform(-np.pi, np.pi), rng.uniform(0.1, np.pi - 0.1), rng.uniform(-np.pi, np.pi)) for _ in range(20)]


def _skew_inverse(S):
    return np.array([S[2, 1], S[0, 2], S[1, 0]])


@pytest.mark.parametrize("angles", ANGLES)
def test_rotation_is_orthogonal_and_matches_elemental_rotations(angles):
    a, b, g = angles
    R = kin.rotation_from_euler(a, b, g)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    A_IR = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])  # (3.1)
    A_RG = np.array([[1, 0, 0], [0, cb, -sb], [0, sb, cb]])
    A_GB = np.array([[cg, -sg, 0], [sg, cg, 0], [0, 0, 1]])
    np.testing.assert_allclose(R, A_IR @ A_RG @ A_GB, atol=1e-15)


@pytest.mark.parametrize("angles", ANGLES)
def test_quaternion_and_euler_round_trips(angles):
    R = kin.rotation_from_euler(*angles)
    p = kin.quaternion_from_rotation(R)
    assert np.linalg.norm(p) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(kin.rotation_from_quaternion(p), R, atol=1e-15)
    np.testing.assert_allclose(kin.euler_from_rotation(R), angles, atol=1e-12)


@pytest.mark.parametrize("angles", ANGLES[:5])
def test_omega_matches_definition_2_3(angles):
    """Omega_B = j^-1(R^T R_dot), with R_dot by central differences."""
    phi = np.array(angles)
    rates = rng.normal(size=3) * 5
    h = 1e-6
    R_dot = (kin.rotation_from_euler(*(phi + h * rates)) - kin.rotation_from_euler(*(phi - h * rates))) / (2 * h)
    expected = _skew_inverse(kin.rotation_from_euler(*phi).T @ R_dot)
    omega = kin.omega_from_euler_rates(phi[1], phi[2], rates)
    np.testing.assert_allclose(omega, expected, atol=1e-8)
    np.testing.assert_allclose(kin.euler_rates_from_omega(phi[1], phi[2], omega), rates, atol=1e-12)


@pytest.mark.parametrize("angles", ANGLES[:5])
def test_quaternion_rates_match_3_44(angles):
    R = kin.rotation_from_euler(*angles)
    p = kin.quaternion_from_rotation(R)
    omega = rng.normal(size=3)
    p_dot = np.array(kin.quaternion_rate_entries(*p, *omega))
    h = 1e-6
    R_dot = (kin.rotation_from_quaternion(p + h * p_dot) - kin.rotation_from_quaternion(p - h * p_dot)) / (2 * h)
    np.testing.assert_allclose(_skew_inverse(R.T @ R_dot), omega, atol=1e-8)


@pytest.mark.parametrize("angles", ANGLES[:8])
def test_contact_points_on_rim_and_C1_lowest(angles):
    r = 0.045
    R = kin.rotation_from_euler(*angles)
    offsets = kin.contact_point_offsets(R, r)
    ez_B = R[:, 2]
    np.testing.assert_allclose(np.linalg.norm(offsets, axis=1), r, rtol=1e-14)
    np.testing.assert_allclose(offsets @ ez_B, 0.0, atol=1e-15)  # in the disk plane
    cosines = offsets @ offsets.T / r**2
    np.testing.assert_allclose(cosines[np.triu_indices(3, 1)], -0.5, atol=1e-14)  # 120 degrees apart
    rim = np.array([R @ [r * np.cos(t), r * np.sin(t), 0.0] for t in np.linspace(0, 2 * np.pi, 3601)])
    assert offsets[0, 2] <= rim[:, 2].min() + 1e-12
    assert offsets[0, 2] == pytest.approx(-r * np.sin(angles[1]), abs=1e-15)  # g_N1 of (2.12)


def test_contact_points_undefined_for_horizontal_disk():
    with pytest.raises(ValueError, match="horizontal"):
        kin.contact_point_offsets(np.eye(3), 0.045)


def test_rest_contact_state_closes_contact_without_slip():
    """(6.2): the material point at C1 is at rest, so gamma_N1 (3.26) and gamma_T1 (3.27) vanish."""
    disk = Disk()
    for init in (InitialState(), InitialState(alpha=0.3, beta=1.2, gamma=0.4, alpha_dot=-50, beta_dot=2, gamma_dot=3)):
        rest = kin.rest_contact_state(disk.r, init.euler, init.euler_rates)
        a, b, g = init.euler
        ad, bd, gd = init.euler_rates
        assert rest["z"] == pytest.approx(disk.r * np.sin(b))
        xd, yd, zd = rest["v_G"]
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        assert zd - disk.r * bd * cb == pytest.approx(0.0, abs=1e-15)  # (3.26)
        assert xd + disk.r * (ad * ca * cb - bd * sa * sb + gd * ca) == pytest.approx(0.0, abs=1e-14)  # (3.27)
        assert yd + disk.r * (ad * sa * cb + bd * ca * sb + gd * sa) == pytest.approx(0.0, abs=1e-14)

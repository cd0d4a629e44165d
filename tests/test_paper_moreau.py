"""The paper's qualitative Moreau results of Sect. 6 (Table 3 start, dt = 1e-5 s as in the paper, 5 s).

* Sect. 6.1, Fig. 7-8 (set-valued Coulomb, Models 1/2): gamma rises and oscillates with a large
  amplitude about the inverted orientation, while z_S "oscillates aperiodically around 0.044 m
  (arithmetic mean for t in [1 s, 5 s], Euler angles) instead of reaching the fully inverted height
  r + e"; the gap g_N1 of Model 1 chatters between 0 and about -2e-9 m.
* Sect. 6.3, Fig. 11 (smooth Coulomb, Models 5/6): the disk inverts within about 0.5 s, the
  oscillation about gamma = pi/2 is damped, and z_S grows to the inverted height r + e; the total
  energy drops fast during the inversion and slowly afterwards.

* Sect. 6.2, Figs. 9/10 (Coulomb-Contensou, Models 3/4): after the inversion a damped oscillation about
  gamma = pi/2 and z_S -> r + e; the normalised quaternion gap saturates near -1.36e-5 m. The law
  (2.24)-(2.27) as stated does not give this for any contact radius (docs/contensou_investigation.md):
  that test is a strict xfail. The diagnostic variant without pivoting torque (contensou_torque_share = 0,
  contact radius 3 pi eps / (8 Omega) = 2.9 mm) does, and is tested as such.

Each run takes well under a second (numba, 500,000 steps).
"""

import math

import numpy as np
import pytest

from tippedisk_analysis import Disk, Friction, Setup, simulate

DISK = Disk()
R_PLUS_E = DISK.r + DISK.e  # fully inverted height of S [m]


@pytest.fixture(scope="module")
def runs():
    cache = {}

    def get(name, **options):
        key = (name, tuple(sorted(options.items())))
        if key not in cache:
            ds = simulate(name, 5.0, dt=1e-5, **options)
            assert ds.attrs["status"] == "completed" and ds.attrs["convergence_failures"] == 0
            cache[key] = ds
        return cache[key]

    return get


def test_model1_does_not_invert_to_r_plus_e(runs):
    """Sect. 6.1: mean z_S on [1, 5] s in [0.043, 0.045] m; S never gets near r + e = 0.0475 m."""
    ds = runs("m1")
    late = ds.sel(time=slice(1.0, 5.0))
    assert 0.043 <= float(late.z_S.mean()) <= 0.045
    assert float(ds.z_S.max()) < DISK.r < R_PLUS_E - 2e-3  # not even S level with G's upright height
    # ... although gamma did rise: a large oscillation about the inverted orientation, beta moves less
    gamma = late.gamma
    assert float(gamma.mean()) == pytest.approx(math.pi / 2, abs=0.2)
    amplitude = float(gamma.max() - gamma.min())
    assert amplitude > 2.0
    assert float(abs(late.beta - math.pi / 2).max()) < 0.25 * amplitude
    # Fig. 8: the gap chatters between 0 and about -2e-9 m (no lift-off, no drift)
    assert -5e-9 < float(ds.g_N1.min()) and float(ds.g_N1.max()) < 1e-10


@pytest.mark.parametrize("normalize", [True, False])
def test_model2_does_not_invert_to_r_plus_e(runs, normalize):
    """Sect. 6.1: the quaternion Model 2 behaves like Model 1; its gap drifts downwards (Fig. 8: "the
    height of the contact point C1 decreases monotonically", no gap correction), with or without the
    quaternion normalisation of Sect. 3.2 (which removes the larger, |p|-driven part of the drift)."""
    ds = runs("m2", normalize_quaternion=normalize)
    assert float(ds.z_S.max()) < DISK.r
    assert 0.043 <= float(ds.z_S.sel(time=slice(1.0, 5.0)).mean()) <= 0.045
    drift = [float(ds.g_N1.sel(time=slice(t, t + 1.0)).mean()) for t in (0.0, 2.0, 4.0)]
    assert drift[0] > drift[1] > drift[2] and drift[2] < (-5e-5 if normalize else -3e-4)


@pytest.mark.parametrize("name, options", [("m5", {}), ("m6", {})])
def test_smooth_coulomb_models_invert_to_r_plus_e(runs, name, options):
    """Sect. 6.3: z_S exceeds 0.047 m within the inversion (< 1 s) and stays near r + e = 0.0475 m."""
    ds = runs(name, **options)
    above = ds.z_S.values > 0.047
    assert above.any()
    t_up = float(ds.time[np.argmax(above)])
    assert 0.3 < t_up < 1.0
    late = ds.sel(time=slice(4.0, 5.0))
    assert float(late.z_S.min()) > 0.047
    assert float(ds.z_S.max()) < R_PLUS_E + 1e-5  # S cannot rise above r + e (up to the tiny penetration)
    # the oscillation about gamma = pi/2 is damped: smaller late than early
    assert float(abs(late.gamma - math.pi / 2).max()) < 0.5 * float(
        abs(ds.gamma.sel(time=slice(1.0, 2.0)) - math.pi / 2).max())
    assert float(ds.z_S.sel(time=slice(0.0, 0.3)).min()) < float(ds.z_S[0])  # z_S "drops slightly" first
    E = ds.E_tot
    E_06 = float(E.sel(time=0.6, method="nearest"))
    fast = (float(E[0]) - E_06) / 0.6  # mean dissipation rates [W]
    slow = (E_06 - float(E[-1])) / 4.4
    assert fast > 5 * slow > 0  # energy drops fast during the inversion, slowly afterwards


def test_set_valued_and_smooth_coulomb_differ_as_in_the_paper(runs):
    """The contrast of Sect. 6.1 vs 6.3 in one number: late mean z_S is 3 mm higher with smooth Coulomb."""
    z1 = float(runs("m1").z_S.sel(time=slice(1.0, 5.0)).mean())
    z5 = float(runs("m5").z_S.sel(time=slice(1.0, 5.0)).mean())
    assert z5 - z1 > 2.5e-3


# ------------------------------------------------------------ Sect. 6.2, Figs. 9/10: Coulomb-Contensou

VARIANT_RADIUS = 3 * math.pi * 0.1 / (8 * 40.0)  # eps_i = 3 pi eps / (8 Omega): (2.29) as the Contensou limit
VARIANT = {"setup": Setup(friction=Friction(contact_radius=VARIANT_RADIUS)), "contensou_torque_share": 0.0}


def _amplitude(ds, t0, t1):
    g = ds.gamma.sel(time=slice(t0, t1)).values
    return 0.5 * float(g.max() - g.min())


@pytest.mark.xfail(strict=True, reason="the Coulomb-Contensou law (2.24)-(2.27) as stated gives no damped oscillation "
                                       "about pi/2 for any contact radius (0.1-10 mm scanned; amplitude ratio 0.99 at "
                                       "the default 1 mm): docs/contensou_investigation.md")
def test_model3_fig9_damped_inversion_with_the_law_as_stated(runs):
    """Issue 11: Model 3 at the paper's settings ends the 5-s run with the gamma oscillation amplitude on
    [4, 5] s below half its amplitude on [1, 2] s."""
    ds = runs("m3")
    assert _amplitude(ds, 4, 5) < 0.5 * _amplitude(ds, 1, 2)


def test_model3_fig9_damped_inversion_in_the_variant_without_pivoting_torque(runs):
    """The same criterion holds when the ball couples spin and sliding but no pivoting torque acts (ratio 0.19),
    with z_S -> r + e; the same radius with the torque (the law) rolls the disk away instead."""
    ds = runs("m3", **VARIANT)
    assert _amplitude(ds, 4, 5) < 0.5 * _amplitude(ds, 1, 2)
    assert abs(float(ds.gamma.sel(time=slice(4.0, 5.0)).mean()) - math.pi / 2) < 0.1
    assert float(ds.z_S[-1]) > R_PLUS_E - 5e-4
    with_torque = runs("m3", setup=VARIANT["setup"])
    assert float(with_torque.z_S[-1]) < DISK.r - DISK.e  # rolled away: S far below its start


def test_model4_fig10_gap_saturates_in_the_variant(runs):
    """Fig. 10: the gap of C1 of the (normalised) quaternion Model 4 saturates near -1.36e-5 m: -1.18e-5 m in
    the variant; the law as stated keeps drifting (-3.0e-5 m at 2.5 s, -4.8e-5 m at 5 s)."""
    ds = runs("m4", **VARIANT)
    g25, g5 = float(ds.g_N1.sel(time=2.5)), float(ds.g_N1[-1])
    assert -1.6e-5 < g5 < -1.0e-5 and abs(g5 - g25) < 0.1 * abs(g5)
    law = runs("m4")
    assert float(law.g_N1[-1]) < 1.2 * float(law.g_N1.sel(time=2.5)) < -2e-5

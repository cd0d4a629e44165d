"""Numbers of docs/contensou_investigation.md (Models 3/4, Coulomb-Contensou; contact radius of Models 7-10),
from the package.

    PYTHONPATH=src python docs/contensou_investigation.py        (about 1 min on one core)

Table 3 start, Sect. 6 parameters, dt = 1e-5 s, tol = 1e-8 unless stated. amp[a,b] is half the
range of gamma on [a, b] s; Fig. 9's criterion is amp[4,5] < 0.5 amp[1,2].
"""

import dataclasses
import math

import numpy as np

import tippedisk_analysis as td


VARIANT = 3 * math.pi * 0.1 / (8 * 40.0)  # 3 pi eps / (8 Omega) = 2.945 mm (Sect. 5 of the .md)


def simulate(model, t_end, contact_radius=1e-3, **options):
    friction = dataclasses.replace(td.Friction(), contact_radius=contact_radius)
    return td.simulate(model, t_end, setup=td.Setup(friction=friction), **options)


def amplitude(ds, t0, t1):
    g = ds.gamma.values[(ds.time.values >= t0) & (ds.time.values <= t1)]
    return 0.5 * float(g.max() - g.min()) if g.size else float("nan")


def line(ds):
    t = ds.time.values
    late = t >= min(4.0, t[-1])
    a12, a45 = amplitude(ds, 1, 2), amplitude(ds, 4, 5)
    k = min(np.searchsorted(t, 5.0), t.size - 1)
    return (f"amp[1,2] {a12:.3f} amp[4,5] {a45:.3f} ratio {a45 / a12:.2f}  gamma[4,5] "
            f"[{ds.gamma.values[late].min():.2f}, {ds.gamma.values[late].max():.2f}]  z_S(5 s) "
            f"{float(ds.z_S[k]) * 1e3:.2f} mm  E(5 s) {float(ds.E_tot[k]):.4f} J  "
            f"alpha_dot(5 s) {float(ds.alpha_dot[k]):.1f}  failures {ds.attrs['convergence_failures']}"
            + ("" if ds.attrs["status"] == "completed"
               else f"  [{ds.attrs['status']} at {t[-1]:.2f} s; values at the end]"))


def leave_and_fall(ds):
    t, g, z = ds.time.values, ds.gamma.values, ds.z_S.values
    out = np.nonzero((t > 1.0) & (np.abs(g - np.pi / 2) > 1.5))[0]
    down = np.nonzero(z < 0.02)[0]
    return (f"|gamma - pi/2| > 1.5 first at {t[out[0]]:.2f} s" if out.size else "|gamma - pi/2| <= 1.5") + \
        (f", z_S < 20 mm at {t[down[0]]:.2f} s" if down.size else ", z_S >= 20 mm")


def main():
    print("A. Model 3, the law (2.24)-(2.27), contact radius scan")
    for rc in (1e-4, 3e-4, 5e-4, 7e-4, 1e-3, 1.2e-3, 1.5e-3, 2e-3, 2.5e-3, 3e-3, 5e-3, 1e-2):
        print(f"  {rc * 1e3:5.1f} mm: {line(simulate('m3', 5.0, rc))}", flush=True)
    print("B. Model 3 at 1 mm: step size, tolerance, prox gains")
    for opt in ({"dt": 5e-6}, {"dt": 2e-5}, {"tol": 1e-6}, {"tol": 1e-12}, {"r_T": 0.02}, {"r_T": 0.15},
                {"r_tau": 0.01}):
        ds = simulate("m3", 5.0, **opt)
        print(f"  {opt}: {line(ds)}  iterations max {ds.prox_iterations_max.values.max():.0f}", flush=True)
    print("C. Model 3 at 2.5 mm, share of the pivoting torque applied (contensou_torque_share)")
    for share in (0.0, 0.04, 0.12, 0.4, 1.0):
        print(f"  {share:4.2f}: {line(simulate('m3', 5.0, 2.5e-3, contensou_torque_share=share))}", flush=True)
    print("D. Model 3 without the pivoting torque, contact radius scan")
    for rc in (5e-4, 1e-3, 1.5e-3, 2e-3, 2.5e-3, VARIANT, 3e-3, 5e-3):
        print(f"  {rc * 1e3:5.1f} mm: {line(simulate('m3', 5.0, rc, contensou_torque_share=0.0))}", flush=True)
    print("E. Model 4, normalised quaternions, 25 s")
    for rc, share in ((1e-3, 1.0), (5e-4, 1.0), (VARIANT, 1.0), (2.5e-3, 0.0), (2.5e-3, 0.04), (VARIANT, 0.0),
                      (VARIANT, 0.0345)):
        ds = simulate("m4", 25.0, rc, contensou_torque_share=share)
        t, g = ds.time.values, ds.g_N1.values
        print(f"  {rc * 1e3:.1f} mm, share {share}: g_N1(2.5 s) {g[np.searchsorted(t, 2.5)]:.3g} m, g_N1(5 s) "
              f"{g[np.searchsorted(t, 5.0)]:.3g} m; {leave_and_fall(ds)}", flush=True)
    print(f"  Model 6 (smooth Coulomb): {leave_and_fall(td.simulate('m6', 25.0))}")
    print("G. Models 7-10 (dry pivoting eps_i mu_tau lambda_N) over the contact radius; 25 s for Models 8, 10")
    for model in ("m7", "m8", "m9", "m10"):
        for rc in (3e-4, 1e-3, 2.5e-3, VARIANT):
            T = 25.0 if model in ("m8", "m10") else 5.0
            ds = simulate(model, T, rc, store_every=100)
            amps = " ".join(f"{amplitude(ds, a, a + 1):.3f}" for a in (1, 4, 24) if a + 1 <= T)
            print(f"  {model} {rc * 1e3:.2f} mm: amp[1,2] amp[4,5] (amp[24,25]) {amps}  E(5 s) "
                  f"{float(ds.E_tot.sel(time=5.0, method='nearest')):.4f} J; {leave_and_fall(ds)}", flush=True)
    print("F. Quaternion normalisation")
    ode = td.simulate("ode-quaternion", 1.0, dt_output=1e-3)
    for norm in (False, True):
        m6 = td.simulate("m6", 1.0, normalize_quaternion=norm)
        diff = np.abs(np.interp(ode.time.values, m6.time.values, m6.gamma.values) - ode.gamma.values).max()
        print(f"  Model 6 vs ODE Model 2 on [0, 1] s, normalised={norm}: max |d gamma| = {diff:.3g} rad")
    for model in ("m2", "m4", "m6"):
        for norm in (True, False):
            g = td.simulate(model, 5.0, normalize_quaternion=norm).g_N1.values
            print(f"  {model} normalised={norm}: g_N1(5 s) = {g[-1]:.3g} m")


if __name__ == "__main__":
    main()

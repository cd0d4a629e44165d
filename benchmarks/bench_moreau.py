"""Moreau time stepping: steps per second of Models 1-10 (numba, warm) vs a plain numpy step.

Run: ``.venv/bin/python benchmarks/bench_moreau.py [--steps 200000] [--numpy-steps 2000] [--quick]``.
Not part of the test suite. The numpy baseline below implements the same step (same
velocity space, same force laws and prox operators, Jacobi sweep) with numpy arrays and
:mod:`tippedisk_analysis.kinematics`; its first steps are checked against the numba loop.
Targets (issue 3): Model 5 >= 1e6 steps/s, every model >= 1e5 steps/s, >= 50x numpy;
the wall time of the 5-s Table 3 run is reported as well.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from tippedisk_analysis import defaults
from tippedisk_analysis import kinematics as kin
from tippedisk_analysis.defaults import CONTOUR_REGULARISATION
from tippedisk_analysis.models import prox
from tippedisk_analysis.parameters import InitialState, Setup
from tippedisk_analysis.solvers.moreau import driver, layout
from tippedisk_analysis.solvers.moreau import models as mo

prox_disk = prox.prox_disk.py_func
prox_interval = prox.prox_interval.py_func
prox_contensou = prox.prox_contensou.py_func


def numpy_step(model, setup, q, u, exg, Pw, dt=1e-5, tol=1e-8, max_iter=1000, rN=0.1, rT=0.1, rtau=0.1, rR=1e-4,
               poly=None):
    """One Moreau step (4.1)-(4.7) in plain numpy; returns (q_E, u_E, exg, Pw)."""
    d, f = setup.disk, setup.friction
    theta = np.array(list(d.inertia_S.values()))
    minv = np.concatenate([np.full(3, 1 / d.m), 1 / theta])
    euler = model.parameterization == mo.EULER

    def advance(q, u, h):
        out = q.copy()
        out[:3] += h * u[:3]
        if euler:
            out[3:6] += h * u[3:6]
        else:
            out[3:7] += h * np.array(kin.quaternion_rate_entries(*q[3:7], *u[3:6]))
        return out

    qM = advance(q, u, 0.5 * dt)
    R = kin.rotation_from_euler(*qM[3:6]) if euler else kin.rotation_from_quaternion(qM[3:7])
    if euler:
        w = kin.omega_from_euler_rates(qM[4], qM[5], u[3:6])
        b, g_, (ad, bd, gd) = qM[4], qM[5], u[3:6]
        a = np.array([ad * (np.cos(b) * bd * np.sin(g_) + np.sin(b) * np.cos(g_) * gd) - bd * np.sin(g_) * gd,
                      ad * (np.cos(b) * bd * np.cos(g_) - np.sin(b) * np.sin(g_) * gd) - bd * np.cos(g_) * gd,
                      -ad * np.sin(b) * bd])
    else:
        w, a = u[3:6].copy(), np.zeros(3)
    r_GS_B = np.array([d.e, 0.0, 0.0])
    vA = np.concatenate([u[:3] + R @ np.cross(w, r_GS_B), w])
    cen = np.cross(w, np.cross(w, r_GS_B)) + np.cross(a, r_GS_B)
    vF = vA.copy()
    vF[:3] += dt * (np.array([0, 0, -setup.gravity]) - R @ cen)
    vF[3:] -= dt * (np.cross(w, theta * w) / theta + a)
    s = math.hypot(R[0, 2], R[1, 2])  # the benchmark state is never horizontal
    exg = np.array([-R[1, 2], R[0, 2], 0.0]) / s  # (2.8)
    off = kin.disk_radius_offsets(np.cross(R[:, 2], exg), R[:, 2], d.r)  # (2.10)-(2.11)
    gaps = qM[2] + off[:, 2]
    use_tau = model.law == mo.CONTENSOU or model.pivot_contour
    c = np.zeros(3)
    if model.pivot_contour:
        k = R[2, 2] ** 2 / (s**2 + CONTOUR_REGULARISATION**2)  # (3.64), regularised as in the step loop
        c = R.T @ np.array([k * R[0, 2], k * R[1, 2], -R[2, 2]]) + np.array([0, 0, 1.0])
    rows, kinds, contact = [], [], []
    for i in np.flatnonzero(gaps <= 0):
        r_SC = off[i] - d.e * R[:, 0]
        for kind, dvec in enumerate(np.eye(3)[[2, 0, 1]]):
            rows.append(np.concatenate([dvec, R.T @ np.cross(r_SC, dvec)]))
            kinds.append(kind)
            contact.append(i)
        if use_tau:
            rows.append(np.concatenate([np.zeros(3), f.contact_radius * R[2, :]]))
            kinds.append(3)
            contact.append(i)
        if model.pivot_contour:
            rows.append(np.concatenate([np.zeros(3), -d.r * c]))
            kinds.append(4)
            contact.append(i)
    W = np.array(rows).reshape(-1, 6)
    kinds, contact = np.array(kinds, int), np.array(contact, int)
    G = (W * minv) @ W.T
    gfree, gA = W @ vF, W @ vA
    P = Pw[contact, kinds] if len(kinds) else np.zeros(0)
    rest = np.array([f.e_N, f.e_T, f.e_T, f.e_tau, f.e_R])
    for _ in range(max_iter if len(P) else 0):
        gE = gfree + G @ P
        xi = gE + rest[kinds] * gA
        Pn = P.copy()
        for i in np.unique(contact):
            j = np.flatnonzero(contact == i)
            pN = max(0.0, P[j[0]] - rN * xi[j[0]])
            Pn[j[0]] = pN
            if model.law == mo.COULOMB:
                Pn[j[1]], Pn[j[2]] = prox_disk(P[j[1]] - rT * xi[j[1]], P[j[2]] - rT * xi[j[2]], f.mu * pN)
            elif model.law == mo.SMOOTH:
                k2 = -f.mu * pN / (math.hypot(gE[j[1]], gE[j[2]]) + f.eps)
                th = 1.0 / (1.0 + f.mu * pN * max(G[j[1], j[1]], G[j[2], j[2]]) / f.eps)
                Pn[j[1]] = P[j[1]] + th * (k2 * gE[j[1]] - P[j[1]])
                Pn[j[2]] = P[j[2]] + th * (k2 * gE[j[2]] - P[j[2]])
            else:
                Pn[j[1]], Pn[j[2]], Pn[j[3]] = prox_contensou(*(P[j[1:4]] - rT * xi[j[1:4]]), f.mu * pN, poly)
            if model.pivot_contour:
                Pn[j[3]] = prox_interval(P[j[3]] - rtau * xi[j[3]], f.mu_tau * pN)
                Pn[j[4]] = prox_interval(P[j[4]] - rR * xi[j[4]], f.mu_R * pN)
        err = 0.0
        for i in np.unique(contact):
            j = np.flatnonzero(contact == i)
            dP = Pn[j] - P[j]
            err += abs(dP[0]) + math.hypot(dP[1], dP[2]) + np.sum(np.abs(dP[3:]))
        P = Pn
        if err < tol:
            break
    vE = vF + minv * (W.T @ P)
    Pw = np.zeros((3, 5))
    Pw[contact, kinds] = P
    uE = np.empty(6)
    uE[:3] = vE[:3] - R @ np.cross(vE[3:], r_GS_B)
    uE[3:] = kin.euler_rates_from_omega(qM[4], qM[5], vE[3:]) if euler else vE[3:]
    qE = advance(qM, uE, 0.5 * dt)
    if not euler and NORMALIZE:
        qE[3:7] /= np.linalg.norm(qE[3:7])
    return qE, uE, exg, Pw


NORMALIZE = defaults.MOREAU_NORMALIZE_QUATERNION  # the default of the quaternion models (Sect. 3.2)


def numba_rate(model, setup, n_steps):
    """Warm steps/s of the compiled loop, starting from the Table 3 state after 0.1 s."""
    q, u, exg = driver.initial_state(model, setup, InitialState())
    par, ipar = driver.parameter_vectors(model, setup, dt=1e-5, tol=1e-8, max_iter=1000, r_N=0.1, r_T=0.1, r_tau=0.1,
                                     r_R=1e-4, normalize_quaternion=NORMALIZE, fall_angle=0.0, store_every=1000)
    poly, Pw, acc = prox.contensou_polygon(), np.zeros((3, 5)), np.zeros(5)
    out = np.zeros((n_steps // 1000 + 20, layout.N_COLUMNS))
    driver.run_steps(q, u, exg, Pw, par, ipar, poly, 10000, 0, out, 0, acc)  # warm up (compile / cache load)
    start = time.perf_counter()
    driver.run_steps(q, u, exg, Pw, par, ipar, poly, n_steps, 10000, out, 0, acc)
    return n_steps / (time.perf_counter() - start), (q, u, exg, Pw)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--numpy-steps", type=int, default=1000)
    parser.add_argument("--quick", action="store_true", help="20,000 steps, 20 numpy steps (the smoke run)")
    args = parser.parse_args()
    if args.quick:
        args.steps, args.numpy_steps = 20_000, 20
    setup = Setup()
    poly = prox.contensou_polygon()
    print(f"{'model':<48}{'numba steps/s':>15}{'numpy steps/s':>15}{'speed-up':>10}{'check':>10}")
    for model in mo.MODELS.values():
        rate, (q, u, exg, Pw) = numba_rate(model, setup, args.steps)
        # numpy baseline from the same state; check one step against the numba loop
        qn, un, _exg, _Pw = numpy_step(model, setup, q.copy(), u.copy(), exg.copy(), Pw.copy(), poly=poly)
        par, ipar = driver.parameter_vectors(model, setup, dt=1e-5, tol=1e-8, max_iter=1000, r_N=0.1, r_T=0.1,
                                         r_R=1e-4, r_tau=0.1, normalize_quaternion=NORMALIZE, fall_angle=0.0,
                                         store_every=1000)
        qc, uc, ec, Pc = q.copy(), u.copy(), exg.copy(), Pw.copy()
        driver.run_steps(qc, uc, ec, Pc, par, ipar, poly, 1, 1, np.zeros((2, layout.N_COLUMNS)), 0, np.zeros(5))
        diff = max(np.max(np.abs(qn - qc)), np.max(np.abs(un - uc)) * 1e-5)
        start = time.perf_counter()
        for _ in range(args.numpy_steps):
            q, u, exg, Pw = numpy_step(model, setup, q, u, exg, Pw, poly=poly)
        np_rate = args.numpy_steps / (time.perf_counter() - start)
        print(f"{model.paper_name + ' ' + model.name:<48}{rate:>15.3g}{np_rate:>15.3g}{rate / np_rate:>9.0f}x"
              f"{diff:>10.1e}")
    for name in ("m5", "m4"):
        from tippedisk_analysis import simulate

        simulate(name, 0.01)
        start = time.perf_counter()
        ds = simulate(name, 5.0)
        print(f"5-s Table 3 run, {ds.attrs['paper_model']}: {time.perf_counter() - start:.2f} s wall "
              f"(step loop {ds.attrs['wall_time']:.2f} s), status {ds.attrs['status']}")


if __name__ == "__main__":
    main()

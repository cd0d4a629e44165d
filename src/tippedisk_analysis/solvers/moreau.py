"""Moreau's midpoint time-stepping scheme (Sect. 4, (4.1)-(4.7)) for the paper's Models 1-10.

One numba-compiled step loop serves all ten models of Table 4; the model picks the
parameterization (Euler angles (3.1)-(3.39) or quaternions (3.40)-(3.67)) and the
dissipation mechanisms. Per step (Sect. 4):

1. q_M = q_A + dt/2 F(q_A) u_A;
2. at q_M: rotation, floating frame (2.8) with continuity when horizontal, candidate
   points C1-C3 (2.10)-(2.11), gaps (2.12), closed set I = {i | g_Ni(q_M) <= 0}, force
   directions of N (normal), T (tangential x, y), tau (pivoting (3.61)), R (contour (3.63)),
   gyroscopic and gravity terms with u_A (see :mod:`..models.moreau_terms` for the
   velocity space used, which is algebraically identical to (4.1));
3. the fixed-point iteration (4.1)-(4.7) written with the Delassus matrix
   G = W^T M^-1 W: gamma_E^k = gamma_free + G P^k, xi = gamma_E + e gamma_A (4.3); the prox
   updates use the new P_N^{k+1} for the friction reservoirs; stop when the summed impulse
   change of the paper is below ``tol``, or count a convergence failure after ``max_iter``;
4. u_E from the impulses, q_E = q_M + dt/2 F(q_M) u_E (optionally normalise the quaternion).

Force laws per closed contact: Signorini/Newton (2.20)-(2.21): P_N = prox_{R+}(P_N - r_N xi_N);
set-valued Coulomb (2.22)/(2.28): P_T = prox_{disk(mu P_N)}(P_T - r_T xi_T);
Coulomb-Contensou (2.24)-(2.27): (P_T, P_tau) = prox_{B_F(mu P_N)}(... - r_T xi_(T,tau)), one
Euclidean projection (r_T used for the whole triple); smooth Coulomb (2.29):
P_T = -mu P_N gamma_TE / (|gamma_TE| + eps), evaluated inside the iteration at the
end-of-step slip (implicit in the slip, first order; the update is relaxed with
theta = 1 / (1 + mu P_N G_TT / eps) so that impacts, where mu P_N G_TT / eps exceeds 1, converge); dry pivoting (2.30) and contour friction
(2.31): projections onto [-mu_tau P_N, mu_tau P_N] and [-mu_R P_N, mu_R P_N]. Impulses are
warm-started from the previous step's values for contacts that stay closed.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time as _time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from .. import kinematics as kin
from ..errors import ParameterError
from ..models import moreau_terms as mt
from ..parameters import InitialState, Setup, to_dict

# friction laws of the tangential direction
COULOMB, CONTENSOU, SMOOTH = 0, 1, 2
EULER, QUATERNION = 0, 1


@dataclass(frozen=True)
class MoreauModel:
    name: str
    number: int
    parameterization: int  # EULER or QUATERNION
    law: int  # COULOMB, CONTENSOU or SMOOTH
    pivot_contour: bool  # dry pivoting (2.30) and contour friction (2.31)

    @property
    def paper_name(self) -> str:
        return f"Model {self.number}"

    @property
    def description(self) -> str:
        law = {COULOMB: "set-valued Coulomb", CONTENSOU: "Coulomb-Contensou", SMOOTH: "smooth Coulomb"}[self.law]
        extra = " + pivoting + contour" if self.pivot_contour else ""
        par = "Euler angles" if self.parameterization == EULER else "quaternions"
        return f"Moreau time stepping, {par}, unilateral contacts C1-C3, {law}{extra} (numba)"


def _models():
    laws = [("coulomb", COULOMB, False), ("contensou", CONTENSOU, False), ("smooth", SMOOTH, False),
            ("coulomb-pivot-contour", COULOMB, True), ("smooth-pivot-contour", SMOOTH, True)]
    out = {}
    for i, (label, law, pc) in enumerate(laws):
        for j, (plabel, par) in enumerate((("euler", EULER), ("quaternion", QUATERNION))):
            number = 2 * i + j + 1
            name = f"moreau-{label}-{plabel}"
            out[name] = MoreauModel(name, number, par, law, pc)
    return out


MODELS: dict[str, MoreauModel] = _models()
OPTIONS = ("dt", "tol", "store_every", "max_iter", "r_N", "r_T", "r_tau", "r_R", "normalize_quaternion",
           "fall_angle", "progress", "checkpoint")

# float parameter vector layout
(_M, _E, _R, _AS, _BS, _CS, _G, _MU, _EPS, _MUTAU, _MUR, _RC, _EN, _ET, _ETAU, _ER, _DT, _TOL, _RN, _RT, _RTAU,
 _RR, _SINFALL) = range(23)
# int parameter vector layout
_PAR, _LAW, _PC, _MAXIT, _NORM, _STORE = range(6)
# stored columns
N_COLS = 35
C_T, C_Q, C_U, C_GAP, C_PN, C_PTX, C_PTY, C_PTAU, C_PR, C_NCL, C_ITMAX, C_ITMEAN = 0, 1, 8, 14, 17, 20, 23, 26, 29, 32, \
    33, 34
STATUS_CODES = {0: "completed", 1: "nonfinite", 2: "fell"}


@njit(cache=True)
def _orientation(q, par_kind, R):
    if par_kind == EULER:
        mt.rotation_euler(q[3], q[4], q[5], R)
    else:
        mt.rotation_quaternion(q[3], q[4], q[5], q[6], R)


@njit(cache=True)
def _advance(q, u, h, par_kind, out, tmp4):
    """out = q + h F(q) u: (3.8) for Euler angles (q_dot = u), (3.44) for quaternions."""
    out[0] = q[0] + h * u[0]
    out[1] = q[1] + h * u[1]
    out[2] = q[2] + h * u[2]
    if par_kind == EULER:
        out[3] = q[3] + h * u[3]
        out[4] = q[4] + h * u[4]
        out[5] = q[5] + h * u[5]
        out[6] = 0.0
    else:
        mt.quaternion_rates(q[3], q[4], q[5], q[6], u[3], u[4], u[5], tmp4)
        for k in range(4):
            out[3 + k] = q[3 + k] + h * tmp4[k]


@njit(cache=True)
def _gaps(q, R, exg, r, off, gaps):
    mt.floating_frame(R, exg)
    mt.contact_offsets(R, exg, r, off)
    for i in range(3):
        gaps[i] = q[2] + off[i, 2]  # (2.12)


@njit(cache=True)
def run_chunk(q, u, exg, Pw, par, ipar, poly, n_steps, step0, out, row0, acc):
    """Advance ``n_steps`` Moreau steps in place; store every ``ipar[_STORE]``-th step into ``out``.

    q (7), u (6): state (Euler: q[6] unused); exg (3): floating-frame e_x^G; Pw (3, 5):
    last impulses per contact [N, Tx, Ty, tau, R] (warm start); acc: [iter_max, iter_sum,
    steps, failures, n_closed] of the current storage interval (failures is the total).
    Returns (steps_done, rows_written, status) with status 0 ok, 1 nonfinite, 2 fell.
    """
    par_kind, law, pc, max_iter, normalize, store_every = ipar[0], ipar[1], ipar[2], ipar[3], ipar[4], ipar[5]
    m, e, r = par[_M], par[_E], par[_R]
    theta = np.array([par[_AS], par[_BS], par[_CS]])
    g, mu, eps, mu_tau, mu_R, rc = par[_G], par[_MU], par[_EPS], par[_MUTAU], par[_MUR], par[_RC]
    dt, tol = par[_DT], par[_TOL]
    rN, rT, rtau, rR = par[_RN], par[_RT], par[_RTAU], par[_RR]
    rest = np.array([par[_EN], par[_ET], par[_ET], par[_ETAU], par[_ER]])
    minv = np.array([1.0 / m, 1.0 / m, 1.0 / m, 1.0 / theta[0], 1.0 / theta[1], 1.0 / theta[2]])

    R = np.empty((3, 3))
    qM = np.empty(7)
    qE = np.empty(7)
    tmp4 = np.empty(4)
    w = np.empty(3)
    a = np.empty(3)
    rates = np.empty(3)
    off = np.empty((3, 3))
    gaps = np.empty(3)
    cvec = np.empty(3)
    vA = np.empty(6)
    vF = np.empty(6)
    W = np.zeros((15, 6))
    Gd = np.zeros((15, 15))
    gfree = np.zeros(15)
    gA = np.zeros(15)
    P = np.zeros(15)
    Pn = np.zeros(15)
    ctype = np.zeros(15, np.int64)  # 0 N, 1 Tx, 2 Ty, 3 tau, 4 R
    ccont = np.zeros(15, np.int64)
    gE = np.zeros(5)
    first = np.zeros(3, np.int64)  # column of P_N of each closed contact, -1 if open
    use_tau = law == CONTENSOU or pc == 1
    rows = 0
    for n in range(n_steps):
        # 1) midpoint (Sect. 4, step 2)
        _advance(q, u, 0.5 * dt, par_kind, qM, tmp4)
        _orientation(qM, par_kind, R)
        # 2) velocities v = A(q_M) u_A = (v_S, Omega) and A_dot u_A
        if par_kind == EULER:
            if abs(math.sin(qM[4])) < par[_SINFALL]:
                return n, rows, 2
            mt.omega_from_rates(qM[4], qM[5], u[3], u[4], u[5], w)
            mt.jdot_rates(qM[4], qM[5], u[3], u[4], u[5], a)
        else:
            w[0], w[1], w[2] = u[3], u[4], u[5]
            a[0], a[1], a[2] = 0.0, 0.0, 0.0
        # Omega x r_GS (B, r_GS = e e_x^B) and (Omega x (Omega x r_GS) + a x r_GS)
        oxr0, oxr1, oxr2 = 0.0, w[2] * e, -w[1] * e
        cen0 = w[1] * oxr2 - w[2] * oxr1 + 0.0
        cen1 = w[2] * oxr0 - w[0] * oxr2 + a[2] * e
        cen2 = w[0] * oxr1 - w[1] * oxr0 - a[1] * e
        for k in range(3):
            vA[k] = u[k] + R[k, 0] * oxr0 + R[k, 1] * oxr1 + R[k, 2] * oxr2  # v_S = v_G + Omega x r_GS
            vA[3 + k] = w[k]
        # free velocity: v_A + M_hat^-1 h_hat' dt (gravity, centripetal of S, gyroscopic, -Theta a)
        L0, L1, L2 = theta[0] * w[0], theta[1] * w[1], theta[2] * w[2]
        gyr0 = w[1] * L2 - w[2] * L1
        gyr1 = w[2] * L0 - w[0] * L2
        gyr2 = w[0] * L1 - w[1] * L0
        for k in range(3):
            vF[k] = vA[k] - dt * (R[k, 0] * cen0 + R[k, 1] * cen1 + R[k, 2] * cen2)
        vF[2] -= dt * g
        vF[3] = vA[3] - dt * (gyr0 / theta[0] + a[0])
        vF[4] = vA[4] - dt * (gyr1 / theta[1] + a[1])
        vF[5] = vA[5] - dt * (gyr2 / theta[2] + a[2])

        # 3) contacts at q_M
        _gaps(qM, R, exg, r, off, gaps)
        s = math.sqrt(R[0, 2] * R[0, 2] + R[1, 2] * R[1, 2])
        if pc == 1:
            mt.contour_direction(R, s, cvec)
        nc = 0
        n_closed = 0
        for i in range(3):
            first[i] = -1
            if gaps[i] > 0.0:
                Pw[i, :] = 0.0
                continue
            n_closed += 1
            first[i] = nc
            # r_SC = r_GC - r_GS (I)
            sx = off[i, 0] - e * R[0, 0]
            sy = off[i, 1] - e * R[1, 0]
            sz = off[i, 2] - e * R[2, 0]
            for d in range(3):  # N (e_z), Tx (e_x), Ty (e_y)
                dx = 1.0 if d == 1 else 0.0
                dy = 1.0 if d == 2 else 0.0
                dz = 1.0 if d == 0 else 0.0
                m0 = sy * dz - sz * dy  # r_SC x d (I)
                m1 = sz * dx - sx * dz
                m2 = sx * dy - sy * dx
                W[nc, 0], W[nc, 1], W[nc, 2] = dx, dy, dz
                for j in range(3):
                    W[nc, 3 + j] = R[0, j] * m0 + R[1, j] * m1 + R[2, j] * m2
                ctype[nc] = d
                ccont[nc] = i
                nc += 1
            if use_tau:  # (3.61): w_tau = eps_i [0, R^T e_z]
                W[nc, 0:3] = 0.0
                for j in range(3):
                    W[nc, 3 + j] = rc * R[2, j]
                ctype[nc] = 3
                ccont[nc] = i
                nc += 1
            if pc == 1:  # (3.63): gamma_R = -r phi_dot
                W[nc, 0:3] = 0.0
                for j in range(3):
                    W[nc, 3 + j] = -r * cvec[j]
                ctype[nc] = 4
                ccont[nc] = i
                nc += 1
        # Delassus matrix and free / start-of-step contact velocities
        for j in range(nc):
            sf = 0.0
            sa = 0.0
            for l in range(6):
                sf += W[j, l] * vF[l]
                sa += W[j, l] * vA[l]
            gfree[j] = sf
            gA[j] = sa
            P[j] = Pw[ccont[j], ctype[j]]
            for k in range(j, nc):
                gs = 0.0
                for l in range(6):
                    gs += W[j, l] * W[k, l] * minv[l]
                Gd[j, k] = gs
                Gd[k, j] = gs

        # 4) fixed-point iteration (4.1)-(4.7)
        it = 0
        if nc > 0:
            converged = False
            while it < max_iter:
                it += 1
                err = 0.0
                for i in range(3):
                    j0 = first[i]
                    if j0 < 0:
                        continue
                    # gamma_E = gamma_free + G P (4.1)-(4.2), xi = gamma_E + e gamma_A (4.3)
                    for k in range(5):
                        gE[k] = 0.0
                    jj = j0
                    while jj < nc and ccont[jj] == i:
                        sgm = gfree[jj]
                        for k in range(nc):
                            sgm += Gd[jj, k] * P[k]
                        gE[ctype[jj]] = sgm
                        jj += 1
                    xiN = gE[0] + rest[0] * gA[j0]
                    pN = mt.prox_nonneg(P[j0] - rN * xiN)  # (4.4)
                    Pn[j0] = pN
                    err += abs(pN - P[j0])
                    xTx = gE[1] + rest[1] * gA[j0 + 1]
                    xTy = gE[2] + rest[2] * gA[j0 + 2]
                    jt = j0 + 3
                    if law == COULOMB:  # (4.5), (2.22)
                        px, py = mt.prox_disk(P[j0 + 1] - rT * xTx, P[j0 + 2] - rT * xTy, mu * pN)
                    elif law == SMOOTH:  # (2.29) at the end-of-step slip
                        k2 = -mu * pN / (math.sqrt(gE[1] * gE[1] + gE[2] * gE[2]) + eps)
                        # relaxed fixed point: theta = 1 / (1 + mu P_N G_TT / eps) makes the linear part
                        # (|gamma_T| << eps) converge in one sweep even for impact-sized P_N; theta ~ 1
                        # in ordinary steps (mu P_N G_TT / eps ~ 1e-4)
                        gtt = max(Gd[j0 + 1, j0 + 1], Gd[j0 + 2, j0 + 2])
                        theta_r = 1.0 / (1.0 + mu * pN * gtt / eps)
                        px = P[j0 + 1] + theta_r * (k2 * gE[1] - P[j0 + 1])
                        py = P[j0 + 2] + theta_r * (k2 * gE[2] - P[j0 + 2])
                    else:  # Coulomb-Contensou (2.24)-(2.27)
                        xtau = gE[3] + rest[3] * gA[jt]
                        px, py, ptau = mt.prox_contensou(P[j0 + 1] - rT * xTx, P[j0 + 2] - rT * xTy,
                                                         P[jt] - rT * xtau, mu * pN, poly)
                        Pn[jt] = ptau
                        err += abs(ptau - P[jt])
                        jt += 1
                    Pn[j0 + 1] = px
                    Pn[j0 + 2] = py
                    err += math.sqrt((px - P[j0 + 1]) ** 2 + (py - P[j0 + 2]) ** 2)
                    if pc == 1:
                        xtau = gE[3] + rest[3] * gA[jt]
                        ptau = mt.prox_interval(P[jt] - rtau * xtau, mu_tau * pN)  # (4.6), (2.30)
                        Pn[jt] = ptau
                        err += abs(ptau - P[jt])
                        xR = gE[4] + rest[4] * gA[jt + 1]
                        pR = mt.prox_interval(P[jt + 1] - rR * xR, mu_R * pN)  # (4.7), (2.31)
                        Pn[jt + 1] = pR
                        err += abs(pR - P[jt + 1])
                for j in range(nc):
                    P[j] = Pn[j]
                if err < tol:
                    converged = True
                    break
            if not converged:
                acc[3] += 1.0
        # 5) end velocity and position
        for l in range(6):
            vF_l = vF[l]
            for j in range(nc):
                vF_l += W[j, l] * P[j] * minv[l]
            vA[l] = vF_l  # v_E
        for i in range(3):
            Pw[i, :] = 0.0
        for j in range(nc):
            Pw[ccont[j], ctype[j]] = P[j]
        for k in range(3):
            w[k] = vA[3 + k]
        oxr0, oxr1, oxr2 = 0.0, w[2] * e, -w[1] * e
        for k in range(3):
            u[k] = vA[k] - (R[k, 0] * oxr0 + R[k, 1] * oxr1 + R[k, 2] * oxr2)  # v_G = v_S - Omega x r_GS
        if par_kind == EULER:
            mt.rates_from_omega(qM[4], qM[5], w, rates)
            u[3], u[4], u[5] = rates[0], rates[1], rates[2]
        else:
            u[3], u[4], u[5] = w[0], w[1], w[2]
        _advance(qM, u, 0.5 * dt, par_kind, qE, tmp4)
        if par_kind == QUATERNION and normalize == 1:
            nq = math.sqrt(qE[3] ** 2 + qE[4] ** 2 + qE[5] ** 2 + qE[6] ** 2)
            for k in range(4):
                qE[3 + k] /= nq
        finite = True
        for k in range(7):
            if not math.isfinite(qE[k]):
                finite = False
        for k in range(6):
            if not math.isfinite(u[k]):
                finite = False
        if not finite:
            return n, rows, 1
        for k in range(7):
            q[k] = qE[k]
        if it > acc[0]:
            acc[0] = it
        acc[1] += it
        acc[2] += 1.0
        acc[4] = n_closed
        if (step0 + n + 1) % store_every == 0:
            row = row0 + rows
            out[row, C_T] = (step0 + n + 1) * dt
            for k in range(7):
                out[row, C_Q + k] = q[k]
            for k in range(6):
                out[row, C_U + k] = u[k]
            _orientation(q, par_kind, R)
            _gaps(q, R, exg, r, off, gaps)
            for i in range(3):
                out[row, C_GAP + i] = gaps[i]
                out[row, C_PN + i] = Pw[i, 0]
                out[row, C_PTX + i] = Pw[i, 1]
                out[row, C_PTY + i] = Pw[i, 2]
                out[row, C_PTAU + i] = Pw[i, 3]
                out[row, C_PR + i] = Pw[i, 4]
            out[row, C_NCL] = n_closed
            out[row, C_ITMAX] = acc[0]
            out[row, C_ITMEAN] = acc[1] / acc[2]
            acc[0] = 0.0
            acc[1] = 0.0
            acc[2] = 0.0
            rows += 1
    return n_steps, rows, 0


# ----------------------------------------------------------------- Python front


def initial_state(model: MoreauModel, setup: Setup, initial: InitialState):
    """q (7), u (6), e_x^G (3) for a closed contact at C1 without slip (6.2)."""
    rest = kin.rest_contact_state(setup.disk.r, initial.euler, initial.euler_rates)
    q = np.zeros(7)
    u = np.zeros(6)
    q[:3] = initial.x, initial.y, rest["z"]
    u[:3] = rest["v_G"]
    R = kin.rotation_from_euler(*initial.euler)
    if model.parameterization == EULER:
        q[3:6] = initial.euler
        u[3:6] = initial.euler_rates
    else:
        q[3:7] = kin.quaternion_from_rotation(R)
        u[3:6] = rest["omega"]
    return q, u, initial_frame(R)


def initial_frame(R: np.ndarray) -> np.ndarray:
    """e_x^G of (2.8); for a horizontal disk (undefined there) e_x^B is taken, Sect. 2.1."""
    exg = np.cross([0.0, 0.0, 1.0], R[:, 2])
    norm = np.linalg.norm(exg)
    return exg / norm if norm > mt.HORIZONTAL_SIN_BETA else R[:, 0].copy()


def parameter_vectors(model: MoreauModel, setup: Setup, *, dt: float, tol: float, max_iter: int, r_N: float,
                      r_T: float, r_tau: float, r_R: float, normalize_quaternion: bool, fall_angle: float,
                      store_every: int):
    d, f = setup.disk, setup.friction
    inertia = d.inertia_S
    par = np.array([d.m, d.e, d.r, inertia["A_S"], inertia["B_S"], inertia["C_S"], setup.gravity, f.mu, f.eps,
                    f.mu_tau, f.mu_R, f.contact_radius, f.e_N, f.e_T, f.e_tau, f.e_R, dt, tol, r_N, r_T, r_tau,
                    r_R, math.sin(fall_angle)])
    ipar = np.array([model.parameterization, model.law, int(model.pivot_contour), max_iter,
                     int(normalize_quaternion), store_every], dtype=np.int64)
    return par, ipar


def _validate(dt, tol, store_every, max_iter, gains, fall_angle, t_end):
    for name, value in (("dt", dt), ("tol", tol), *gains.items()):
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise ParameterError(f"{name} = {value!r} must be a positive number")
    if dt > 1e-3:
        raise ParameterError(f"dt = {dt} s is too coarse for Moreau's scheme here; give dt <= 1e-3 (paper: 1e-5)")
    if t_end / dt > 1e10:
        raise ParameterError(f"t_end / dt = {t_end / dt:.3g} steps is too many; give a larger dt or shorter t_end")
    for name, value in (("store_every", store_every), ("max_iter", max_iter)):
        if not (isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= 1):
            raise ParameterError(f"{name} = {value!r} must be a positive integer")
    if not (math.isfinite(fall_angle) and 0 <= fall_angle < math.pi / 2):
        raise ParameterError(f"fall_angle = {fall_angle!r} rad must lie in [0, pi/2); give e.g. 0.01")


def integrate(model: MoreauModel, setup: Setup, initial: InitialState, t_end: float, *, dt: float = 1e-5,
              tol: float = 1e-8, store_every: int | None = None, max_iter: int = 1000, r_N: float = 0.1,
              r_T: float = 0.1, r_tau: float = 0.1, r_R: float = 1e-4, normalize_quaternion: bool = False,
              fall_angle: float | None = None, progress: bool | None = None, state=None,
              checkpoint: str | os.PathLike | None = None):
    """Run the step loop; returns (stored rows, status code, failures, steps, wall time, options used).

    ``state = (q, u)`` replaces the closed rest contact of ``initial`` (e.g. a drop test):
    q = [x, y, z, alpha, beta, gamma, 0] or [x, y, z, p0..p3], u = [v_G, Euler rates or Omega_B].
    ``checkpoint``: a file that receives the loop's full state every ``CHECKPOINT_SECONDS`` of
    wall time; a later call with the same arguments resumes from it (finished steps are not
    redone, the result is bitwise that of an uninterrupted run), and it is removed at the end.
    """
    if store_every is None:
        store_every = max(1, int(round(1e-3 / dt)))  # 1 ms sampling: 5000 samples for a 5-s run
    if fall_angle is None:
        fall_angle = 1e-2 if model.parameterization == EULER else 0.0
    gains = {"r_N": r_N, "r_T": r_T, "r_tau": r_tau, "r_R": r_R}
    _validate(dt, tol, store_every, max_iter, gains, fall_angle, t_end)
    n_total = int(math.floor(t_end / dt + 1e-9))
    if n_total < 1:
        raise ParameterError(f"t_end = {t_end} s is shorter than one step dt = {dt} s; give t_end >= dt")
    par, ipar = parameter_vectors(model, setup, dt=dt, tol=tol, max_iter=max_iter, normalize_quaternion=
                                  normalize_quaternion, fall_angle=fall_angle, store_every=store_every, **gains)
    q, u, exg = initial_state(model, setup, initial)
    if state is not None:
        q, u = np.array(state[0], dtype=float), np.array(state[1], dtype=float)
        if q.shape != (7,) or u.shape != (6,) or not (np.all(np.isfinite(q)) and np.all(np.isfinite(u))):
            raise ParameterError("state must be (q, u) of finite values with 7 and 6 entries")
        R = np.empty((3, 3))
        _orientation(q, model.parameterization, R)
        exg = initial_frame(R)
    poly = mt.contensou_polygon()
    Pw = np.zeros((3, 5))
    acc = np.zeros(5)
    n_rows = n_total // store_every + 1
    out = np.zeros((n_rows, N_COLS))
    # row 0: the initial state
    out[0, C_Q:C_Q + 7] = q
    out[0, C_U:C_U + 6] = u
    R0 = np.empty((3, 3))
    gaps0 = np.empty(3)
    _orientation(q, model.parameterization, R0)
    _gaps(q, R0, exg.copy(), setup.disk.r, np.empty((3, 3)), gaps0)
    out[0, C_GAP:C_GAP + 3] = gaps0

    done, rows, status = 0, 1, 0
    resume = _Checkpoint(checkpoint, _fingerprint(model, setup, initial, t_end, state, par, ipar)) if checkpoint else None
    if resume is not None and resume.exists():
        q, u, exg, Pw, acc, stored, done, status = resume.load()
        rows = len(stored)
        out[:rows] = stored

    chunk = max(store_every, (20000 // store_every) * store_every)
    expected = n_total * 1e-6  # rough seconds on one core (measured 1e6-6e6 steps/s, benchmarks/)
    show = progress if progress is not None else (expected > 5.0 and sys.stderr.isatty())
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=n_total, initial=done, unit="step", unit_scale=True, desc=model.name, file=sys.stderr)
    start = last_save = _time.perf_counter()
    try:
        while done < n_total and status == 0:
            n = min(chunk, n_total - done)
            steps, written, status = run_chunk(q, u, exg, Pw, par, ipar, poly, n, done, out, rows, acc)
            done += steps
            rows += written
            if bar is not None:
                bar.update(steps)
            if resume is not None and _time.perf_counter() - last_save > CHECKPOINT_SECONDS:
                resume.save(q, u, exg, Pw, acc, out[:rows], done, status)
                last_save = _time.perf_counter()
    finally:
        if bar is not None:
            bar.close()
    wall = _time.perf_counter() - start
    if resume is not None:
        resume.remove()
    options = {"dt": dt, "tol": tol, "store_every": store_every, "max_iter": max_iter, **gains,
               "normalize_quaternion": int(normalize_quaternion), "fall_angle": fall_angle}
    return out[:rows], status, int(acc[3]), done, wall, options


CHECKPOINT_SECONDS = 10.0


def _fingerprint(model, setup, initial, t_end, state, par, ipar) -> str:
    """Everything that determines a run, to refuse resuming another run's checkpoint."""
    return json.dumps({"model": model.name, "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
                       "state": None if state is None else np.asarray(state[0]).tolist() + np.asarray(state[1]).tolist(),
                       "par": par.tolist(), "ipar": ipar.tolist()}, sort_keys=True)


class _Checkpoint:
    """The loop state of a Moreau run in an .npz file, written atomically."""

    def __init__(self, path, fingerprint: str):
        self.path = Path(path)
        self.fingerprint = fingerprint

    def exists(self) -> bool:
        return self.path.is_file()

    def load(self):
        try:
            with np.load(self.path) as f:
                stored = {name: f[name].copy() for name in f.files}
        except (OSError, ValueError) as exc:
            raise ParameterError(f"checkpoint {str(self.path)!r} is unreadable ({exc.__class__.__name__}); "
                                 "delete it to start afresh") from None
        if str(stored.get("fingerprint")) != self.fingerprint:
            raise ParameterError(f"checkpoint {str(self.path)!r} belongs to a different run; delete it or "
                                 "choose another output file")
        return (stored["q"], stored["u"], stored["exg"], stored["Pw"], stored["acc"], stored["out"],
                int(stored["done"]), int(stored["status"]))

    def save(self, q, u, exg, Pw, acc, out, done, status) -> None:
        tmp = self.path.with_name(self.path.name + ".part.npz")
        np.savez(tmp, fingerprint=self.fingerprint, q=q, u=u, exg=exg, Pw=Pw, acc=acc, out=out, done=done,
                 status=status)
        os.replace(tmp, self.path)

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)


def run(model_name: str, setup: Setup, initial: InitialState, t_end: float, **options):
    """Simulate a Moreau model and return the dataset (schema of :mod:`..results`)."""
    import xarray as xr

    from ..results import describe, make_attrs

    model = MODELS[model_name]
    rows, status_code, failures, steps, wall, used = integrate(model, setup, initial, t_end, **options)
    data = outputs(model, setup, rows, used["dt"])
    status = STATUS_CODES[status_code]
    t_final = steps * used["dt"]
    if status == "completed":
        message = f"reached t_end = {t_end:g} s in {steps} steps"
    elif status == "fell":
        message = (f"the disk came within fall_angle = {used['fall_angle']:g} rad of horizontal at t = "
                   f"{t_final:.6g} s, the Euler-angle singularity; use a quaternion model to continue")
    else:
        message = (f"non-finite state at t = {t_final:.6g} s; the dataset ends at the last stored sample; "
                   "try a smaller --dt")
    if failures:
        status = "not_converged" if status == "completed" else status
        message += (f"; the prox iteration hit max_iter = {used['max_iter']} in {failures} step(s): "
                    "raise --max-iter or --tol, or lower the r_* gains")
    config = {"model": model_name, "setup": to_dict(setup), "initial": to_dict(initial), "t_end": t_end,
              "integrator": {"name": "moreau-midpoint (numba)", **used}}
    time = data.pop("time")
    contact_vars = {k: data.pop(k) for k in ("P_N", "P_Tx", "P_Ty", "P_tau", "P_R")}
    ds = xr.Dataset({name: ("time", np.asarray(v, dtype=float)) for name, v in data.items()},
                    coords={"time": time, "contact": np.array([1, 2, 3], dtype=np.int8)},
                    attrs=make_attrs("simulation", config, status, message, model=model_name,
                                     paper_model=model.paper_name, n_steps=steps, t_final=t_final,
                                     convergence_failures=failures, wall_time=wall))
    for name, values in contact_vars.items():
        ds[name] = (("time", "contact"), values)
        ds[name.replace("P_", "lambda_") + "_contact"] = (("time", "contact"), values / used["dt"])
    ds["n_closed"] = ds["n_closed"].astype(np.int8)
    ds["contact"].attrs.update(long_name="candidate contact point C_i", units="1")
    if model.parameterization == QUATERNION:
        for name in ("alpha_dot", "beta_dot", "gamma_dot"):
            ds[name].attrs["comment"] = "set to 0 where the disk is horizontal (sin beta = 0): Euler rates are undefined there"
    return describe(ds)


def outputs(model: MoreauModel, setup: Setup, rows: np.ndarray, dt: float) -> dict:
    """Schema variables from stored rows (vectorized numpy, using :mod:`kinematics`)."""
    d = setup.disk
    q, u = rows[:, C_Q:C_Q + 7], rows[:, C_U:C_U + 6]
    data = {"time": rows[:, C_T], "x": q[:, 0], "y": q[:, 1], "z": q[:, 2]}
    if model.parameterization == EULER:
        R = kin.rotation_from_euler(q[:, 3], q[:, 4], q[:, 5])
        euler = q[:, 3:6].T
        rates = u[:, 3:6]
        omega = kin.omega_from_euler_rates(q[:, 4], q[:, 5], rates)
    else:
        p = q[:, 3:7]
        for k in range(4):
            data[f"p{k}"] = p[:, k]
        data["quaternion_norm_error"] = np.linalg.norm(p, axis=1) - 1.0
        R = kin.rotation_from_quaternion(p / np.linalg.norm(p, axis=1)[:, None])
        euler = np.array(kin.euler_from_rotation(R))
        euler[0], euler[2] = np.unwrap(euler[0]), np.unwrap(euler[2])
        omega = u[:, 3:6]
        with np.errstate(divide="ignore", invalid="ignore"):
            rates = kin.euler_rates_from_omega(euler[1], euler[2], omega)
        rates = np.where(np.isfinite(rates), rates, 0.0)  # horizontal disk: rates undefined, stored as 0
    for k, name in enumerate(("alpha", "beta", "gamma")):
        data[name] = euler[k]
        data[name + "_dot"] = rates[:, k]
    for k, name in enumerate(("x_dot", "y_dot", "z_dot")):
        data[name] = u[:, k]
    for k, name in enumerate(("omega_x", "omega_y", "omega_z")):
        data[name] = omega[:, k]
    r_GS = d.e * R[:, :, 0]
    omega_I = np.einsum("nij,nj->ni", R, omega)
    v_S = u[:, :3] + np.cross(omega_I, r_GS)
    inertia = np.array(list(d.inertia_S.values()))
    data["z_S"] = q[:, 2] + r_GS[:, 2]
    data["E_kin"] = 0.5 * d.m * np.sum(v_S**2, axis=1) + 0.5 * np.sum(inertia * omega**2, axis=1)
    data["E_pot"] = d.m * setup.gravity * data["z_S"]
    data["E_tot"] = data["E_kin"] + data["E_pot"]
    for i in range(3):
        data[f"g_N{i + 1}"] = rows[:, C_GAP + i]
    # slip and normal velocity at C1 (2.13)-(2.15), from the stored gap geometry
    sin_beta = np.hypot(R[:, 0, 2], R[:, 1, 2])
    safe = np.where(sin_beta > 0, sin_beta, 1.0)
    ey = np.stack([-R[:, 2, 2] * R[:, 0, 2] / safe, -R[:, 2, 2] * R[:, 1, 2] / safe, sin_beta], axis=1)  # (2.8)
    v_C1 = u[:, :3] + np.cross(omega_I, -d.r * ey)
    data["slip_x"], data["slip_y"], data["gamma_N1"] = v_C1[:, 0], v_C1[:, 1], v_C1[:, 2]
    data["lambda_N"] = rows[:, C_PN] / dt
    data["n_closed"] = rows[:, C_NCL]
    data["prox_iterations_max"] = rows[:, C_ITMAX]
    data["prox_iterations_mean"] = rows[:, C_ITMEAN]
    data["P_N"] = rows[:, C_PN:C_PN + 3]
    data["P_Tx"] = rows[:, C_PTX:C_PTX + 3]
    data["P_Ty"] = rows[:, C_PTY:C_PTY + 3]
    data["P_tau"] = rows[:, C_PTAU:C_PTAU + 3]
    data["P_R"] = rows[:, C_PR:C_PR + 3]
    return data

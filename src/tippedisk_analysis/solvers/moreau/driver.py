"""Run the numba step loop of a Moreau model: initial state, parameter vectors, validation,
progress and checkpoints around :func:`.step.run_steps`."""

from __future__ import annotations

import math
import os
import sys
import time as _time

import numpy as np

from ... import defaults, files
from ... import kinematics as kin
from ...errors import ParameterError
from ...models import moreau_geometry as geo
from ...models import prox
from ...parameters import InitialState, Setup
from . import layout as L
from .checkpoint import Checkpoint, fingerprint
from .models import CONTENSOU, EULER, MoreauModel
from .step import contact_gaps, orientation, run_steps


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
    ex_G = np.cross([0.0, 0.0, 1.0], R[:, 2])
    norm = np.linalg.norm(ex_G)
    return ex_G / norm if norm > geo.HORIZONTAL_SIN_BETA else R[:, 0].copy()


def parameter_vectors(model: MoreauModel, setup: Setup, *, dt: float, tol: float, max_iter: int, r_N: float,
                      r_T: float, r_tau: float, r_R: float, normalize_quaternion: bool, fall_angle: float,
                      store_every: int, contensou_torque_share: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(par, flags): the float and integer vectors of :mod:`.layout`."""
    d, f = setup.disk, setup.friction
    inertia = d.inertia_S
    par = np.empty(L.N_PAR)
    for index, value in ((L.M, d.m), (L.E, d.e), (L.RADIUS, d.r), (L.A_S, inertia["A_S"]), (L.B_S, inertia["B_S"]),
                         (L.C_S, inertia["C_S"]), (L.GRAVITY, setup.gravity), (L.MU, f.mu), (L.EPS, f.eps),
                         (L.MU_TAU, f.mu_tau), (L.MU_R, f.mu_R), (L.CONTACT_RADIUS, f.contact_radius),
                         (L.E_N, f.e_N), (L.E_T, f.e_T), (L.E_TAU, f.e_tau), (L.E_R, f.e_R), (L.DT, dt), (L.TOL, tol),
                         (L.R_N, r_N), (L.R_T, r_T), (L.R_TAU, r_tau), (L.R_R, r_R),
                         (L.SIN_FALL_ANGLE, math.sin(fall_angle)), (L.CONTENSOU_TORQUE_SHARE, contensou_torque_share)):
        par[index] = value
    flags = np.empty(L.N_FLAGS, dtype=np.int64)
    for index, value in ((L.PARAMETERIZATION, model.parameterization), (L.LAW, model.law),
                         (L.PIVOT_CONTOUR, int(model.pivot_contour)), (L.MAX_ITER, max_iter),
                         (L.NORMALIZE_QUATERNION, int(normalize_quaternion)), (L.STORE_EVERY, store_every)):
        flags[index] = value
    return par, flags


def default_fall_angle(model: MoreauModel) -> float:
    return defaults.FALL_ANGLE if model.parameterization == EULER else defaults.FALL_ANGLE_QUATERNION_MOREAU


def _validate_torque_share(model, share) -> float:
    if isinstance(share, bool) or not (isinstance(share, int | float | np.floating) and 0.0 <= share <= 1.0):
        raise ParameterError(f"contensou_torque_share = {share!r} must be a number in [0, 1]; give 1 (the law "
                             "(2.24)-(2.27), default) or 0 (the diagnostic variant without pivoting torque)")
    if share != 1.0 and model.law != CONTENSOU:
        raise ParameterError(f"contensou_torque_share applies to the Coulomb-Contensou Models 3/4 only, not to "
                             f"{model.paper_name} ({model.name}); leave it at 1")
    return float(share)


def whole_steps(t_end: float, dt: float) -> int:
    """The number of steps dt in t_end, t_end / dt rounded down unless it is an integer to round-off (relative:
    600 / 1e-5 is 59999999.99999999 in floating point, and an absolute 1e-9 does not reach 6e7)."""
    ratio = t_end / dt
    nearest = round(ratio)
    return int(nearest) if abs(ratio - nearest) <= 1e-9 * max(1.0, ratio) else int(math.floor(ratio))


def _validate(model, dt, tol, store_every, max_iter, gains, fall_angle, t_end):
    for name, value in (("dt", dt), ("tol", tol), *gains.items()):
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise ParameterError(f"{name} = {value!r} must be a positive number")
    if dt > defaults.MOREAU_MAX_DT:
        raise ParameterError(f"dt = {dt} s is too coarse for Moreau's scheme here; give dt <= "
                             f"{defaults.MOREAU_MAX_DT:g} (paper: {defaults.MOREAU_DT:g})")
    if t_end / dt > 1e10:
        raise ParameterError(f"t_end / dt = {t_end / dt:.3g} steps is too many; give a larger dt or shorter t_end")
    for name, value in (("store_every", store_every), ("max_iter", max_iter)):
        if not (isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= 1):
            raise ParameterError(f"{name} = {value!r} must be a positive integer")
    lowest_ok = 0.0 if model.parameterization != EULER else None
    if not (isinstance(fall_angle, int | float) and math.isfinite(fall_angle) and fall_angle < math.pi / 2
            and (fall_angle > 0 or fall_angle == lowest_ok)):
        closed = "(0, pi/2)" if lowest_ok is None else "[0, pi/2)"
        raise ParameterError(f"fall_angle = {fall_angle!r} rad must lie in {closed} for {model.name}; "
                             f"give e.g. {defaults.FALL_ANGLE:g}")


def integrate(model: MoreauModel, setup: Setup, initial: InitialState, t_end: float, *, dt: float = defaults.MOREAU_DT,
              tol: float = defaults.MOREAU_TOL, store_every: int | None = None,
              max_iter: int = defaults.MOREAU_MAX_ITER, r_N: float = defaults.MOREAU_GAINS["r_N"],
              r_T: float = defaults.MOREAU_GAINS["r_T"], r_tau: float = defaults.MOREAU_GAINS["r_tau"],
              r_R: float = defaults.MOREAU_GAINS["r_R"],
              normalize_quaternion: bool = defaults.MOREAU_NORMALIZE_QUATERNION,
              fall_angle: float | None = None, progress: bool | None = None, state=None,
              checkpoint: str | os.PathLike | None = None, contensou_torque_share: float = 1.0):
    """Run the step loop; returns (stored rows, status code, failures, steps, wall time, options used).

    ``state = (q, u)`` replaces the closed rest contact of ``initial`` (e.g. a drop test):
    q = [x, y, z, alpha, beta, gamma, 0] or [x, y, z, p0..p3], u = [v_G, Euler rates or Omega_B].
    ``checkpoint``: a file that receives the loop's full state every ``CHECKPOINT_SECONDS`` of
    wall time; a later call with the same arguments resumes from it (finished steps are not
    redone, the result is bitwise that of an uninterrupted run), and it is removed at the end.

    ``normalize_quaternion`` (quaternion Models 2, 4, 6, 8, 10): p <- p / |p| after each step, as the
    paper prescribes after (3.67) (default); False keeps the unnormalised scheme for drift studies.

    ``contensou_torque_share`` (Models 3/4 only; a diagnostic variant, not a friction law): the share
    in [0, 1] of the Coulomb-Contensou pivoting torque eps_i P_tau that acts on the disk. 1 (default)
    is the law (2.24)-(2.27). Below 1 the spin still regularises the sliding force through the ball
    (gamma_tau = eps_i omega_IB enters the prox unchanged), but the pivoting impulse does no work on
    the disk in the share removed: not a consistent friction law. With 0 and a contact radius of
    2.5-2.9 mm it reproduces the paper's Figs. 9, 10 and 15 (docs/contensou_investigation.md). The
    stored P_tau is the prox impulse either way.
    """
    share = _validate_torque_share(model, contensou_torque_share)
    if not (isinstance(normalize_quaternion, bool | np.bool_) or normalize_quaternion in (0, 1)):
        raise ParameterError(f"normalize_quaternion = {normalize_quaternion!r} must be True (default, Sect. 3.2 "
                             "after (3.67)) or False (the unnormalised drift study)")
    normalize_quaternion = bool(normalize_quaternion)
    if store_every is None:
        store_every = max(1, int(round(defaults.MOREAU_STORE_INTERVAL / dt)))
    if fall_angle is None:
        fall_angle = default_fall_angle(model)
    gains = {"r_N": r_N, "r_T": r_T, "r_tau": r_tau, "r_R": r_R}
    _validate(model, dt, tol, store_every, max_iter, gains, fall_angle, t_end)
    n_total = whole_steps(t_end, dt)
    if n_total < 1:
        raise ParameterError(f"t_end = {t_end} s is shorter than one step dt = {dt} s; give t_end >= dt")
    par, flags = parameter_vectors(model, setup, dt=dt, tol=tol, max_iter=max_iter,
                                   normalize_quaternion=normalize_quaternion, fall_angle=fall_angle,
                                   store_every=store_every, contensou_torque_share=share, **gains)
    q, u, ex_G = initial_state(model, setup, initial)
    if state is not None:
        q, u = np.array(state[0], dtype=float), np.array(state[1], dtype=float)
        if q.shape != (7,) or u.shape != (6,) or not (np.all(np.isfinite(q)) and np.all(np.isfinite(u))):
            raise ParameterError("state must be (q, u) of finite values with 7 and 6 entries")
        R = np.empty((3, 3))
        orientation(q, model.parameterization, R)
        ex_G = initial_frame(R)
    ball = prox.contensou_polygon()
    P_last = np.zeros((L.N_CONTACTS, L.N_IMPULSES))
    stats = np.zeros(L.N_STATS)
    n_rows = n_total // store_every + 1
    out = np.zeros((n_rows, L.N_COLUMNS))
    # row 0: the initial state
    out[0, L.COL_Q:L.COL_Q + 7] = q
    out[0, L.COL_U:L.COL_U + 6] = u
    R0 = np.empty((3, 3))
    gaps0 = np.empty(3)
    orientation(q, model.parameterization, R0)
    contact_gaps(q, R0, ex_G.copy(), setup.disk.r, np.empty((3, 3)), gaps0)
    out[0, L.COL_GAP:L.COL_GAP + 3] = gaps0

    done, rows, status = 0, 1, L.STATUS_OK
    resume = (Checkpoint(checkpoint, fingerprint(model, setup, initial, t_end, state, par, flags))
              if checkpoint else None)
    if resume is not None and resume.exists():
        saved = resume.load()
        q, u, ex_G, P_last, stats = saved["q"], saved["u"], saved["ex_G"], saved["P_last"], saved["stats"]
        done, status = int(saved["done"]), int(saved["status"])
        rows = len(saved["out"])
        out[:rows] = saved["out"]

    chunk = max(store_every, (defaults.MOREAU_CHUNK_STEPS // store_every) * store_every)
    expected = n_total * 1e-6  # rough seconds on one core (measured 1e6-6e6 steps/s, benchmarks/)
    show = progress if progress is not None else (expected > 5.0 and sys.stderr.isatty())
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=n_total, initial=done, unit="step", unit_scale=True, desc=model.name, file=sys.stderr)
    start = last_save = _time.perf_counter()
    try:
        while done < n_total and status == L.STATUS_OK:
            n = min(chunk, n_total - done)
            steps, written, status = run_steps(q, u, ex_G, P_last, par, flags, ball, n, done, out, rows, stats)
            done += steps
            rows += written
            if bar is not None:
                bar.update(steps)
            if resume is not None and _time.perf_counter() - last_save > defaults.CHECKPOINT_SECONDS:
                resume.save(q=q, u=u, ex_G=ex_G, P_last=P_last, stats=stats, out=out[:rows], done=done, status=status)
                last_save = _time.perf_counter()
                files.hold_for_interrupt("checkpoint")
    finally:
        if bar is not None:
            bar.close()
    wall = _time.perf_counter() - start
    if resume is not None:
        resume.remove()
    options = {"dt": dt, "tol": tol, "store_every": store_every, "max_iter": max_iter, **gains,
               "normalize_quaternion": int(normalize_quaternion), "fall_angle": fall_angle,
               **({"contensou_torque_share": share} if model.law == CONTENSOU else {})}
    return out[:rows], status, int(stats[L.STAT_FAILURES]), done, wall, options

"""Periodic orbits of a :class:`.system.System` at fixed parameters: Newton on the shooting equations from a
guess (a point and a period, a Hopf point, a simulation's Poincare return), the first integrals' levels, and
a finite-difference monodromy as an independent check of the variational one.

Statuses of a search (:data:`STATUS`): ``converged`` (a periodic orbit); ``equilibrium`` (Newton went to a
point: an equilibrium solves the shooting equations for every T, never an orbit); ``not_converged`` (the
residual of the last iterate is in the message); ``nonfinite``. Branches start here or at a Hopf point
(:mod:`.orbit_branches`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from . import normal_forms
from .flows import TAYLOR_TOL, Flow, FlowError
from .discretisations import make_problem
from .orbit_base import OrbitProblem, PeriodicOrbit, newton
from .system import System

NEWTON_TOL = 1e-10  # largest scaled Newton step at convergence
NEWTON_MAX_ITER = 25
AMPLITUDE_TOL = 1e-7  # scaled amplitude below which a converged "orbit" is an equilibrium
STATUS = {"converged": 0, "equilibrium": 1, "not_converged": 2, "nonfinite": 3}
"""int8 codes of ``orbit_status`` in periodic-orbit datasets."""


def find_orbit(system: System, state, period: float, pars=None, *, method: str = "shooting", tol: float = TAYLOR_TOL,
               newton_tol: float = NEWTON_TOL, max_iter: int = NEWTON_MAX_ITER, amplitude_tol: float = AMPLITUDE_TOL,
               pinned=(), **discretisation) -> PeriodicOrbit:
    """A periodic orbit near (``state``, ``period``) by Newton's method; always returns a status.

    ``method``: ``shooting`` (``segments``, default 1; ``phase``: poincare or integral) or ``collocation``
    (``ntst`` x ``ncol``, the mesh adapted to the integrated guess and again to the orbit found,
    :mod:`.collocation`); ``discretisation``: the method's options (:mod:`.discretisations`). Gauss-Newton with
    the phase condition fixed at the guess (least-squares steps of at most MAX_NEWTON_STEP in scaled unknowns,
    halved while they increase the residual).
    Statuses: ``converged`` (a periodic orbit);
    ``equilibrium`` (Newton converged, or was converging, to a point: amplitude below ``amplitude_tol``
    -- an equilibrium is a solution of the shooting equations for every T, never an orbit);
    ``not_converged`` (the message holds the residual of the last iterate); ``nonfinite``.
    """
    if not (isinstance(period, int | float) and math.isfinite(period) and period > 0):
        raise ParameterError(f"period guess T = {period!r} must be a positive number")
    state = np.asarray(state, dtype=float)
    if state.shape != (system.n,) or not np.all(np.isfinite(state)):
        raise ParameterError(f"the state guess must be {system.n} finite numbers ({', '.join(system.state_names)})")
    levels = integral_levels(system, state, pars) if system.integrals else None
    pins = {name: float(state[system.state_index(name)]) for name in pinned}
    prob = make_problem(method, system, pars, period_scale=float(period), tol=tol, levels=levels, pins=pins,
                        **discretisation)
    try:
        u = prob.unknowns(state, float(period))
    except FlowError as exc:
        return _failed(prob, state, period, "nonfinite", f"the guess cannot be integrated: {exc}")
    status, u, it, F = newton(prob, u, newton_tol, max_iter)
    for _ in range(2 if method == "collocation" and status == "converged" else 0):
        remeshed = prob.improved(u)  # the mesh of the orbit found (the guess's may differ): solve again on it
        if remeshed is None:
            break
        status, u, more, F = newton(prob, remeshed, newton_tol, max_iter)
        it += more
    if status == "nonfinite":
        return _failed(prob, prob.split(u)[0][0], prob.split(u)[1], "nonfinite",
                       f"the Newton iterate {it} left the domain of the equations (non-finite flow)")
    if status == "guess":
        return _failed(prob, state, period, "nonfinite", "the guess cannot be integrated over the period")
    try:
        orbit = prob.orbit(u, status, "", None, it)
    except FlowError as exc:
        return _failed(prob, prob.split(u)[0][0], prob.split(u)[1], "nonfinite", str(exc))
    residual = orbit.residual
    if orbit.amplitude < amplitude_tol:
        orbit.status = "equilibrium"
        orbit.message = (f"Newton {'converged' if status == 'converged' else 'was converging'} to an equilibrium "
                         f"(amplitude {orbit.amplitude:.2g} in scaled units after {it} steps, residual "
                         f"{residual:.2g}): not a periodic orbit")
    elif status == "converged":
        k = _covering(prob, orbit)
        if k > 1:  # the guess went round k times: the orbit of the least period (its multipliers are mu^(1/k))
            least = find_orbit(system, orbit.states[0], orbit.period / k, pars, method=method, tol=tol,
                               newton_tol=newton_tol, max_iter=max_iter, amplitude_tol=amplitude_tol, pinned=pinned,
                               **discretisation)
            if least.converged:
                least.message += f" (the guess T = {period:.6g} went {k} times round it)"
                return least
        error = (f", estimated discretisation error {orbit.discretisation_error:.2g}"
                 if orbit.discretisation_error is not None else "")
        orbit.message = (f"periodic orbit, T = {orbit.period:.12g}, {it} Newton steps, residual {residual:.2g}"
                         f"{error}; {_stability_text(orbit)}")
    else:
        orbit.message = (f"Newton did not converge in {it} steps: residual {residual:.3g} (of the {prob.method} "
                         f"equations, per state scale) at T = {orbit.period:.6g}, amplitude {orbit.amplitude:.3g}; "
                         "no periodic orbit near the guess")
    return orbit


COVER_RTOL = 1e-6  # |x(T/k) - x(0)| / scale below this share of the amplitude: the orbit closes after T/k


def _covering(prob: OrbitProblem, orbit: PeriodicOrbit, most: int = 7) -> int:
    """The least k in 2 .. ``most`` for which the converged orbit closes after T/k already (1 if none): a
    solution of the shooting equations with k times the orbit's least period."""
    x0 = orbit.states[0]
    scale = np.asarray(prob.system.state_scale)
    for k in range(2, most + 1):
        try:
            x = prob.flow.advance(x0, orbit.period / k, orbit.pars)
        except FlowError:
            return 1
        if np.max(np.abs(x - x0) / scale) <= COVER_RTOL * orbit.amplitude:
            return k
    return 1


def _stability_text(orbit: PeriodicOrbit) -> str:
    flag, n_unstable = orbit.classification()
    if not orbit.multipliers_reliable:
        return (f"stability undecided: the multipliers fail their check (the flow direction's is off 1 by "
                f"{orbit.flow_multiplier_error:.2g})")
    word = {0: "stable", 1: "marginal", 2: f"unstable ({n_unstable} multiplier(s) outside the unit circle)"}[flag]
    big = orbit.multipliers[~orbit.trivial]
    return f"{word}, largest nontrivial |multiplier| {np.abs(big).max(initial=0.0):.6g}"


def integral_levels(system: System, state, pars=None) -> dict:
    """The first integrals' values at ``state`` ({name: value})."""
    if not system.integrals:
        return {}
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    values = system.integrals_field().values(np.asarray(state, dtype=float), pars)
    return dict(zip(system.integrals, map(float, values)))


def _failed(prob: OrbitProblem, state, period, status, message) -> PeriodicOrbit:
    n = prob.n
    return PeriodicOrbit(status, message, prob.system, prob.pars.copy(), np.atleast_2d(state).copy(), float(period),
                         None, None, math.inf, 0, np.full(n, complex(math.nan)), np.zeros(n, bool), np.zeros(1),
                         np.atleast_2d(state).copy(), np.zeros((1, len(prob.system.observables))), method=prob.method)


def monodromy_fd(system: System, state, period: float, pars=None, h: float = 1e-6,
                 tol: float = TAYLOR_TOL) -> np.ndarray:
    """Monodromy by central finite differences of the flow (an independent check of the variational one)."""
    flow = Flow(system, tol)
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    state = np.asarray(state, dtype=float)
    M = np.empty((system.n, system.n))
    for j in range(system.n):
        d = h * system.state_scale[j]
        e = np.zeros(system.n)
        e[j] = d
        M[:, j] = (flow.advance(state + e, period, pars) - flow.advance(state - e, period, pars)) / (2 * d)
    return M


@dataclass(frozen=True)
class HopfGuess:
    """An orbit guess near a Hopf point of an isolated equilibrium (Kuznetsov's normal form)."""

    value: float  # parameter value of the guess, value_H + dp
    state: np.ndarray  # x_H + 2 Re(r q)
    period: float  # 2 pi / omega
    value_hopf: float
    equilibrium: np.ndarray
    omega: float
    l1: float  # first Lyapunov coefficient
    a: float  # d Re(lambda) / d parameter
    radius: float  # r of z in x = x_H + z q + conj(z q), r^2 = -a dp / l1


def hopf_guess(system: System, parameter: str, value: float, state, *, radius: float = 0.05,
               dp: float | None = None, pars=None) -> HopfGuess:
    """Start of a periodic-orbit branch at a Hopf point (``value``, ``state`` of the equilibrium, corrected by
    Newton): critical eigenvector q and frequency omega of the Jacobian, first Lyapunov coefficient l1 and
    a = d Re lambda / dp from exact derivative tensors; the orbit of radius r lies at dp = -l1 r^2 / a
    (or at the given dp with r from the same relation, or r if l1 vanishes)."""
    k = system.parameter_index(parameter)
    field = system.field((), (k,))
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    pars[k] = value
    n = system.n
    x = np.asarray(state, dtype=float).copy()
    for _ in range(20):  # the equilibrium, by Newton at the given parameter value
        T1 = field.tensor(x, pars, 1)
        step = np.linalg.solve(T1[:, :n], -field.values(x, pars))
        x += step
        if np.max(np.abs(step)) < 1e-14 * (1 + np.max(np.abs(x))):
            break
    T1, T2 = field.tensor(x, pars, 1), field.tensor(x, pars, 2)
    J, B = T1[:, :n], T2[:, :n, :n]
    C = field.tensor(x, pars, 3, with_parameters=False)
    nf = normal_forms.first_lyapunov_coefficient(J, B, C)
    if abs(nf["eigenvalue"].real) > 1e-6 * max(1.0, nf["frequency"]):
        raise ParameterError(f"{system.name}: the critical eigenvalue at {parameter} = {value:g} is "
                             f"{nf['eigenvalue']:.4g}, not imaginary: give a Hopf point")
    q, p = nf["q"], nf["p"]
    x_p = -np.linalg.solve(J, T1[:, n])
    a = float(np.vdot(p, T2[:, :n, n] @ q + np.einsum("ijk,j,k->i", B, x_p, q)).real)
    l1 = nf["l1"]
    if dp is None:
        if abs(l1) < 1e-12:
            raise ParameterError(f"{system.name}: l1 = {l1:.2g} vanishes at the Hopf point (a Bautin point); give dp")
        dp = -l1 * radius ** 2 / a
    elif abs(l1) > 1e-12 and -a * dp / l1 > 0:
        radius = math.sqrt(-a * dp / l1)
    guess = x + 2 * (radius * q).real
    return HopfGuess(value + dp, guess, 2 * math.pi / nf["frequency"], value, x, nf["frequency"], l1, a, radius)


def orbit_from_hopf(system: System, parameter: str, value: float, state, *, radius: float = 0.05,
                    pars=None, **newton) -> tuple[PeriodicOrbit, HopfGuess]:
    """The periodic orbit of radius ~``radius`` born at the Hopf point (Newton from :func:`hopf_guess`)."""
    g = hopf_guess(system, parameter, value, state, radius=radius, pars=pars)
    p = np.array(system.pars if pars is None else pars, dtype=float)
    p[system.parameter_index(parameter)] = g.value
    orbit = find_orbit(system, g.state, g.period, p, **newton)
    orbit.value, orbit.parameter = g.value, parameter
    return orbit, g


def simulation_guess(system: System, state, pars=None, *, index: int = 0, level: float | None = None,
                     transient: float = 100.0, max_time: float = 1000.0, dt: float = 0.01,
                     tol: float = TAYLOR_TOL):
    """(state, return time) of a Poincaré return of a simulation: after ``transient``, two successive upward
    crossings of x[index] = level (default: the value at the end of the transient), located by Newton on
    the crossing time from samples ``dt`` apart."""
    flow = Flow(system, tol)
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    x = np.asarray(state, dtype=float)
    if transient > 0:
        x = flow.advance(x, transient, pars)
    level = float(x[index]) if level is None else float(level)
    crossings: list = []
    t0, n_grid = 0.0, 1000
    while t0 < max_time and len(crossings) < 2:
        times = dt * np.arange(n_grid + 1)
        states = flow.trajectory(x, times, pars)
        g = states[:, index] - level
        for j in np.flatnonzero((g[:-1] < 0) & (g[1:] >= 0)):
            s = times[j] + dt * (-g[j]) / (g[j + 1] - g[j])
            for _ in range(30):
                z = flow.advance(x, s, pars)
                ds = -(z[index] - level) / flow.rhs(z, pars)[index]
                s += ds
                if abs(ds) < 1e-15 * (1 + s):
                    break
            crossings.append((t0 + s, flow.advance(x, s, pars)))
            if len(crossings) == 2:
                break
        x, t0 = states[-1], t0 + times[-1]
    if len(crossings) < 2:
        raise ParameterError(f"{system.name}: no two crossings of {system.state_names[index]} = {level:g} within "
                             f"{max_time:g} time units after the transient; choose another section or start")
    (ta, xa), (tb, _xb) = crossings
    return xa, tb - ta

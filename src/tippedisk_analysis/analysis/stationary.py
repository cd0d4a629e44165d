"""Stationary spinning solutions (Sect. 6, Fig. 6): equilibria of the reduced system (:mod:`.reduced`).

Stationary solutions (Fig. 6, spinning about the vertical through C1, G and S, no slip):

* noninverted: beta = pi/2, gamma = -pi/2 (S below G), omega = (-Omega, 0, 0), u = 0;
* inverted:    beta = pi/2, gamma = +pi/2 (S above G), omega = (+Omega, 0, 0), u = 0;

for every spin rate alpha_dot = Omega (by (3.3) with beta_dot = gamma_dot = 0). They form
one-parameter families in Omega; :func:`solve` finds an equilibrium near a guess with a
prescribed alpha_dot = Omega by Newton's method and returns a status instead of raising.

Other equilibria do not exist for mu > 0, eps > 0 and lambda_N > 0: at an equilibrium the
energy is constant, so the friction power -mu lambda_N |gamma_T|^2 / (|gamma_T| + eps) vanishes,
the slip and hence the friction force are zero; S then keeps its horizontal velocity, which in
the turning frame means it is at rest; the disk rotates about the vertical through S, C1 is at rest
on that axis, the normal force exerts no moment about S, and steady rotation without moment is
about a principal axis: e_x^B vertical, i.e. the two families above (docs/continuation.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..defaults import NEWTON_MAX_ITER, NEWTON_TOL
from ..errors import ParameterError
from ..models import ode
from .reduced import N_STATE, OMEGA_X_INDEX, alpha_dot_gradient, evaluate, jacobian

__all__ = ["stationary_state", "Equilibrium", "solve"]

BRANCHES = {"noninverted": -1.0, "inverted": +1.0}  # sign of gamma = sign * pi/2 (Fig. 6)


def stationary_state(branch: str, omega) -> np.ndarray:
    """Closed-form stationary solution of ``branch`` at spin rate(s) ``omega`` [rad/s], shape (7, N).

    beta = pi/2, gamma = sign pi/2, omega_B = (sign Omega, 0, 0) by (3.3) with
    beta_dot = gamma_dot = 0, u = 0 (G, S and C1 lie on the spin axis, so v_G = -Omega x r_GC1 = 0).
    d state / d Omega = sign e_{omega_x}: the family direction.
    """
    sign = branch_sign(branch)
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    x = np.zeros((N_STATE, omega.size))
    x[0] = 0.5 * math.pi
    x[1] = sign * 0.5 * math.pi
    x[OMEGA_X_INDEX] = sign * omega
    return x


def branch_sign(branch: str) -> float:
    if branch not in BRANCHES:
        raise ParameterError(f"unknown branch {branch!r}; choose one of {', '.join(BRANCHES)}")
    return BRANCHES[branch]


@dataclass(frozen=True)
class Equilibrium:
    """Result of :func:`solve`: a status, never an exception, so sweeps can flag failures."""

    state: np.ndarray  # (7,), reduced.STATE_NAMES order (the last iterate if not converged)
    status: str  # "converged", "no_equilibrium", "max_iter", "singular", "nonfinite", "lift_off"
    message: str
    residual: float  # max |rhs| at ``state``, scaled: [rad/s, rad/s, m/s^2, m/s^2, rad/s^2...] mixed
    iterations: int
    lambda_N: float  # normal force [N]

    @property
    def converged(self) -> bool:
        return self.status == "converged"


def solve(guess, omega: float, pars=None, *, tol: float = NEWTON_TOL, max_iter: int = NEWTON_MAX_ITER) -> Equilibrium:
    """Newton (Gauss-Newton on the overdetermined system) for an equilibrium of the reduced system.

    Unknowns: the 7 reduced states. Equations: rhs = 0 (7) and alpha_dot = omega (1); the
    extra equation pins the member of the spin family (without it the Jacobian is singular
    along d/dOmega). The step solves the 8x7 linear least-squares problem with the exact
    Jacobian (:mod:`.stability`), which converges quadratically to a zero-residual solution.
    Converged when the step is below ``tol`` (relative) and the residual is at round-off level
    (``1e-12 |J| (1 + |x|)``). Otherwise the status says why: "no_equilibrium" (Gauss-Newton
    stalled at a least-squares minimum with a finite residual), "max_iter", "singular"
    (rank-deficient step), "nonfinite", or "lift_off" (converged with lambda_N <= 0: outside the
    bilateral model).
    """
    pars = ode.parameter_vector() if pars is None else np.asarray(pars, dtype=float)
    x = np.array(guess, dtype=float).reshape(N_STATE)
    if not (np.all(np.isfinite(x)) and math.isfinite(omega)):
        raise ParameterError("guess and omega must be finite numbers; give a finite initial state")
    status, message, it = "max_iter", f"no equilibrium within {max_iter} Newton steps of the guess", 0
    res = math.inf
    for it in range(1, max_iter + 1):
        F, J = _newton_system(x, omega, pars)
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(J))):
            status, message = "nonfinite", "the equations are not finite at the iterate (sin(beta) -> 0?)"
            break
        res = float(np.max(np.abs(F)))
        step, _resid, rank, _sv = np.linalg.lstsq(J, -F, rcond=None)
        if rank < N_STATE:
            status, message = "singular", "the Newton matrix is rank deficient; try another guess"
            break
        x = x + step
        if np.max(np.abs(step)) <= tol * (1.0 + np.max(np.abs(x))):
            F, J = _newton_system(x, omega, pars)
            res = float(np.max(np.abs(F)))
            # round-off level of the residual: |J| times the rounding of the state
            if res <= 1e-12 * np.abs(J).max() * (1.0 + np.max(np.abs(x))):
                status, message = "converged", f"converged in {it} Newton steps, residual {res:.2e}"
            else:
                status = "no_equilibrium"
                message = (f"Newton stalled at a least-squares minimum with residual {res:.3g}: "
                           "no equilibrium near the guess")
            break
    else:  # max_iter: report the residual at the returned iterate, not at the one before it
        res = float(np.max(np.abs(_newton_system(x, omega, pars)[0])))
    lam = float(evaluate(x, pars)["lambda_N"][0]) if np.all(np.isfinite(x)) else math.nan
    if status == "converged" and not lam > 0:
        status, message = "lift_off", f"equilibrium has lambda_N = {lam:.3g} N <= 0: the contact would open"
    return Equilibrium(x, status, message, res, it, lam)


def _newton_system(x, omega, pars):
    """Residual (8,) and its Jacobian (8, 7): rhs = 0 and alpha_dot = omega."""
    ev = evaluate(x, pars)
    F = np.append(ev["rhs"][:, 0], ev["alpha_dot"][0] - omega)
    J = np.vstack([jacobian(x, pars)[0], alpha_dot_gradient(x, pars)])
    return F, J

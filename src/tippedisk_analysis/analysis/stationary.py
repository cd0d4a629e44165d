"""Stationary spinning solutions (Sect. 6, Fig. 6) as equilibria of a symmetry-reduced system.

The ODE Model 1 state (Sect. 4.1, :mod:`tippedisk_analysis.models.ode`) is
(x, y, z, alpha, beta, gamma, x_dot, y_dot, z_dot, omega_x, omega_y, omega_z, W_friction).
Its right-hand side does not depend on x, y (horizontal translation), alpha (rotation of
the whole motion about e_z^I, (3.1)) nor W_friction (an integral of the friction power),
so a spinning disk with alpha_dot = Omega is a *relative* equilibrium: alpha grows and
v_G turns with the disk. The reduction used here:

* drop x, y, alpha (cyclic) and W_friction (a quadrature);
* z = r sin(beta) and z_dot = r cos(beta) beta_dot: the bilateral constraint g_N1 = 0
  (2.12) and its derivative, which the acceleration-level constraint (4.9) keeps invariant;
* express the horizontal velocity of G in the R-frame, I turned by alpha about e_z^I (3.1):
  u = (e_x^R . v_G, e_y^R . v_G), i.e. u_x = cos(alpha) x_dot + sin(alpha) y_dot,
  u_y = -sin(alpha) x_dot + cos(alpha) y_dot. Differentiating in the turning frame,
  u_x_dot = a_x^R + alpha_dot u_y and u_y_dot = a_y^R - alpha_dot u_x.

Reduced state (STATE_NAMES): (beta, gamma, u_x, u_y, omega_x, omega_y, omega_z), seven
first-order equations. The right-hand side is *not* a second copy of the physics: it is
:func:`tippedisk_analysis.models.ode.system` for ODE Model 1 with alpha = 0 substituted
(where the R-frame and the I-frame coincide, so a_G in I equals a_G in R), x_dot -> u_x,
y_dot -> u_y, z -> r sin(beta), z_dot -> r cos(beta) beta_dot, plus the turning-frame terms
above; beta_dot, gamma_dot and alpha_dot are the inverse of (3.3) from the same module.

Stationary solutions (Fig. 6, spinning about the vertical through C1, G and S, no slip):

* noninverted: beta = pi/2, gamma = -pi/2 (S below G), omega = (-Omega, 0, 0), u = 0;
* inverted:    beta = pi/2, gamma = +pi/2 (S above G), omega = (+Omega, 0, 0), u = 0;

for every spin rate alpha_dot = Omega (by (3.3) with beta_dot = gamma_dot = 0). They form
one-parameter families in Omega; :func:`solve` finds an equilibrium near a guess with a
prescribed alpha_dot = Omega by Newton's method and returns a status instead of raising.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from ..errors import ParameterError
from ..models import ode
from ..parameters import Setup

STATE_NAMES = ("beta", "gamma", "u_x", "u_y", "omega_x", "omega_y", "omega_z")
BRANCHES = {"noninverted": -1.0, "inverted": +1.0}  # sign of gamma = sign * pi/2 (Fig. 6)
OMEGA_X_INDEX = STATE_NAMES.index("omega_x")  # the direction of the spin family, see stationary_state


@dataclass(frozen=True)
class ReducedSystem:
    """Heyoka expressions of the reduced dynamics (module docstring)."""

    variables: list  # heyoka variables, STATE_NAMES order
    rhs: list  # d/dt of the variables
    alpha_dot: object  # spin rate about e_z^I (inverse of (3.3)) [rad/s]
    lambda_N: object  # normal force at C1 [N]
    slip: list  # gamma_T1 in the R-frame [m/s]


@functools.lru_cache(maxsize=None)
def reduced_system() -> ReducedSystem:
    """Build the reduced right-hand side from ODE Model 1's expressions (alpha = 0 substituted)."""
    full_vars, sys, _fall, outputs = ode.system(ode.EULER)
    names = ode.EULER.state_names
    rhs_full = dict(zip(names, (rhs for _var, rhs in sys)))
    out = dict(zip(ode.OUTPUT_NAMES, outputs))
    beta, gamma, u_x, u_y, w_x, w_y, w_z = variables = hy.make_vars(*STATE_NAMES)
    r = ode.P["r"]
    _alpha_dot, beta_dot, _gamma_dot = ode.kin.euler_rate_entries_from_omega(beta, gamma, w_x, w_y, w_z, xp=hy)
    subs = {
        "x": hy.expression(0.0), "y": hy.expression(0.0), "alpha": hy.expression(0.0),  # cyclic
        "z": r * hy.sin(beta),  # g_N1 = 0 (2.12)
        "z_dot": r * hy.cos(beta) * beta_dot,  # g_N1_dot = 0
        "x_dot": u_x, "y_dot": u_y,  # alpha = 0: R-frame = I-frame
        "W_friction": hy.expression(0.0),
    }

    def reduce(expr):
        return hy.subs(expr, subs)

    alpha_dot = reduce(rhs_full["alpha"])
    rhs = [
        reduce(rhs_full["beta"]),
        reduce(rhs_full["gamma"]),
        reduce(rhs_full["x_dot"]) + alpha_dot * u_y,  # d/dt (e_x^R . v_G)
        reduce(rhs_full["y_dot"]) - alpha_dot * u_x,  # d/dt (e_y^R . v_G)
        reduce(rhs_full["omega_x"]),
        reduce(rhs_full["omega_y"]),
        reduce(rhs_full["omega_z"]),
    ]
    return ReducedSystem(list(variables), rhs, alpha_dot, reduce(out["lambda_N"]),
                         [reduce(out["slip_x"]), reduce(out["slip_y"])])


@functools.lru_cache(maxsize=None)
def _rhs_cfunc():
    red = reduced_system()
    return hy.cfunc([*red.rhs, red.alpha_dot, red.lambda_N, *red.slip], red.variables)


def parameter_vector(setup: Setup | None = None, slip_smoothing: float = 1e-12) -> np.ndarray:
    """Runtime parameters in the order of ode.PARAMETER_NAMES (fall_angle unused here)."""
    from ..solvers.taylor import parameter_values

    return parameter_values(setup or Setup(), fall_angle=0.1, slip_smoothing=slip_smoothing)


def _pars_block(pars: np.ndarray, n: int, nparams: int) -> np.ndarray:
    pars = np.asarray(pars, dtype=float)
    if pars.ndim == 1:
        pars = np.repeat(pars[:, None], n, axis=1)
    return np.ascontiguousarray(pars[:nparams])


def call_batch(cf, states: np.ndarray, pars) -> np.ndarray:
    """Evaluate a heyoka cfunc on states (nvars, N) with pars (npars,) or (npars, N)."""
    states = np.ascontiguousarray(states, dtype=float)
    if cf.nparams == 0:
        return cf(states)
    return cf(states, pars=_pars_block(pars, states.shape[1], cf.nparams))


def evaluate(states, pars) -> dict[str, np.ndarray]:
    """Reduced right-hand side and diagnostics in a batch.

    states: shape (7,) or (7, N) in STATE_NAMES order; pars: (11,) or (11, N)
    (ode.PARAMETER_NAMES order, see :func:`parameter_vector`). Returns ``rhs`` (7, N),
    ``alpha_dot``, ``lambda_N`` [N] and ``slip`` (2, N) [m/s].
    """
    cf = _rhs_cfunc()
    x = np.atleast_2d(np.asarray(states, dtype=float).T).T
    x = np.ascontiguousarray(x.reshape(len(STATE_NAMES), -1))
    out = call_batch(cf, x, pars)
    return {"rhs": out[:7], "alpha_dot": out[7], "lambda_N": out[8], "slip": out[9:11]}


def stationary_state(branch: str, omega) -> np.ndarray:
    """Closed-form stationary solution of ``branch`` at spin rate(s) ``omega`` [rad/s], shape (7, N).

    beta = pi/2, gamma = sign pi/2, omega_B = (sign Omega, 0, 0) by (3.3) with
    beta_dot = gamma_dot = 0, u = 0 (G, S and C1 lie on the spin axis, so v_G = -Omega x r_GC1 = 0).
    d state / d Omega = sign e_{omega_x}: the family direction.
    """
    sign = _branch_sign(branch)
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    x = np.zeros((len(STATE_NAMES), omega.size))
    x[0] = 0.5 * math.pi
    x[1] = sign * 0.5 * math.pi
    x[OMEGA_X_INDEX] = sign * omega
    return x


def _branch_sign(branch: str) -> float:
    if branch not in BRANCHES:
        raise ParameterError(f"unknown branch {branch!r}; choose one of {', '.join(BRANCHES)}")
    return BRANCHES[branch]


@dataclass(frozen=True)
class Equilibrium:
    """Result of :func:`solve`: a status, never an exception, so sweeps can flag failures."""

    state: np.ndarray  # (7,), STATE_NAMES order (the last iterate if not converged)
    status: str  # "converged", "no_equilibrium", "max_iter", "singular", "nonfinite", "lift_off"
    message: str
    residual: float  # max |rhs| at ``state``, scaled: [rad/s, rad/s, m/s^2, m/s^2, rad/s^2...] mixed
    iterations: int
    lambda_N: float  # normal force [N]

    @property
    def converged(self) -> bool:
        return self.status == "converged"


def solve(guess, omega: float, pars=None, *, tol: float = 1e-12, max_iter: int = 30) -> Equilibrium:
    """Newton (Gauss-Newton on the overdetermined system) for an equilibrium of the reduced system.

    Unknowns: the 7 reduced states. Equations: rhs = 0 (7) and alpha_dot = omega (1); the
    extra equation pins the member of the spin family (without it the Jacobian is singular
    along d/dOmega). The step solves the 8x7 linear least-squares problem with the exact
    Jacobian (:mod:`.stability`), which converges quadratically to a zero-residual solution.
    Converged when the step is below ``tol`` (relative) and the residual is at round-off level
    (1e-12 |J| (1 + |x|)). Otherwise the status says why: "no_equilibrium" (Gauss-Newton
    stalled at a least-squares minimum with a finite residual), "max_iter", "singular"
    (rank-deficient step), "nonfinite", or "lift_off" (converged with lambda_N <= 0: outside the
    bilateral model).
    """
    pars = parameter_vector() if pars is None else np.asarray(pars, dtype=float)
    x = np.array(guess, dtype=float).reshape(len(STATE_NAMES))
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
        if rank < len(STATE_NAMES):
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
    lam = float(evaluate(x, pars)["lambda_N"][0]) if np.all(np.isfinite(x)) else math.nan
    if status == "converged" and not lam > 0:
        status, message = "lift_off", f"equilibrium has lambda_N = {lam:.3g} N <= 0: the contact would open"
    return Equilibrium(x, status, message, res, it, lam)


def _newton_system(x, omega, pars):
    """Residual (8,) and its Jacobian (8, 7): rhs = 0 and alpha_dot = omega."""
    from .stability import jacobian

    ev = evaluate(x, pars)
    F = np.append(ev["rhs"][:, 0], ev["alpha_dot"][0] - omega)
    J = np.vstack([jacobian(x, pars)[0], _alpha_dot_gradient(x, pars)])
    return F, J


@functools.lru_cache(maxsize=None)
def _alpha_dot_grad_cfunc():
    red = reduced_system()
    grad = hy.diff_tensors([red.alpha_dot], diff_args=red.variables, diff_order=1).jacobian
    return hy.cfunc(list(np.asarray(grad).ravel()), red.variables)


def _alpha_dot_gradient(x, pars) -> np.ndarray:
    cf = _alpha_dot_grad_cfunc()
    return call_batch(cf, np.asarray(x, dtype=float).reshape(-1, 1), pars)[:, 0]


def reduced_from_full(alpha, beta, gamma, x_dot, y_dot, omega_x, omega_y, omega_z) -> np.ndarray:
    """Reduced states (7, N) from ODE Model 1 states (e.g. a simulation dataset's variables):
    u = (e_x^R . v_G, e_y^R . v_G) with the R-frame turned by alpha about e_z^I (3.1)."""
    alpha = np.asarray(alpha, dtype=float)
    ca, sa = np.cos(alpha), np.sin(alpha)
    u_x = ca * np.asarray(x_dot) + sa * np.asarray(y_dot)
    u_y = -sa * np.asarray(x_dot) + ca * np.asarray(y_dot)
    return np.atleast_2d(np.array([beta, gamma, u_x, u_y, omega_x, omega_y, omega_z], dtype=float).T).T.reshape(
        len(STATE_NAMES), -1)

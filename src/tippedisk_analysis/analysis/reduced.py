"""The symmetry-reduced system of ODE Model 1 (declared in :mod:`tippedisk_analysis.models.reduced`): its
right-hand side and exact derivatives.

The ODE Model 1 state (Sect. 4.1, :mod:`tippedisk_analysis.models.ode`) is
(x, y, alpha, beta, gamma, x_dot, y_dot, omega_x, omega_y, omega_z, W_friction); the height of G
and its rate follow from the contact, z = r sin(beta) and z_dot = r cos(beta) beta_dot.
Its right-hand side does not depend on x, y (horizontal translation), alpha (rotation of
the whole motion about e_z^I, (3.1)) nor W_friction (an integral of the friction power),
so a spinning disk with alpha_dot = Omega is a *relative* equilibrium: alpha grows and
v_G turns with the disk. The reduction used here:

* drop x, y, alpha (cyclic) and W_friction (a quadrature);
* express the horizontal velocity of G in the R-frame, I turned by alpha about e_z^I (3.1):
  u = (e_x^R . v_G, e_y^R . v_G), i.e. u_x = cos(alpha) x_dot + sin(alpha) y_dot,
  u_y = -sin(alpha) x_dot + cos(alpha) y_dot. Differentiating in the turning frame,
  u_x_dot = a_x^R + alpha_dot u_y and u_y_dot = a_y^R - alpha_dot u_x.

Reduced state (STATE_NAMES): (beta, gamma, u_x, u_y, omega_x, omega_y, omega_z), seven
first-order equations. The right-hand side is *not* a second copy of the physics: it is
:func:`tippedisk_analysis.models.ode.system` for ODE Model 1 with alpha = 0 substituted
(where the R-frame and the I-frame coincide, so a_G in I equals a_G in R), x_dot -> u_x,
y_dot -> u_y, plus the turning-frame terms above; beta_dot, gamma_dot and alpha_dot are the
inverse of (3.3) from the same module.

Derivatives are exact: heyoka differentiates the expressions symbolically (``hy.diff_tensors``)
and the System compiles them once per process (cached on disk by heyoka): the Jacobian for
stability (:mod:`.stability`), and (:func:`field`) the tensors up to third order, including
derivatives with respect to the runtime parameters, for continuation and normal forms.
Every function evaluates in batches: states (7, N), parameters (11,) or (11, N) in the order of
:data:`tippedisk_analysis.models.ode.PARAMETER_NAMES` (:func:`tippedisk_analysis.models.ode.parameter_vector`).
"""

from __future__ import annotations

import functools

import heyoka as hy
import numpy as np

from ..dynamics.tensors import Field
from ..models.reduced import N_STATE, SLIP_NORM_INDEX, STATE_NAMES, reduced_system, system

__all__ = ["system", "evaluate", "jacobian", "reduced_from_full", "full_from_reduced"]

# runtime parameters the derivative tensors differentiate by (continuation parameters and the inertia)
TENSOR_PARAMETERS = ("mu", "eps", "e", "A", "B", "C")
OMEGA_X_INDEX = STATE_NAMES.index("omega_x")  # the direction of the spin family (stationary.stationary_state)


@functools.lru_cache(maxsize=None)  # the System caches by expression text: fetch it once
def _rhs_cfunc():
    red = reduced_system()
    return system().function("rhs and diagnostics", [*red.rhs, red.alpha_dot, red.lambda_N, *red.slip])


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
    x = np.ascontiguousarray(x.reshape(N_STATE, -1))
    out = call_batch(cf, x, pars)
    return {"rhs": out[:7], "alpha_dot": out[7], "lambda_N": out[8], "slip": out[9:11]}


@functools.lru_cache(maxsize=None)  # the System caches by expression text: fetch it once
def _jacobian_cfunc():
    return system().jacobian_function()


def jacobian(states, pars) -> np.ndarray:
    """Exact Jacobian d rhs / d state of the reduced system, shape (N, 7, 7).

    states: (7,) or (7, N) in STATE_NAMES order; pars: (11,) or (11, N), ode.PARAMETER_NAMES order.
    """
    x = np.asarray(states, dtype=float).reshape(N_STATE, -1)
    out = call_batch(_jacobian_cfunc(), x, pars)  # (49, N), row-major J[i, j]
    return out.T.reshape(-1, N_STATE, N_STATE)


@functools.lru_cache(maxsize=None)  # the System caches by expression text: fetch it once
def _alpha_dot_grad_cfunc():
    return system().function("alpha_dot gradient", system().gradient_expressions([reduced_system().alpha_dot]))


def alpha_dot_gradient(x, pars) -> np.ndarray:
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


def full_from_reduced(state, *, alpha: float = 0.0) -> np.ndarray:
    """ODE Model 1 state (ode.EULER.state_names) from a reduced state (7,): x = y = 0, the given alpha,
    horizontal v_G from u turned by alpha (3.1), W_friction = 0. The inverse of :func:`reduced_from_full`."""
    beta, gamma, u_x, u_y, w_x, w_y, w_z = np.asarray(state, dtype=float)
    ca, sa = np.cos(alpha), np.sin(alpha)
    return np.array([0.0, 0.0, alpha, beta, gamma, ca * u_x - sa * u_y, sa * u_x + ca * u_y, w_x, w_y, w_z, 0.0])


def field() -> Field:
    """The reduced right-hand side (7 outputs) and alpha_dot (output 7) with exact derivative tensors
    with respect to the 7 states and the runtime parameters TENSOR_PARAMETERS (in that order)."""
    return system().field(("alpha_dot",), TENSOR_PARAMETERS)


def parameter_derivative_index(name: str) -> int:
    """Position of runtime parameter ``name`` among the arguments of ``field().tensor``."""
    return N_STATE + TENSOR_PARAMETERS.index(name)


@functools.lru_cache(maxsize=None)
def _split_fields() -> tuple[Field, Field]:
    split = reduced_system(split_slip_norm=True)
    red = reduced_system()
    return Field(split.rhs, split.variables, [hy.par[SLIP_NORM_INDEX]]), Field(red.slip, red.variables)


def nonsmooth_split(state, pars) -> tuple[np.ndarray, np.ndarray]:
    """The non-smooth quadratic term of the reduced rhs at a zero-slip state: (G_xs (7, 7), Gamma (2, 7)).

    The law (2.29) depends on |gamma_T|, which is not differentiable at zero slip, so the rhs is
    only C^1 there: f(x* + w) = J w + B(w, w) / 2 + N(w) + O(|w|^3) with the odd, degree-two term
    N(w) = (G_xs w) |Gamma w|, G_xs = d^2 f / dx d|gamma_T| (f written with |gamma_T| as a separate
    argument) and Gamma = d gamma_T / dx. (The model's analytic |gamma_T| = sqrt(|gamma_T|^2 +
    delta^2) - delta has zero slope at zero slip, so B is the smooth part.) Exact derivatives.
    """
    split, slip = _split_fields()
    pars_split = np.append(np.asarray(pars, dtype=float)[: SLIP_NORM_INDEX], 0.0)
    T2 = split.tensor(state, pars_split, 2)
    return T2[:, :N_STATE, N_STATE], slip.tensor(state, pars, 1)

"""The critical spin in closed form: the spin above which friction damps the nutation of the inverted disk.

Linearise the slow flow (:mod:`tippedisk_analysis.models.slow_flow`, (S1)-(S3)) at the inverted spin
(beta = pi/2, gamma = pi/2, omega = (Omega, 0, 0): upright, S straight above G). omega_x is the family of
spins (a zero eigenvalue); on (beta, gamma, omega_y, omega_z) the Jacobian is exactly K0 + eps K1
(:func:`spin_matrices`: K0 the rolling disk's, K1 the first-order slip's, proportional to 1/mu). Its
characteristic polynomial, to first order in eps, is

    lambda^4 + eps a3 lambda^3 + c2 lambda^2 + eps a1 lambda + c0,                                (C1)

with the rolling coefficients c2, c0 and the friction coefficients a3, a1 (:func:`coefficients`). Rolling
(eps = 0) has the pairs +-i nu_1, +-i nu_2 with

    nu^2 = (c2 -+ sqrt(c2^2 - 4 c0)) / 2                                                          (C2)

where c2^2 > 4 c0 (above the spin where the two pairs collide). Friction gives each pair the real part

    Re lambda = -eps (a1 - a3 nu^2) / (2 (c2 - 2 nu^2)) + O(eps^2).                                (C3)

The critical spin omega_c is where the nutation (the slower pair, nu_1) turns from growing to damped:

    a1 = a3 nu_1^2,   equivalently   a1^2 - c2 a1 a3 + c0 a3^2 = 0 (a cubic in Omega^2).              (C4)

a1 and a3 are both proportional to 1/mu and (C4) is homogeneous in them: omega_c depends on m, e, r, A, B, C
and g only, not on mu or eps. The other pair (the precession, nu_2) grows above omega_c: the inverted spin
itself is never asymptotically stable. The free disk stays near it for a slow time of order 1/eps and falls
(:mod:`.spin_passage`).

The nutation is damped above omega_c only while it oscillates. c0 = nu_1^2 nu_2^2 is a quadratic in Omega^2,

    c0 = P Omega^4 + Q Omega^2 + R,   P = -(C_C - A)(A - B - m r e) / (B_C C_C)                   (C6)

(:func:`stiffness_coefficients`), and where it turns negative nu_1 has fallen to zero: the rolling inverted spin
turns into a saddle and two spins with the disk turned in its own plane branch off (a pitchfork). R > 0, so
for e < (A - B) / (m r) (P < 0) this happens at one spin, :func:`saddle_spins`, which ends the damped window.

From omega_c, the initial spin a start needs (C5, :func:`initial_spin_threshold`): the disk reaches the
inverted spin only with an energy E_spin(omega_c) = A omega_c^2 / 2 + m g (r + e) (rolling energy of
:mod:`tippedisk_analysis.models.rolling`), so the start's rolling energy must be at least that. Friction
dissipates on the way (power O(eps) for a time O(1/eps): an amount independent of eps), and the criterion
r + 0.8 e is passed below the inverted spin's energy: the two nearly cancel, so (C5) is not a bound but lands 3-6 %
below the full model's threshold on the disks checked (docs/inversion_criterion.md; the prediction that counts
friction's work, (C7): :mod:`.inversion_energy`).

:func:`derive` repeats the derivation in sympy from the package's own expressions
(``slow_flow.slow_dynamics``); tests check that it gives :func:`spin_matrices` exactly.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.optimize import brentq

from ..errors import ParameterError
from ..models import rolling, slow_flow
from ..parameters import Disk, InitialState, Setup
from ..results import make_attrs
from . import inversion
from .rolling import spin_state

__all__ = ["spin_matrices", "characteristic", "coefficients", "rates", "first_order_pairs",
           "stiffness_coefficients", "saddle_spins", "CriticalSpin", "omega_critical", "initial_spin_threshold",
           "prediction_map", "derive", "window_top", "check_spin", "check_against_jacobian"]

SCAN = (1.0, 400.0, 800)  # rad/s: omega_c is looked for on this grid of Omega (first growing -> damped change)
SADDLE_OFFSET = 1e-9  # relative: the grid also holds the spins this close to each saddle spin, either side


def spin_matrices(Omega, m, e, r, A, B, C, g, mu):
    """(K0, K1): the rolling and the first-order slip Jacobian (4 x 4 nested lists, rows and columns beta,
    gamma, omega_y, omega_z) of the slow flow at the inverted spin Omega [rad/s]; the slow flow's Jacobian is
    K0 + eps K1 exactly. Arithmetic only: numbers give numbers, sympy symbols give the closed form.
    B_C, C_C: the inertia about the tangent and the normal axis through the contact point; d = r + e, the
    height of S above it."""
    d = r + e
    B_C, C_C = B + m * r * (r + 2 * e), C + m * r * (r + 2 * e)
    K0 = [[0, -Omega, -1, 0],
          [Omega, 0, 0, 1],
          [-m * d * (Omega**2 * r + g) / B_C, 0, 0, Omega * (C_C - A - m * r * d) / B_C],
          [0, -m * (Omega**2 * r * d - e * g) / C_C, Omega * (A - B_C) / C_C, 0]]
    row2 = B_C**2 * C_C * g * mu
    row3 = B_C * C_C**2 * g * mu
    k21 = (Omega**3 * d * m * r * (A * d**2 * m - 2 * B_C * C_C + 2 * B_C * d**2 * m - B_C * d * m * r
                                   + d**3 * m**2 * r)
           + Omega * d * g * m**2 * (-A * d**2 + A * d * r - 2 * B_C * d**2 + 3 * B_C * d * r - B_C * r**2
                                     + 2 * C_C * d**2 - C_C * d * r - d**3 * m * r + d**2 * m * r**2)) / row2
    k22 = (C_C * d**3 * g * m**2
           - Omega**2 * d * m * (A**2 * d + A * B_C * d - A * B_C * r - A * C_C * d + A * d**2 * m * r - 2 * B_C**2 * d
                                 + B_C**2 * r + 2 * B_C * C_C * d + B_C * C_C * r - B_C * d**2 * m * r
                                 - C_C * d**2 * m * r)) / row2
    k30 = (-Omega**3 * d * m * r * (A * d**2 * m - 2 * B_C * C_C + 2 * C_C * d**2 * m)
           - Omega * d**2 * g * m**2 * (A * d - 2 * B_C * d + B_C * r + 2 * C_C * d)) / row3
    k33 = (B_C * d**2 * g * m**2 * e
           - Omega**2 * d * m * (A**2 * d - A * B_C * d + A * C_C * d + A * d**2 * m * r + 2 * B_C * C_C * d
                                 - 2 * B_C * C_C * r - 2 * C_C**2 * d + 2 * C_C * d**2 * m * r)) / row3
    K1 = [[0, 0, 0, 0], [0, 0, 0, 0], [0, k21, k22, 0], [k30, 0, 0, k33]]
    return K0, K1


def characteristic(K0, K1):
    """(c2, c0, a3, a1) of (C1): the characteristic polynomial of K0 + eps K1 to first order in eps, for 4 x 4
    matrices with the sparsity of :func:`spin_matrices` (K0: entries 01 02 10 13 20 23 31 32; K1: 21 22 30 33)."""
    (_, a01, a02, _), (a10, _, _, a13), (a20, _, _, a23), (_, a31, a32, _) = K0
    (_, b21, b22, _), (b30, _, _, b33) = K1[2:]
    c2 = -a01 * a10 - a02 * a20 - a13 * a31 - a23 * a32
    c0 = a01 * a10 * a23 * a32 - a01 * a13 * a20 * a32 - a02 * a10 * a23 * a31 + a02 * a13 * a20 * a31
    a3 = -(b22 + b33)
    a1 = (a01 * a10 * (b22 + b33) - a01 * a13 * b30 - a02 * a10 * b21 + a02 * a20 * b33 - a02 * a23 * b30
          + a13 * a31 * b22 - a13 * a32 * b21)
    return c2, c0, a3, a1


def coefficients(Omega, m, e, r, A, B, C, g, mu):
    """(c2, c0, a3, a1) of (C1) at the inverted spin Omega [rad/s]."""
    return characteristic(*spin_matrices(Omega, m, e, r, A, B, C, g, mu))


def stiffness_coefficients(m, e, r, A, B, C, g):
    """(P, Q, R) of the rolling coefficient c0 = P Omega^4 + Q Omega^2 + R of (C1) at the inverted spin (C6).
    Arithmetic only, as :func:`spin_matrices` (a test checks the identity with :func:`coefficients` in sympy)."""
    d = r + e
    B_C, C_C = B + m * r * (r + 2 * e), C + m * r * (r + 2 * e)
    P = -(C_C - A) * (A - B - m * r * e) / (B_C * C_C)
    Q = m * g * (e * (C_C - A - m * r * d) - d * (A - B_C) - m * d * r**2) / (B_C * C_C)
    R = m**2 * d * e * g**2 / (B_C * C_C)
    return P, Q, R


def saddle_spins(disk: Disk | None = None, gravity: float = 9.81) -> tuple[float, ...]:
    """The spins [rad/s], ascending, at which c0 of (C1) changes sign (C6): where it is negative the rolling
    inverted spin is a saddle (its nutation is a real pair), and at each such spin a pitchfork of spins turned
    in the disk's plane branches off. Empty when c0 > 0 at every spin, as for the Table 1-2 disk."""
    disk = Disk() if disk is None else disk
    P, Q, R = stiffness_coefficients(disk.m, disk.e, disk.r, disk.A, disk.B, disk.C, gravity)
    squares = np.roots([P, Q, R]) if P != 0 else np.array([-R / Q]) if Q != 0 else np.array([])
    real = [float(w2.real) for w2 in squares if abs(w2.imag) <= 1e-12 * abs(w2) and w2.real > 0]
    return tuple(sorted(math.sqrt(w2) for w2 in real))


def window_top(saddles, omega_c: float) -> float:
    """The first of ``saddles`` (:func:`saddle_spins`) above omega_c [rad/s]: where the damped window closes (NaN
    if it does not)."""
    return next((w for w in saddles if w > omega_c), math.nan)


def _values(disk: Disk, gravity: float, mu: float) -> dict:
    return dict(m=disk.m, e=disk.e, r=disk.r, A=disk.A, B=disk.B, C=disk.C, g=gravity, mu=mu)


def rates(Omega: float, disk: Disk | None = None, gravity: float = 9.81, mu: float = 0.3) -> dict:
    """The rolling frequencies nu [rad/s] (C2) and the first-order real parts per eps [1/m] (C3) of the
    nutation (slower pair) and the precession (faster pair) at the inverted spin; NaN where the rolling spin is
    not elliptic (c2^2 < 4 c0: below the collision of the pairs; or c0, c2 < 0: real eigenvalues)."""
    disk = Disk() if disk is None else disk
    c2, c0, a3, a1 = coefficients(float(Omega), **_values(disk, gravity, mu))
    disc = c2 * c2 - 4 * c0
    if disc < 0 or c0 < 0 or c2 < 0:  # not four imaginary eigenvalues
        nan = float("nan")
        return {"nu_nutation": nan, "nu_precession": nan, "rate_nutation": nan, "rate_precession": nan}
    (nu_1, rate_1), (nu_2, rate_2) = first_order_pairs(c2, c0, a3, a1)
    return {"nu_nutation": nu_1, "nu_precession": nu_2, "rate_nutation": rate_1, "rate_precession": rate_2}


def first_order_pairs(c2, c0, a3, a1) -> tuple:
    """((nu_1, rate_1), (nu_2, rate_2)) of (C1) with c2, c0 > 0 and c2^2 > 4 c0: the frequencies (C2), slower
    first, and Re lambda / eps of each pair (C3)."""
    root = math.sqrt(c2 * c2 - 4 * c0)
    return tuple((math.sqrt(n2), -(a1 - a3 * n2) / (2 * (c2 - 2 * n2))) for n2 in ((c2 - root) / 2, (c2 + root) / 2))


@dataclass(frozen=True)
class CriticalSpin:
    """omega_c [rad/s] (C4) of a disk, with the nutation's frequency and the precession's rate there (C3, per
    eps), the spin above which the precession grows (``omega_precession``, NaN if it does not turn on SCAN), the
    spins where the rolling inverted spin turns into a saddle or back (``saddle_spins``, (C6): the damped window
    above omega_c ends at the next one) and ``status``: completed; no_crossing (the nutation does not turn from
    growing to damped on SCAN) or not_elliptic (the rolling inverted spin is a saddle at every Omega on SCAN),
    both with omega_c NaN."""

    omega_critical: float
    nu_nutation: float  # rad/s, the nutation frequency at omega_c
    rate_precession: float  # 1/m: Re lambda / eps of the precession at omega_c (> 0: it grows)
    omega_precession: float  # rad/s: the precession pair turns from damped to growing there
    saddle_spins: tuple  # rad/s: c0 of (C1) changes sign there (C6)
    status: str
    message: str


def _first_turn(rate, grid: np.ndarray, values: np.ndarray, growing_to_damped: bool) -> float:
    """The first zero of ``rate`` on ``grid`` where its sign changes the given way (NaN if none)."""
    sign = -1.0 if growing_to_damped else 1.0
    change = np.flatnonzero((sign * values[:-1] < 0) & (sign * values[1:] > 0))
    if change.size == 0:
        return float("nan")
    return float(brentq(rate, grid[change[0]], grid[change[0] + 1], xtol=1e-12, rtol=1e-14))


def omega_critical(disk: Disk | None = None, gravity: float = 9.81, mu: float = 0.3) -> CriticalSpin:
    """The critical spin omega_c (C4): the first Omega on SCAN where the nutation of the inverted spin turns
    from growing to damped, refined by Brent's method on (C3). Independent of mu and eps (module docstring);
    mu only scales the rate reported."""
    disk = Disk() if disk is None else disk
    for name, value, why in (("gravity", gravity, "in m/s^2"), ("mu", mu, "friction is what damps the nutation")):
        if not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
            raise ParameterError(f"{name} = {value!r}: the critical spin needs {name} > 0 ({why})")
    saddles = saddle_spins(disk, gravity)
    # the grid meets each saddle spin from both sides: a window closing there may be narrower than the grid's step
    edges = [w * (1 + side * SADDLE_OFFSET) for w in saddles for side in (-1, 1)]
    grid = np.unique(np.concatenate([np.linspace(*SCAN), [w for w in edges if SCAN[0] < w < SCAN[1]]]))

    def rate(key):
        return lambda w: rates(w, disk, gravity, mu)[key]

    nutation = np.array([rate("rate_nutation")(w) for w in grid])
    precession = np.array([rate("rate_precession")(w) for w in grid])
    w_p = _first_turn(rate("rate_precession"), grid, precession, growing_to_damped=False)
    span = f"{SCAN[0]:g}-{SCAN[1]:g} rad/s"
    nan = float("nan")
    if not np.isfinite(nutation).any():
        return CriticalSpin(nan, nan, nan, nan, saddles, "not_elliptic",
                            f"the rolling inverted spin has real eigenvalues at every Omega on {span}: no nutation "
                            "to damp, so the closed form gives no critical spin for this disk")
    w = _first_turn(rate("rate_nutation"), grid, nutation, growing_to_damped=True)
    if math.isnan(w):
        where = {1: f"above {saddles[0]:.4f} rad/s", 2: f"between {saddles[0]:.4f} and {saddles[-1]:.4f} rad/s"}
        saddle = f"; it is a saddle {where[len(saddles)]} (c0 < 0, (C6))" if saddles else ""
        return CriticalSpin(nan, nan, nan, w_p, saddles, "no_crossing",
                            f"the nutation of the inverted spin does not turn from growing to damped on {span}"
                            + saddle)
    at = rates(w, disk, gravity, mu)
    top = window_top(saddles, w)
    window = (f"from {w:.4f} up to {top:.4f} rad/s, where the rolling inverted spin turns into a saddle "
              "(c0 = 0, (C6))" if math.isfinite(top) else f"above {w:.4f} rad/s")
    return CriticalSpin(w, at["nu_nutation"], at["rate_precession"], w_p, saddles, "completed",
                        f"the nutation of the inverted spin is damped {window}")


def initial_spin_threshold(omega_c: float, setup: Setup | None = None, gamma0: float | None = None) -> float:
    """(C5) the initial spin [rad/s] of Table 3's start (gamma0 [rad]) whose rolling energy equals that of the
    inverted spin at omega_c (friction's losses neglected). Not a bound: friction's work and the lenient criterion
    r + 0.8 e nearly cancel, and it lands 3-6 % below the full model's threshold on the disks checked; a start with
    S above G can pass the criterion in one swing below it (docs/inversion_criterion.md)."""
    setup = Setup() if setup is None else setup
    gamma0 = InitialState().gamma if gamma0 is None else float(gamma0)
    inversion.check_start(setup, gamma0)
    if not (math.isfinite(omega_c) and omega_c > 0):
        raise ParameterError(f"omega_c = {omega_c} rad/s: give a positive finite critical spin")
    system = rolling.reduced_system()
    pars = rolling.parameter_vector(setup)

    def energy(state):
        return float(system.observe(state, pars)["E_tot"])

    e_spin = energy(spin_state("inverted", omega_c))
    e_rest = energy(inversion.start_state("slow", 0.0, setup, gamma0))
    e_unit = energy(inversion.start_state("slow", 1.0, setup, gamma0)) - e_rest  # kinetic energy at 1 rad/s
    # e_spin > e_rest: the start is upright (z_S <= r + e) and the spin has kinetic energy
    return math.sqrt((e_spin - e_rest) / e_unit)


@functools.lru_cache(maxsize=None)
def derive():
    """(symbols, K0, K1, K2) in sympy, derived from ``slow_flow.slow_dynamics`` (the package's slow flow) at the
    inverted spin: the state perturbed along each coordinate by t, differentiated in t at t = 0; K1 the
    derivative in eps, K0 the value at eps = 0, K2 the second derivative in eps (zero: the Jacobian is linear
    in eps). About 10 s."""
    import sympy as sp

    from ..models.ode import Trig

    names = ("m", "e", "r", "A", "B", "C", "gravity", "mu", "eps")
    symbols = {n: sp.Symbol("g" if n == "gravity" else n, positive=True) for n in names}
    symbols["Omega"] = sp.Symbol("Omega", positive=True)
    x = sp.symbols("beta gamma omega_x omega_y omega_z", real=True)
    trig = Trig(0, 1, sp.sin(x[0]), sp.cos(x[0]), sp.sin(x[1]), sp.cos(x[1]))
    delta = sp.Symbol("delta", positive=True)  # the force smoothing: drops out at the spin (lambda_T = 0)
    flow = slow_flow.slow_dynamics(list(x), trig, pars=symbols, sqrt=sp.sqrt, diff=sp.diff, smoothing=delta)
    spin = (sp.pi / 2, sp.pi / 2, symbols["Omega"], 0, 0)
    t = sp.Symbol("t")
    keep = (0, 1, 3, 4)  # beta, gamma, omega_y, omega_z (omega_x: the family of spins)
    J = sp.zeros(4, 4)
    for col, j in enumerate(keep):
        at = {x[k]: spin[k] + (t if k == j else 0) for k in range(5)}
        for row, i in enumerate(keep):
            J[row, col] = sp.diff(flow.rhs[i].subs(at), t).subs(t, 0)
    eps = symbols["eps"]
    K0 = J.subs(eps, 0).applyfunc(sp.simplify)
    K1 = J.diff(eps).subs(eps, 0).applyfunc(sp.simplify)
    return symbols, K0, K1, J.diff(eps, 2).applyfunc(sp.simplify)


CHECK_EPS_PER_MU = 3e-4  # m/s: the eps of the check over mu (the Jacobian depends on eps / mu only)


def check_spin(omega_c: float, disk: Disk | None = None, gravity: float = 9.81) -> float:
    """The spin [rad/s] :func:`check_against_jacobian` measures the nutation's size at: 1 rad/s above omega_c, or
    halfway to the damped window's top (C6) where that is nearer."""
    top = window_top(saddle_spins(disk, gravity), omega_c)
    return min(omega_c + 1.0, 0.5 * (omega_c + top)) if math.isfinite(top) else omega_c + 1.0


def check_against_jacobian(omega_c: float, setup: Setup | None = None) -> float:
    """The real part of the nutation pair of the slow flow's numerical Jacobian (heyoka) at the inverted spin
    omega_c, relative to its size at :func:`check_spin` (a little higher, inside the damped window), at eps =
    CHECK_EPS_PER_MU mu: zero to O(eps / mu) when (C4) is right (the answer checks itself), whatever the setup's
    mu."""
    setup = Setup() if setup is None else setup
    reference = check_spin(omega_c, setup.disk, setup.gravity)
    setup = inversion.with_eps(setup, CHECK_EPS_PER_MU * setup.friction.mu)
    system, pars = slow_flow.system(), inversion.parameters("slow", setup)

    def nutation_real(w):
        ev = np.linalg.eigvals(system.jacobian(spin_state("inverted", w), pars))
        oscillating = ev[np.abs(ev.imag) > 1e-9 * max(1.0, w)]
        return oscillating[np.argmin(np.abs(oscillating.imag))].real

    return float(nutation_real(omega_c) / abs(nutation_real(reference)))


MAP_FLAGS = {"completed": 0, "no_crossing": 1, "not_elliptic": 2, "no_disk": 3}
PADDING = -1.0


def prediction_map(e_values, r_values, *, base: Disk | None = None, gravity: float = 9.81,
                   gamma0: float | None = None) -> xr.Dataset:
    """omega_c (C4) and the initial spin threshold (C5) over eccentricity e [m] x radius r [m] (kind
    ``critical_spin_map``). ``base`` (default: the drilled disk of Sect. 5) gives the rest: a geometry moves its
    hole for each e (m, A, B, C recomputed; a point whose hole would leave the disk is ``no_disk``), a disk
    given by values keeps m and A, B, C about G. Points without a value hold -1 and say why in ``status``."""
    base = Disk.from_geometry() if base is None else base
    e_values, r_values = np.asarray(e_values, dtype=float), np.asarray(r_values, dtype=float)
    for name, values in (("e", e_values), ("r", r_values)):
        if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)) or np.any(values < 0):
            raise ParameterError(f"{name} values {values!r} [m]: give a non-empty 1-D array of finite values >= 0")
    shape = (e_values.size, r_values.size)
    omega_c, threshold = np.full(shape, PADDING), np.full(shape, PADDING)
    status = np.full(shape, MAP_FLAGS["no_disk"], dtype=np.int8)
    for j, r in enumerate(r_values):
        for i, e in enumerate(e_values):
            try:
                if base.geometry is not None:  # the hole offset that gives e on a disk of radius r
                    g = dataclasses.replace(base.geometry, r=float(r), b=0.5 * (float(r) - base.geometry.a))
                    disk = Disk.from_geometry(g.rho, g.r, g.a, g.offset_for(float(e)), g.h)
                else:
                    disk = dataclasses.replace(base, r=float(r), e=float(e))
            except ParameterError:
                continue
            found = omega_critical(disk, gravity)
            status[i, j] = MAP_FLAGS[found.status]
            if found.status == "completed":
                omega_c[i, j] = found.omega_critical
                threshold[i, j] = initial_spin_threshold(found.omega_critical, Setup(disk=disk, gravity=gravity),
                                                         gamma0)
    attrs = {"units": "rad s-1", "padding_value": PADDING, "comment": "-1: no value (status)"}
    ds = xr.Dataset(
        {"omega_critical": (("e", "r"), omega_c, {**attrs, "long_name": "critical spin (C4): the inverted spin's "
                                                   "nutation is damped above it"}),
         "initial_spin_threshold": (("e", "r"), threshold,
                                    {**attrs, "long_name": "initial spin of Table 3's start with the rolling energy "
                                                           "of the inverted spin at omega_c (C5)"}),
         "status": (("e", "r"), status, {"long_name": "what each point gave",
                                         "flag_values": np.array(list(MAP_FLAGS.values()), dtype=np.int8),
                                         "flag_meanings": " ".join(MAP_FLAGS)})},
        coords={"e": ("e", e_values, {"units": "m", "long_name": "eccentricity of S"}),
                "r": ("r", r_values, {"units": "m", "long_name": "disk radius"})})
    n_done = int((status == MAP_FLAGS["completed"]).sum())
    config = {"e": e_values.tolist(), "r": r_values.tolist(), "gravity": gravity,
              "gamma0": InitialState().gamma if gamma0 is None else gamma0,
              "base": "drilled geometry" if base.geometry is not None else dataclasses.asdict(base)}
    ds.attrs = make_attrs("critical_spin_map", config, "completed" if n_done else "no_value",
                          f"omega_c at {n_done} of {status.size} (e, r) points; the others: see status",
                          title="Critical spin of the tippedisk in closed form over eccentricity and radius")
    return ds

"""A zoo of systems a user might declare, none of them in the package's catalogue, with answers known exactly
or from an independent integrator (scipy's DOP853 at rtol = atol = 1e-12).

Each entry is declared as a user would: plain heyoka expressions (integer powers written ``x**3``), named
parameters, no state scales, no tuning. The references never call the package.
"""

from __future__ import annotations

import math

import heyoka as hy
import numpy as np
from scipy.integrate import solve_ivp

from tippedisk_analysis import dynamics as dy

x, y, z = hy.make_vars("x", "y", "z")
p0 = hy.par[0]


def duffing_vdp(mu: float = 1.0) -> dy.System:
    """x'' + mu (x^2 - 1) x' + x + x^3 / 2 = 0: a limit cycle for mu > 0, conservative at mu = 0."""
    return dy.System("duffing_vdp", [x, y], [y, -p0 * (x**2 - 1) * y - x - 0.5 * x**3], parameters={"mu": mu})


def van_der_pol(mu: float = 1.0) -> dy.System:
    """x'' - mu (1 - x^2) x' + x = 0 (a relaxation oscillator for large mu)."""
    return dy.System("vdp_user", [x, y], [y, p0 * (1 - x**2) * y - x], parameters={"mu": mu})


def bautin(mu: float = -0.5) -> dy.System:
    """Polar r' = r (mu + 2 r^2 - r^4), theta' = 1: a subcritical Hopf point at mu = 0 (l1 > 0); for -1 < mu < 0 a
    stable origin inside an unstable cycle r_u^2 = 1 - sqrt(1 + mu), inside a stable cycle r_s^2 = 1 + sqrt(1 + mu),
    both of period 2 pi."""
    r2 = x**2 + y**2
    g = 2 * r2 - r2**2
    return dy.System("bautin_user", [x, y], [p0 * x - y + g * x, x + p0 * y + g * y], parameters={"mu": mu})


def c1_hopf(mu: float = -0.1) -> dy.System:
    """Polar r' = r (mu - r), theta' = 1, r written sqrt(x^2 + y^2 + 1e-24) - 1e-12 (a user's smoothing of |x|): a
    Hopf point at mu = 0 of a field that is C^1 but not C^2 there, with stable cycles of radius mu (linear in mu,
    not sqrt: no first Lyapunov coefficient describes it), period 2 pi."""
    r = hy.sqrt(x**2 + y**2 + 1e-24) - 1e-12
    return dy.System("c1_hopf_user", [x, y], [p0 * x - y - r * x, x + p0 * y - r * y], parameters={"mu": mu})


def c2_hopf(mu: float = -0.5) -> dy.System:
    """x' = mu x - y + 3 relu(x)^3 - x^3, y' = x + mu y: C^2 but not C^3 at the origin, where the Hopf point's l1
    would take the third derivatives (-6 on one side, +12 on the other)."""
    r = hy.relu(x)
    return dy.System("c2_hopf_user", [x, y], [p0 * x - y + 3 * r * r * r - x * x * x, x + p0 * y],
                     parameters={"mu": mu})


def predator_prey(size: float = 1.0) -> dy.System:
    """Rosenzweig-MacArthur with densities of ``size`` (x = size X): X' = X (1 - X / mu) - X Y / (1 + X),
    Y' = 0.5 X Y / (1 + X) - 0.2 Y; a Hopf point at mu = 7/3 (the paradox of enrichment), smooth."""
    return dy.System("predator_prey_user", [x, y],
                     [x * (1 - x / (p0 * size)) - x * y / (size + x), 0.5 * x * y / (size + x) - 0.2 * y],
                     parameters={"mu": 2.0})


def generalised_hopf(mu: float = -0.1) -> dy.System:
    """r' = r (mu - r^4), theta' = 1: l1 = 0 at the Hopf point mu = 0, but not a centre: stable orbits of radius
    mu^(1/4) and period 2 pi for mu > 0."""
    r2 = x**2 + y**2
    return dy.System("gh_user", [x, y], [p0 * x - y - r2**2 * x, x + p0 * y - r2**2 * y], parameters={"mu": mu})


def escape() -> dy.System:
    """x' = -x + x^3, y' = -y: the origin attracts |x| < 1; |x| > 1 blows up in finite time; |x| = 1 is a saddle."""
    return dy.System("escape", [x, y], [-x + x**3, -y])


def pendulum(delta: float = 0.1) -> dy.System:
    """x'' + delta x' + sin x = 0: slow spirals into the equilibria 2 pi k."""
    return dy.System("pendulum_user", [x, y], [y, -p0 * y - hy.sin(x)], parameters={"delta": delta})


def double_well(delta: float = 0.15) -> dy.System:
    """x'' + delta x' - x + x^3 = 0: two stable foci (+-1, 0) and a saddle at the origin."""
    return dy.System("well_user", [x, y], [y, -p0 * y + x - x**3], parameters={"delta": delta})


def fitzhugh_nagumo(eps: float = 0.08) -> dy.System:
    """v' = v - v^3/3 - w + 0.5, w' = eps (v + 0.7 - 0.8 w): slow-fast, a relaxation cycle."""
    return dy.System("fhn_user", [x, y], [x - x**3 / 3 - y + 0.5, p0 * (x + 0.7 - 0.8 * y)], parameters={"eps": eps})


def chen(a: float = 35.0) -> dy.System:
    """Chen's system (a, b, c) = (35, 3, 28): chaos; the divergence -a - b + c = -10 is constant."""
    return dy.System("chen_user", [x, y, z], [p0 * (y - x), (28 - p0) * x - x * z + 28 * y, x * y - 3 * z],
                     parameters={"a": a})


def lorenz(rho: float = 15.0) -> dy.System:
    """Lorenz (sigma, beta) = (10, 8/3): for 1 < rho < 24.74 the pair C+- = (+-s, +-s, rho - 1), s = sqrt(beta (rho
    - 1)), is stable, the origin a saddle whose stable manifold holds the z-axis."""
    return dy.System("lorenz_user", [x, y, z], [10 * (y - x), x * (p0 - z) - y, x * y - 8 / 3 * z],
                     parameters={"rho": rho})


def roessler(c: float = 4.0) -> dy.System:
    """Roessler (a, b) = (0.2, 0.2): at c = 4 a stable period-4 orbit (four loops before it closes)."""
    return dy.System("roessler_user", [x, y, z], [-y - z, x + 0.2 * y, 0.2 + z * (x - p0)], parameters={"c": c})


def thomas(b: float = 0.208186) -> dy.System:
    """Thomas' cyclically symmetric system x' = sin y - b x (and cyclic): weak chaos at b = 0.208186 (largest
    exponent about 0.005, from a scipy DOP853 QR run over 8000 time units: 0.0048-0.0062); divergence -3b exactly."""
    return dy.System("thomas_user", [x, y, z], [hy.sin(y) - p0 * x, hy.sin(z) - p0 * y, hy.sin(x) - p0 * z],
                     parameters={"b": b})


def selkov(b: float = 0.6) -> dy.System:
    """Sel'kov's glycolysis model x' = -x + a y + x^2 y, y' = b - a y - x^2 y, a = 0.08."""
    return dy.System("selkov_user", [x, y], [-x + 0.08 * y + x**2 * y, p0 - 0.08 * y - x**2 * y], parameters={"b": b})


def canard(eps: float = 0.05) -> dy.System:
    """eps x' = y - x^3/3 + x, y' = a - x: a Hopf point at a = 1, and the canard explosion just below it."""
    return dy.System("canard_user", [x, y], [(y - x**3 / 3 + x) / eps, p0 - x], parameters={"a": 1.2})


def damped_oscillator(delta: float = 0.04) -> dy.System:
    """x'' + delta x' + x = 0: eigenvalues -delta/2 +- i sqrt(1 - delta^2/4), a slow spiral into the origin."""
    return dy.System("damped_user", [x, y], [y, -p0 * y - x], parameters={"delta": delta})


# ------------------------------------------------------------------------------------ references
def reference_run(rhs, state, t_end: float, **kwargs):
    """scipy's DOP853 at rtol = atol = 1e-12 (independent of the package)."""
    return solve_ivp(rhs, (0.0, t_end), state, method="DOP853", rtol=1e-12, atol=1e-12, **kwargs)


def reference_period(rhs, state, transient: float, returns: int = 4) -> float:
    """The return time to y = 0 (downwards) after ``transient``, averaged over ``returns`` returns."""
    section = lambda t, u: u[1]  # noqa: E731
    section.direction = -1
    run = reference_run(rhs, state, transient, events=None)
    run = reference_run(rhs, run.y[:, -1], 400.0, events=section)
    times = run.t_events[0][: returns + 1]
    return float(np.mean(np.diff(times)))


def vdp_rhs(mu: float):
    return lambda t, u: [u[1], mu * (1 - u[0] ** 2) * u[1] - u[0]]


def duffing_vdp_rhs(mu: float):
    return lambda t, u: [u[1], -mu * (u[0] ** 2 - 1) * u[1] - u[0] - 0.5 * u[0] ** 3]


def fhn_rhs(eps: float):
    return lambda t, u: [u[0] - u[0] ** 3 / 3 - u[1] + 0.5, eps * (u[0] + 0.7 - 0.8 * u[1])]


def bautin_radii(mu: float) -> tuple[float, float]:
    """(r_u, r_s) of :func:`bautin`."""
    return math.sqrt(1 - math.sqrt(1 + mu)), math.sqrt(1 + math.sqrt(1 + mu))

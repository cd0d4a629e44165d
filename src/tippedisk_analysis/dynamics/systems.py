"""The textbook catalogue: systems with known answers, declared once as :class:`.system.System`s and used by the
tests, the command line (``--system``), the studies and the docs (van der Pol, the Hopf and Bautin normal forms,
Roessler, a cycle times a Hopf normal form (Neimark-Sacker), a Hamiltonian loop with energy-selecting damping
(homoclinic), the conservative Duffing oscillator (a family in the energy), Lorenz)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from ..errors import ParameterError
from .system import System


@dataclass(frozen=True)
class Textbook:
    """A textbook system with a known start: a Hopf point (parameter value and equilibrium) or an orbit guess."""

    build: object  # () -> System
    parameter: str  # the natural continuation parameter
    start: dict  # {"hopf": (value, state)} or {"orbit": (value, state, period)}
    facts: str  # what is known exactly (the tests check it)


def _planar_rotation(n: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.linalg.qr(rng.normal(size=(n, n)))[0]


def _vanderpol() -> System:
    x, y = hy.make_vars("x", "y")
    mu = hy.par[0]
    return System("vanderpol", (x, y), (y, mu * (1 - x * x) * y - x), {"mu": 1.0},
                  description="van der Pol oscillator x'' - mu (1 - x^2) x' + x = 0")


HOPF_ROTATION = _planar_rotation(3)


def _hopf() -> System:
    """Hopf normal form z' = (beta + i omega) z + (l1 + i c) z |z|^2 with a slave w' = -w + u v, rotated in R^3."""
    x = hy.make_vars("x1", "x2", "x3")
    beta, omega, l1, c = (hy.par[i] for i in range(4))
    R = HOPF_ROTATION
    u, v, w = (sum(R[j, i] * x[j] for j in range(3)) for i in range(3))  # xi = R^T x
    r2 = u * u + v * v
    g = [beta * u - omega * v + (l1 * u - c * v) * r2, omega * u + beta * v + (c * u + l1 * v) * r2, -w + u * v]
    rhs = tuple(sum(R[i, j] * g[j] for j in range(3)) for i in range(3))  # x' = R g
    return System("hopf_normal_form", tuple(x), rhs, {"beta": 0.0, "omega": 1.0, "l1": -1.0, "c": 0.5},
                  description="Hopf normal form (rotated in R^3): cycles r^2 = -beta/l1, T = 2 pi/(omega + c r^2)")


def _bautin() -> System:
    x, y = hy.make_vars("x", "y")
    beta, ell = hy.par[0], hy.par[1]
    r2 = x * x + y * y
    a = beta + ell * r2 - r2 * r2
    return System("bautin", (x, y), (a * x - y, x + a * y), {"beta": 0.0, "l": 1.0},
                  description="Bautin normal form z' = (beta + i) z + l z|z|^2 - z|z|^4: fold of cycles at "
                              "beta = -l^2/4, r^2 = l/2")


def _roessler() -> System:
    x, y, z = hy.make_vars("x", "y", "z")
    a, b, c = hy.par[0], hy.par[1], hy.par[2]
    return System("roessler", (x, y, z), (-y - z, x + a * y, b + z * (x - c)), {"a": 0.2, "b": 0.2, "c": 2.5},
                  description="Roessler system")


def _torus() -> System:
    """A limit cycle times a Hopf normal form: (x1, x2) r' = r(1 - r^2), theta' = 1; z = x3 + i x4,
    z' = (beta + k x1 + i omega2) z - z |z|^2. The cycle r = 1, z = 0 has multipliers 1, exp(-4 pi) and
    exp(2 pi (beta +- i omega2)) (the mean of x1 over the cycle is 0): a Neimark-Sacker point at beta = 0
    with angle 2 pi omega2 (mod 2 pi)."""
    x1, x2, x3, x4 = hy.make_vars("x1", "x2", "x3", "x4")
    beta, k, w2 = hy.par[0], hy.par[1], hy.par[2]
    r2 = x1 * x1 + x2 * x2
    z2 = x3 * x3 + x4 * x4
    g = beta + k * x1 - z2
    return System("torus", (x1, x2, x3, x4),
                  (x1 * (1 - r2) - x2, x2 * (1 - r2) + x1, g * x3 - w2 * x4, w2 * x3 + g * x4),
                  {"beta": -0.1, "k": 0.5, "omega2": math.sqrt(2.0)},
                  description="limit cycle x Hopf normal form: Neimark-Sacker at beta = 0")


def _homoclinic() -> System:
    """x' = y, y' = x - x^2 - y (H - c), H = y^2/2 - x^2/2 + x^3/3: dH/dt = -y^2 (H - c), so the level set
    H = c is an attracting periodic orbit for c in (-1/6, 0) (a Hopf point at c = -1/6, the centre (1, 0)),
    and H = 0 the homoclinic loop of the saddle (0, 0) (eigenvalues +-1): the period grows without bound
    as c -> 0."""
    x, y = hy.make_vars("x", "y")
    c = hy.par[0]
    H = y * y / 2 - x * x / 2 + x * x * x / 3
    return System("homoclinic_loop", (x, y), (y, x - x * x - y * (H - c)), {"c": -0.1},
                  description="Hamiltonian loop with energy-selecting damping: homoclinic at c = 0")


def _duffing() -> System:
    """The conservative Duffing oscillator x'' + x + k x^3 = 0: energy E = v^2/2 + x^2/2 + k x^4/4, a family of
    periodic orbits parametrised by E (period by quadrature), two trivial multipliers (flow and energy)."""
    x, v = hy.make_vars("x", "v")
    k = hy.par[0]
    return System("duffing", (x, v), (v, -x - k * x * x * x), {"k": 1.0}, n_trivial=2,
                  integrals={"E": v * v / 2 + x * x / 2 + k * x ** 4 / 4},
                  description="conservative Duffing oscillator: a family of orbits in the energy")


def _double_well() -> System:
    """The damped double-well oscillator x'' + delta x' - x + x^3 = 0: stable foci at (x, v) = (+-1, 0), a saddle
    at 0; the symmetry (x, v) -> (-x, -v) swaps the two basins."""
    x, v = hy.make_vars("x", "v")
    return System("double_well", (x, v), (v, -hy.par[0] * v + x - x * x * x), {"delta": 0.3},
                  description="damped double-well oscillator: two symmetric basins")


def _ab() -> System:
    """AUTO-07p's demo 'ab' (an exothermic reaction): u1' = -u1 + D (1 - u1) exp(u2),
    u2' = -u2 + D B (1 - u1) exp(u2) - beta u2."""
    u1, u2 = hy.make_vars("u1", "u2")
    D, B, beta = hy.par[0], hy.par[1], hy.par[2]
    return System("ab", (u1, u2), (-u1 + D * (1 - u1) * hy.exp(u2), -u2 + D * B * (1 - u1) * hy.exp(u2) - beta * u2),
                  {"D": 0.0, "B": 14.0, "beta": 2.0}, description="AUTO-07p demo ab")


def _lorenz() -> System:
    x, y, z = hy.make_vars("x", "y", "z")
    s, r, b = hy.par[0], hy.par[1], hy.par[2]
    return System("lorenz", (x, y, z), (s * (y - x), x * (r - z) - y, x * y - b * z),
                  {"sigma": 10.0, "rho": 28.0, "beta": 8.0 / 3.0}, state_scale=(10.0, 10.0, 10.0),
                  description="Lorenz system")


TEXTBOOK = {
    "vanderpol": Textbook(_vanderpol, "mu", {"orbit": (1.0, (2.0, 0.0), 6.66)},
                          "mu = 1: T = 6.6632868593231 (literature); planar: nontrivial multiplier exp(int div f dt)"),
    "hopf": Textbook(_hopf, "beta", {"hopf": (0.0, (0.0, 0.0, 0.0))},
                     "supercritical Hopf at beta = 0: r^2 = -beta/l1, T = 2 pi/(omega + c r^2)"),
    "bautin": Textbook(_bautin, "beta", {"hopf": (0.0, (0.0, 0.0))},
                       "subcritical Hopf at beta = 0 (l1 = l); fold of cycles at beta = -l^2/4, r^2 = l/2; T = 2 pi"),
    "roessler": Textbook(_roessler, "c", {"orbit": (2.5, (4.3, 0.0, 0.03), 6.0)},
                         "a = b = 0.2: period doubling near c = 2.83"),
    "torus": Textbook(_torus, "beta", {"orbit": (-0.1, (1.0, 0.0, 0.0, 0.0), 2 * math.pi)},
                      "Neimark-Sacker at beta = 0, angle 2 pi sqrt(2) mod 2 pi"),
    "homoclinic": Textbook(_homoclinic, "c", {"hopf": (-1.0 / 6.0, (1.0, 0.0))},
                           "Hopf at c = -1/6, homoclinic loop at c = 0 (saddle eigenvalues +-1)"),
    "duffing": Textbook(_duffing, "E", {"orbit": (0.5, (1.0, 0.0), 5.0)},
                        "conservative: orbits in a family parametrised by the energy E (a level of a first integral)"),
    "double_well": Textbook(_double_well, "delta", {},
                            "delta > 0: stable foci (+-1, 0), basins swapped by (x, v) -> -(x, v)"),
    "ab": Textbook(_ab, "D", {"hopf": (0.13090004482004158, (0.8950806338678032, 4.177042958049749))},
                   "B = 14, beta = 2: folds D = 0.10573898, 0.08893185; Hopf D = 0.13090004 (exact algebra); orbits "
                   "to a homoclinic limit D = 0.10550707 (AUTO-07p)"),
    "lorenz": Textbook(_lorenz, "rho", {}, "sigma 10, rho 28, beta 8/3: Lyapunov exponents 0.9056, 0, -14.5723"),
}


@functools.lru_cache(maxsize=None)
def textbook_system(name: str) -> System:
    """The catalogue's System of that name (``TEXTBOOK[name].facts``: what is known of it exactly)."""
    if name not in TEXTBOOK:
        raise ParameterError(f"unknown system {name!r}; choose one of {', '.join(TEXTBOOK)}")
    return TEXTBOOK[name].build()

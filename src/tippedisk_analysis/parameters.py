"""Parameters of the tippedisk: frozen, validated dataclasses (SI units).

* :class:`Disk` -- mass, eccentricity, radius and inertia about the geometric
  centre G (Sect. 2, Tables 1-2), directly or from the drilled-disk geometry of
  Sect. 5 (:meth:`Disk.from_geometry`).
* :class:`Friction` -- friction and restitution coefficients (Sect. 2.2, 6).
* :class:`InitialState` -- Euler angles and rates (Table 3); the position and
  velocity of G follow from a closed contact at C1 without slip (6.2).

Sweep a value with :func:`dataclasses.replace`, which re-runs the validation.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

STANDARD_GRAVITY = 9.81  # m/s^2, the value used in the paper's simulations


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ParameterError(message)


def _require_finite(obj) -> None:
    for field in dataclasses.fields(obj):
        value = getattr(obj, field.name)
        if isinstance(value, float | int) and not math.isfinite(value):
            raise ParameterError(f"{type(obj).__name__}.{field.name} = {value} is not finite; give a finite number")


@dataclass(frozen=True)
class Disk:
    """Rigid, infinitely thin eccentric disk.

    m [kg]; e [m], distance G->S along e_x^B; r [m], rim radius;
    A, B, C [kg m^2], principal inertia about G in the body frame (2.32).
    """

    m: float = 0.435
    e: float = 2.5e-3
    r: float = 0.045
    A: float = 0.249e-3
    B: float = 0.227e-3
    C: float = 0.468e-3

    def __post_init__(self) -> None:
        _require_finite(self)
        _require(self.r > 0, f"disk radius r = {self.r} m must be positive; give r > 0")
        _require(self.m > 0, f"disk mass m = {self.m} kg must be positive; give m > 0")
        _require(self.e >= 0, f"eccentricity e = {self.e} m must not be negative; give 0 <= e < r")
        _require(
            self.e < self.r,
            f"eccentricity e = {self.e} m is not smaller than the radius r = {self.r} m; give 0 <= e < r",
        )
        for name, value in self.inertia_S.items():
            _require(
                value > 0,
                f"inertia about the centre of gravity {name} = {value:.3g} kg m^2 is not positive; "
                "check A, B, C (about G) against m e^2",
            )
        A, B, C = self.inertia_S.values()
        _require(
            A + B >= C * (1 - 1e-12) and A + C >= B and B + C >= A,
            "inertia about S violates the triangle inequality (A+B >= C etc.); check A, B, C",
        )

    @property
    def inertia_S(self) -> dict[str, float]:
        """Principal inertia about S: A_S = A, B_S = B - m e^2, C_S = C - m e^2 (parallel axes)."""
        me2 = self.m * self.e**2
        return {"A_S": self.A, "B_S": self.B - me2, "C_S": self.C - me2}

    @classmethod
    def from_geometry(
        cls, rho: float = 7700.0, r: float = 0.045, a: float = 0.015, b: float = 0.02, h: float = 0.01
    ) -> Disk:
        """Homogeneous disk (density rho, radius r, height h) with a hole of radius a
        whose centre lies a distance b from G on the side opposite to S (Sect. 5, Fig. 5).

        e = b a^2 / (r^2 - a^2); m and inertia from (5.1)-(5.2) and Table 2.
        """
        for name, value in {"rho": rho, "r": r, "a": a, "b": b, "h": h}.items():
            _require(math.isfinite(value) and value > 0, f"geometry {name} = {value} must be positive; give {name} > 0")
        _require(a < r, f"hole radius a = {a} m is not smaller than the disk radius r = {r} m; give a < r")
        _require(b + a <= r, f"hole (b + a = {b + a} m) reaches past the rim r = {r} m; give b + a <= r")
        k = rho * math.pi * h / 12.0
        return cls(
            m=rho * math.pi * (r**2 - a**2) * h,
            e=b * a**2 / (r**2 - a**2),
            r=r,
            A=k * (3 * r**4 + r**2 * h**2 - a**2 * h**2 - 3 * a**4),
            B=k * (3 * r**4 + r**2 * h**2 - a**2 * h**2 - 3 * a**4 - 12 * a**2 * b**2),
            C=k * (6 * r**4 - 6 * a**4 - 12 * a**2 * b**2),
        )


@dataclass(frozen=True)
class Friction:
    """Friction and impact coefficients (Sect. 2.2; values of Sect. 6).

    mu [-], sliding friction (2.22), (2.29); eps [m/s], smoothing of (2.29);
    mu_tau [-], pivoting friction (2.30); mu_R [-], contour friction (2.31);
    contact_radius [m], radius of the contact area in gamma_tau = eps_i omega_IB (2.16)
    (not given in the paper; 1 mm assumed);
    e_N, e_T, e_tau, e_R [-], restitution coefficients (2.21), (2.28).
    """

    mu: float = 0.3
    eps: float = 0.1
    mu_tau: float = 0.003
    mu_R: float = 0.003
    contact_radius: float = 1e-3
    e_N: float = 0.0
    e_T: float = 0.0
    e_tau: float = 0.0
    e_R: float = 0.0

    def __post_init__(self) -> None:
        _require_finite(self)
        for name in ("mu", "mu_tau", "mu_R"):
            value = getattr(self, name)
            _require(value >= 0, f"friction coefficient {name} = {value} must not be negative; give {name} >= 0")
        _require(
            self.eps > 0,
            f"smoothing eps = {self.eps} m/s must be positive (eps -> 0 is the set-valued law); give eps > 0",
        )
        _require(self.contact_radius > 0, f"contact_radius = {self.contact_radius} m must be positive")
        for name in ("e_N", "e_T", "e_tau", "e_R"):
            value = getattr(self, name)
            _require(0 <= value <= 1, f"restitution coefficient {name} = {value} must lie in [0, 1]")


@dataclass(frozen=True)
class InitialState:
    """Initial orientation and rates in the z-x-z Euler angles of (3.1) (Table 3).

    alpha, beta, gamma [rad]; alpha_dot, beta_dot [rad/s]; gamma_dot [rad/s] or None
    for Table 3's gamma_dot = -alpha_dot cos(beta) (no spin about the disk normal);
    x, y [m], horizontal position of G. The height z and the velocity of G are not
    free: they close the contact at C1 and make its velocity vanish (no slip), see
    :func:`tippedisk_analysis.kinematics.rest_contact_state`.
    """

    alpha: float = 0.0
    beta: float = 0.5 * math.pi
    gamma: float = -0.5 * math.pi + 0.1
    alpha_dot: float = 40.0
    beta_dot: float = 0.0
    gamma_dot: float | None = None
    x: float = 0.0
    y: float = 0.0

    def __post_init__(self) -> None:
        _require_finite(self)
        if self.gamma_dot is not None:
            _require(math.isfinite(self.gamma_dot), f"gamma_dot = {self.gamma_dot} is not finite")
        _require(
            0.0 < self.beta < math.pi,
            f"beta = {self.beta} rad puts the disk flat or upside down; give 0 < beta < pi "
            "(beta = pi/2 is upright)",
        )

    @property
    def gamma_dot_value(self) -> float:
        """gamma_dot, with Table 3's default -alpha_dot cos(beta)."""
        if self.gamma_dot is None:
            return -self.alpha_dot * math.cos(self.beta)
        return self.gamma_dot

    @property
    def euler(self) -> np.ndarray:
        return np.array([self.alpha, self.beta, self.gamma])

    @property
    def euler_rates(self) -> np.ndarray:
        return np.array([self.alpha_dot, self.beta_dot, self.gamma_dot_value])


@dataclass(frozen=True)
class Setup:
    """Everything physical a simulation needs: disk, friction, gravity [m/s^2]."""

    disk: Disk = dataclasses.field(default_factory=Disk)
    friction: Friction = dataclasses.field(default_factory=Friction)
    gravity: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        _require(math.isfinite(self.gravity) and self.gravity > 0, f"gravity = {self.gravity} m/s^2 must be positive")


def to_dict(obj) -> dict:
    """Nested plain dict of a parameter dataclass (for JSON attributes)."""
    return dataclasses.asdict(obj)

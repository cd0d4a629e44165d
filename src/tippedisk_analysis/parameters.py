"""Parameters of the tippedisk: frozen, validated dataclasses (SI units).

* :class:`Disk` -- mass, eccentricity, radius and inertia about the geometric
  centre G (Sect. 2, Tables 1-2), directly or from the drilled-disk geometry of
  Sect. 5 (:meth:`Disk.from_geometry`, :class:`DiskGeometry`, kept with the disk).
  :meth:`Disk.with_eccentricity` and :meth:`Disk.with_mass` change one property
  consistently (a geometric disk moves its hole or changes its density; a disk given
  by values holds its inertia about G, or scales it with the mass).
* :class:`Friction` -- friction and restitution coefficients (Sect. 2.2, 6).
* :class:`InitialState` -- Euler angles and rates (Table 3); the position and
  velocity of G follow from a closed contact at C1 without slip (6.2).

Sweep a value with :func:`dataclasses.replace`, which re-runs the validation.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

STANDARD_GRAVITY = 9.81  # m/s^2, the value used in the paper's simulations


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ParameterError(message)


def _require_finite(obj, optional: tuple[str, ...] = (), skip: tuple[str, ...] = ()) -> None:
    """Every numeric field a finite int or float, stored as float (``optional`` fields may be None)."""
    for field in dataclasses.fields(obj):
        value = getattr(obj, field.name)
        if field.name in skip or (field.name in optional and value is None):
            continue
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ParameterError(f"{type(obj).__name__}.{field.name} = {value!r} is a {type(value).__name__}; "
                                 f"give a number, e.g. {type(obj).__name__}({field.name}={field.default!r})")
        if not math.isfinite(value):
            raise ParameterError(f"{type(obj).__name__}.{field.name} = {value} is not finite; give a finite number")
        object.__setattr__(obj, field.name, float(value))


@dataclass(frozen=True)
class DiskGeometry:
    """The drilled steel disk of Sect. 5 (Fig. 5, Table 1): a homogeneous cylinder of density
    rho [kg/m^3], radius r [m] and thickness h [m] with a through hole of radius a [m] whose
    centre lies a distance b [m] from G, on the side opposite to S."""

    rho: float = 7700.0
    r: float = 0.045
    a: float = 0.015
    b: float = 0.02
    h: float = 0.01

    def __post_init__(self) -> None:
        _require_finite(self)
        for name in ("rho", "r", "a", "b", "h"):
            value = getattr(self, name)
            _require(value > 0, f"geometry {name} = {value} must be positive; give {name} > 0")
        _require(self.a < self.r,
                 f"hole radius a = {self.a} m is not smaller than the disk radius r = {self.r} m; give a < r")
        _require(self.b + self.a <= self.r,
                 f"hole (b + a = {self.b + self.a:.6g} m) reaches past the rim r = {self.r} m; give b + a <= r")

    @property
    def eccentricity(self) -> float:
        """e = b a^2 / (r^2 - a^2) (Sect. 5)."""
        return self.b * self.a**2 / (self.r**2 - self.a**2)

    def offset_for(self, e: float) -> float:
        """The hole offset b that gives the eccentricity e (the inverse of :attr:`eccentricity`)."""
        return e * (self.r**2 - self.a**2) / self.a**2

    def mass_properties(self) -> dict[str, float]:
        """m, e, A, B, C about G of (5.1)-(5.2)."""
        rho, r, a, b, h = self.rho, self.r, self.a, self.b, self.h
        k = rho * math.pi * h / 12.0
        return {
            "m": rho * math.pi * (r**2 - a**2) * h,
            "e": self.eccentricity,
            "A": k * (3 * r**4 + r**2 * h**2 - a**2 * h**2 - 3 * a**4),
            "B": k * (3 * r**4 + r**2 * h**2 - a**2 * h**2 - 3 * a**4 - 12 * a**2 * b**2),
            "C": k * (6 * r**4 - 6 * a**4 - 12 * a**2 * b**2),
        }


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
    geometry: DiskGeometry | None = None

    def __post_init__(self) -> None:
        if isinstance(self.geometry, dict):  # from a stored configuration
            object.__setattr__(self, "geometry", DiskGeometry(**self.geometry))
        _require(self.geometry is None or isinstance(self.geometry, DiskGeometry),
                 f"Disk.geometry = {self.geometry!r} must be a DiskGeometry or None; use Disk.from_geometry(...)")
        _require_finite(self, skip=("geometry",))
        if self.geometry is not None:
            expected = {"r": self.geometry.r, **self.geometry.mass_properties()}
            for name, value in expected.items():
                _require(math.isclose(getattr(self, name), value, rel_tol=1e-9, abs_tol=1e-15),
                         f"Disk.{name} = {getattr(self, name):.6g} does not match its geometry ({name} = {value:.6g}); "
                         "change the geometry (Disk.from_geometry, disk.with_eccentricity) or give geometry=None")
        _require(self.r > 0, f"disk radius r = {self.r} m must be positive; give r > 0")
        _require(self.m > 0, f"disk mass m = {self.m} kg must be positive; give m > 0")
        _require(self.e >= 0, f"eccentricity e = {self.e} m must not be negative; give 0 <= e < r")
        _require(
            self.e < self.r,
            f"eccentricity e = {self.e} m is not smaller than the radius r = {self.r} m; give 0 <= e < r",
        )
        about_G = {"A_S": self.A, "B_S": self.B, "C_S": self.C}
        for name, value in self.inertia_S.items():
            if value <= 0 and about_G[name] > 0:  # Steiner: X_S = X - m e^2 (Table 2 is about G)
                e_max = math.sqrt(about_G[name] / self.m)
                _require(False, f"eccentricity e = {self.e} m is too large for this disk's inertia: {name} = "
                                f"{name[0]} - m e^2 = {value:.3g} kg m^2 would not be positive; give e < {e_max:.4g} m "
                                f"(or a larger {name[0]})")
            _require(value > 0, f"inertia about the centre of gravity {name} = {value:.3g} kg m^2 is not positive; "
                                "check A, B, C (about G) against m e^2")
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

        e = b a^2 / (r^2 - a^2); m and inertia from (5.1)-(5.2) and Table 2. The geometry is kept
        (``geometry``, stored in every configuration), so an eccentricity sweep can move the hole.
        The exact values differ from the rounded Table 2 in the third digit.
        """
        geometry = DiskGeometry(rho=rho, r=r, a=a, b=b, h=h)
        return cls(r=r, geometry=geometry, **geometry.mass_properties())

    @property
    def source(self) -> str:
        """How the disk was given: ``geometry`` (Sect. 5) or ``values`` (Table 2 or m, e, r, A, B, C)."""
        return "geometry" if self.geometry is not None else "values"

    @property
    def eccentricity_rule(self) -> str:
        """What :meth:`with_eccentricity` holds fixed (stored with every eccentricity sweep)."""
        if self.geometry is not None:
            return ("hole offset b moved (b = e (r^2 - a^2) / a^2); rho, r, a, h held fixed; "
                    "m, A, B, C recomputed from (5.1)-(5.2)")
        return "m, r and the inertia A, B, C about G held fixed"

    def with_eccentricity(self, e: float) -> Disk:
        """The disk with eccentricity ``e`` [m]: a disk built from a geometry moves its hole (b follows
        from e; m, A, B, C recomputed); a disk given by values keeps m, r and A, B, C about G."""
        if self.geometry is not None:
            g = self.geometry
            b = g.offset_for(float(e))
            if not 0 < b <= g.r - g.a:
                raise ParameterError(f"eccentricity e = {e} m needs the hole offset b = {b:.6g} m, outside "
                                     f"(0, r - a] = (0, {g.r - g.a:.6g}] m for this geometry; give "
                                     f"0 < e <= {DiskGeometry(g.rho, g.r, g.a, g.r - g.a, g.h).eccentricity:.6g} m")
            return Disk.from_geometry(g.rho, g.r, g.a, b, g.h)
        return dataclasses.replace(self, e=float(e))

    def with_mass(self, m: float) -> Disk:
        """The disk of the same shape and another density: mass ``m`` [kg], A, B, C scaled by m / self.m
        (e and r unchanged). A disk built from a geometry changes its density rho."""
        _require(isinstance(m, numbers.Real) and not isinstance(m, bool) and math.isfinite(m) and m > 0,
                 f"disk mass m = {m!r} kg must be a positive number; give m > 0")
        if self.geometry is not None:
            g = self.geometry
            return Disk.from_geometry(g.rho * m / self.m, g.r, g.a, g.b, g.h)
        k = m / self.m
        return dataclasses.replace(self, m=float(m), A=self.A * k, B=self.B * k, C=self.C * k)


def eccentricity_columns(disk: Disk, e_values) -> dict[str, np.ndarray]:
    """m, e, A, B, C of ``disk.with_eccentricity(e)`` for every e (each validated): the parameter
    columns of an eccentricity sweep (stability and outcome maps)."""
    disks = [disk.with_eccentricity(float(e)) for e in np.atleast_1d(np.asarray(e_values, dtype=float))]
    return {name: np.array([getattr(d, name) for d in disks]) for name in ("m", "e", "A", "B", "C")}


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
        _require_finite(self, optional=("gamma_dot",))
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
        for name, cls in (("disk", Disk), ("friction", Friction)):
            value = getattr(self, name)
            _require(isinstance(value, cls), f"Setup.{name} = {value!r} must be a {cls.__name__}; give e.g. "
                                             f"Setup({name}={cls.__name__}())")
        _require(isinstance(self.gravity, numbers.Real) and not isinstance(self.gravity, bool)
                 and math.isfinite(self.gravity) and self.gravity > 0,
                 f"gravity = {self.gravity!r} m/s^2 must be a positive number")
        object.__setattr__(self, "gravity", float(self.gravity))


def to_dict(obj) -> dict:
    """Nested plain dict of a parameter dataclass (for JSON attributes). A disk given by values has no
    ``geometry`` key, so its configuration reads as before drilled disks were kept (stored datasets,
    checkpoints and chunk directories stay comparable)."""
    return _without_empty_geometry(dataclasses.asdict(obj))


def setup_from_dict(d: dict) -> Setup:
    """The :class:`Setup` of its :func:`to_dict` form (a dataset's configuration)."""
    return Setup(Disk(**d["disk"]), Friction(**d["friction"]), d.get("gravity", Setup().gravity))


def _without_empty_geometry(d):
    if isinstance(d, dict):
        return {k: _without_empty_geometry(v) for k, v in d.items() if not (k == "geometry" and v is None)}
    return d

"""The interface of the continuation core (:mod:`.continuation`): its options, the :class:`Problem` a
continuation problem implements, and the points, special points and branches it returns."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from .detection import hopf_test, nearest_pair, nearest_real, zero_test
from .linear_algebra import DenseLinearisation


@dataclass(frozen=True)
class Options:
    """Step control and tolerances, in scaled unknowns (u / scale)."""

    ds: float = 0.02  # first step
    ds_min: float = 1e-8
    ds_max: float = 0.2
    max_points: int = 500
    tol: float = 1e-11  # corrector: largest scaled Newton step of the last iteration
    max_newton: int = 8
    locate_tol: float = 1e-10  # |test function| of a located special point (eigenvalue units)
    growth: float = 1.5  # step growth after a correction in at most easy_iterations iterations
    easy_iterations: int = 3  # (chord steps, with a sparse Jacobian, take one or two more than Newton's)

    def __post_init__(self):
        for name in ("ds", "ds_min", "ds_max", "tol", "locate_tol", "growth"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ParameterError(f"continuation option {name} = {value!r} must be a positive number")
        if not self.ds_min <= abs(self.ds) <= self.ds_max:
            raise ParameterError(f"step ds = {self.ds} must lie in [ds_min, ds_max] = [{self.ds_min}, {self.ds_max}]")
        if int(self.max_points) != self.max_points or self.max_points < 2:
            raise ParameterError(f"max_points = {self.max_points!r} must be an integer >= 2")
        if not (isinstance(self.max_newton, int) and self.max_newton >= 1):
            raise ParameterError(f"max_newton = {self.max_newton!r} must be an integer >= 1")
        if not (isinstance(self.easy_iterations, int) and self.easy_iterations >= 1):
            raise ParameterError(f"easy_iterations = {self.easy_iterations!r} must be an integer >= 1")
        if self.growth < 1:
            raise ParameterError(f"growth = {self.growth!r} must be >= 1 (the step grows after easy corrections)")


class Problem:
    """Interface of a continuation problem (subclass and implement the methods).

    names: unknowns (states, then parameters); scale: their typical magnitudes (the arclength
    metric); parameters: indices of the free parameters among the unknowns (the first one's
    tangent component is the fold test); bounds: {index: (low, high)} where a branch ends.
    """

    names: tuple[str, ...]
    scale: np.ndarray
    parameters: tuple[int, ...]
    bounds: dict
    terminal: frozenset = frozenset()  # kinds of special points at which a branch ends (e.g. a branch of
    # periodic orbits at the Hopf point where its amplitude vanishes)

    def residual(self, u: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def linearise(self, u: np.ndarray, scale: np.ndarray, row: np.ndarray | None = None):
        """The Jacobian at u in the unknowns u / scale, with ``row`` appended (the arclength constraint), ready to
        solve: an object with ``solve(b)``, ``magnitude(v)`` (|A| |v| per row), ``reusable`` (a factorisation that
        serves chord steps) and ``rows``. Default: the dense :meth:`jacobian` (least squares)."""
        A = self.jacobian(u) * scale[None, :]
        return DenseLinearisation(A if row is None else np.vstack([A, row]))

    def state_jacobian(self, u: np.ndarray) -> np.ndarray:
        """Square matrix whose eigenvalues decide stability and the test functions."""
        raise NotImplementedError

    def state_eigenvalues(self, u: np.ndarray) -> np.ndarray:
        """The eigenvalues that decide stability and the test functions, by real part descending (default: of
        the state Jacobian; a problem may compute them without forming it, e.g. from a matrix pencil)."""
        ev = np.linalg.eigvals(self.state_jacobian(u))
        return ev[np.argsort(-ev.real, kind="stable")]

    def second_derivative(self, u: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """F_uu[a, b] (for branch switching)."""
        raise NotImplementedError

    def describe(self, kind: str, u: np.ndarray) -> dict:
        """Normal-form coefficients etc. of a located special point (optional)."""
        return {}

    def end_message(self, kind: str, u: np.ndarray, where: str) -> str:
        """The branch's message where it ends at a terminal special point of ``kind`` at u (``where``: the
        parameters' values there)."""
        return f"ended at a {kind} point at {where}"

    def project(self, u: np.ndarray) -> np.ndarray:
        """Map an iterate onto a known solution manifold (default: none). A family of equilibria
        known in closed form keeps its states exact this way."""
        return u

    def discretisation(self):
        """What the unknowns refer to, if the problem changes it along a branch (a collocation mesh); stored
        with every point (default None: fixed)."""
        return None

    def use(self, discretisation) -> None:
        """Make the unknowns refer to ``discretisation`` (a point's) again (default: nothing to do)."""

    def remesh(self, point: "Point") -> tuple[np.ndarray, np.ndarray] | None:
        """Called at every accepted point: the point's unknowns and unit tangent (scaled) carried to a new
        discretisation (an adapted mesh), or None to keep it (default)."""
        return None

    def refine(self, u: np.ndarray) -> bool:
        """Called with every new solution before it is accepted: True if its discretisation is too coarse and
        the problem switched to a finer one (the core then redoes the step from the last point, carried there);
        default False."""
        return False

    def carry(self, point: "Point") -> tuple[np.ndarray, np.ndarray]:
        """The point's unknowns and unit tangent on the problem's present discretisation (after refine)."""
        return point.u, point.tangent

    def set_reference(self, u: np.ndarray) -> None:
        """Called with the start guess, the corrected start and every accepted point of a branch (default:
        nothing). Problems with a moving reference, e.g. the phase condition of periodic orbits relative to
        the last orbit found (AUTO, BifurcationKit), update it here; located special points and bound points
        are computed with the reference of the regular point before them."""

    def tests(self, point: "Point") -> dict[str, float]:
        """Test functions whose sign changes mark special points (default: equilibrium branches)."""
        return {"fold": point.tangent[self.parameters[0]], "branch_point": zero_test(point.eigenvalues),
                "hopf": hopf_test(point.eigenvalues)}

    def located_value(self, kind: str, point: "Point") -> float:
        """A smooth function vanishing at the special point, in eigenvalue units where possible
        (used to locate it; NaN if undefined there)."""
        if kind == "fold":
            return point.tangent[self.parameters[0]]
        if kind == "branch_point":
            return nearest_real(point.eigenvalues)
        if kind == "hopf":
            return nearest_pair(point.eigenvalues).real
        return self.tests(point)[kind]

    def accept(self, kind: str, point: "Point", value: float, options: "Options") -> bool | str:
        """Whether a located point is the special point (a Hopf test zero may be a neutral saddle); a string
        declines it with the reason it could not be confirmed (reported with the branch's unlocated points)."""
        if kind == "hopf":
            scale = np.abs(point.eigenvalues).max()
            return math.isfinite(value) and abs(value) <= max(options.locate_tol, 1e-8 * scale)
        return True


@dataclass
class Point:
    u: np.ndarray
    tangent: np.ndarray  # unit tangent in scaled unknowns
    arclength: float  # scaled arclength from the start
    eigenvalues: np.ndarray  # of the state Jacobian, sorted by real part (descending)
    newton_iterations: int
    special: str = ""  # kind if this point is a located special point
    discretisation: object = None  # what u refers to (Problem.discretisation), e.g. a collocation mesh


@dataclass
class SpecialPoint:
    kind: str  # a key of LABELS
    index: int  # position in Branch.points
    u: np.ndarray
    eigenvalues: np.ndarray
    value: float  # the located test function
    data: dict = field(default_factory=dict)  # frequency, normal-form coefficients, ...
    label: str = ""  # e.g. HOPF1, set when the branch is finished


@dataclass
class Branch:
    points: list
    special_points: list
    status: str  # one of STATUSES
    message: str
    options: Options
    unlocated: list = field(default_factory=list)  # test-function sign changes that were no zero, where

    def array(self, attribute: str) -> np.ndarray:
        return np.array([getattr(p, attribute) for p in self.points])

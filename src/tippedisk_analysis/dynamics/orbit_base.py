"""What every discretisation of periodic orbits shares (shooting, :mod:`.shooting`; collocation,
:mod:`.collocation`): the unknowns u = (states at the nodes, T[, p]), the continuation parameter (a runtime
parameter, a first integral's level or a pinned state), the level equations, the test functions on the Floquet
multipliers, and the record of an orbit (:class:`PeriodicOrbit`).

A subclass evaluates u (``_evaluate``: a dict with the monodromy ``M``, the flow direction ``f0`` at x(0), the
period ``T`` and ``half`` = (x(0) - x(T/2)) / scale, or ``error``); the rest is here:

* levels: I_j(x(0)) = c_j for the first integrals, x(0)[i] = c_i for the pinned states (``pins``: picks one
  orbit of a family that no first integral labels, e.g. the symmetric orbits of a reversible system);
* the state Jacobian of the continuation core is the monodromy with the flow direction deflated exactly
  (:func:`.flows.deflate`), so its eigenvalues are the nontrivial multipliers and the special points come from
  them (:mod:`.orbit_branches`);
* a turn of the parameter is a fold of cycles where a nontrivial multiplier is 1 within FOLD_MULTIPLIER_TOL, or
  where the count of nontrivial multipliers outside the unit circle differs between orbits either side of it
  (a multiplier crossed +1): at a fold the critical and the trivial multiplier form a double 1 that a
  discretisation error delta splits by about sqrt(delta), and on very unstable orbits (multipliers of 1e60 and
  more) the critical one is resolved only to about 0.1; its count is not;
* ``event``: an orbit reaches one of the System's terminal events (:class:`.system.Event`, e.g. a model's edge of
  validity): the signed event functions min_k +-g(x_k) over the orbit's nodes change sign; a special point, and
  the branch's end where the problem is to stop there (:meth:`OrbitProblem.end_at_events`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from . import continuation
from .flows import MULTIPLIER_TOL, STABILITY, classify, deflate, floquet
from .system import System

N_SAMPLES = 128  # samples stored per orbit
MAX_NEWTON_STEP = 0.5  # largest Newton step in scaled unknowns (a trust region: no jumps along near-null directions)
TRIVIAL_TOL = 1e-3  # |mu - 1| of the flow direction's multiplier up to which the multipliers are trusted ...
DECIDING_SHARE, DECIDING_CAP = 0.1, 1e-2  # ... or up to this share of the nontrivial ones' distance from the unit
# circle, and at most DECIDING_CAP
FOLD_MULTIPLIER_TOL = 1e-3  # a fold of cycles: its nontrivial multiplier nearest 1 is at most this far from 1 ...
FOLD_PROBES = (1e-3, 4e-3, 1.6e-2, 6.4e-2, 0.256)  # ... or the count outside the unit circle differs between the
# orbits either side (the bracket the turn was found in, else orbits this far, in scaled arclength, along its tangent)
COUNTS_KEPT = 64  # the counts of the last orbits whose test functions were evaluated (the bracket among them)
HOPF_NEAR = 0.25  # a Hopf end is looked for among orbits below this share of the largest orbit so far ...
HOPF_ALIGNED = 0.9  # ... or whose x_0 - x(T/2) lies within arccos(0.9) of the reference's


class OrbitProblem(continuation.Problem):
    """Periodic orbits of ``system`` with ``n_nodes`` state blocks in u; a continuation problem if ``parameter``
    is set (a runtime parameter, a first integral's name or a pinned state's name)."""

    def __init__(self, system: System, pars, n_nodes: int, *, parameter: str | None, levels: dict | None,
                 pins: dict | None, bounds: dict | None, period_first: bool = False):
        self.system = system
        self.n = system.n
        self.pars = np.array(system.pars if pars is None else pars, dtype=float)
        self.integral_names = tuple(system.integrals)
        self.pins = {name: float(v) for name, v in (pins or {}).items()}
        self._pin_index = [system.state_index(name) for name in self.pins]
        self.level_names = (*self.integral_names, *self.pins)
        self.level_parameter = parameter if parameter in self.level_names else None
        self.p_index = None if parameter is None or self.level_parameter else system.parameter_index(parameter)
        self.parameter = parameter
        self.levels = dict(levels or {})
        missing = [name for name in self.integral_names if name not in self.levels and name != self.level_parameter]
        if missing:
            raise ParameterError(f"{system.name} has first integrals: give the levels of {', '.join(missing)} "
                                 "(find_orbit takes them from the guess)")
        self._integrals = system.integrals_field() if system.integrals else None
        self.n_nodes = n_nodes
        # u = (nodes, T[, p]), or (T[, p], nodes) where the number of nodes may change along a branch
        self.t_index = 0 if period_first else self.n * n_nodes
        self.x_start = (2 if parameter else 1) if period_first else 0
        self.parameters = (self.t_index + 1,) if parameter else ()
        self.bounds = {}
        for name, (low, high) in (bounds or {}).items():
            index = {"T": self.t_index, parameter: self.t_index + 1}.get(name)
            if index is None:
                raise ParameterError(f"bound on {name!r}: give bounds on T or the continuation parameter {parameter}")
            self.bounds[index] = (float(low), float(high))
        self._half_ref = np.zeros(self.n)
        self._half_ref_norm = self._largest = 0.0
        self.terminal = frozenset({"hopf"})
        self._counts: dict[float, int | None] = {}  # arclength: multipliers outside the unit circle (None: undecided)
        self._events = [e for e in system.events if e.direction in ("negative", "positive")]
        self._event_function = (system.function("terminal events", [e.expression for e in self._events])
                                if self._events else None)

    def end_at_events(self, end: bool) -> None:
        """Whether a branch ends at the first orbit that reaches a terminal event of the System (else the point is
        marked and the branch goes on)."""
        self.terminal = frozenset({"hopf", "event"} if end else {"hopf"})

    # -- unknowns
    def split(self, u):
        """(node states (nodes, n), T, p or None) of u."""
        u = np.asarray(u, dtype=float)
        X = u[self.x_start:self.x_start + self.n * self.n_nodes].reshape(-1, self.n)
        return X, float(u[self.t_index]), (float(u[self.t_index + 1]) if self.parameter else None)

    def pack(self, X, T: float, p: float | None = None) -> np.ndarray:
        """u from node states X (nodes, n), the period and the parameter's value (the layout of this problem)."""
        head = [T] + ([p] if self.parameter else [])
        X = np.ravel(X)
        return np.concatenate([head, X] if self.t_index == 0 else [X, head]).astype(float)

    def runtime(self, u) -> np.ndarray:
        pars = self.pars.copy()
        if self.p_index is not None:
            pars[self.p_index] = u[self.t_index + 1]
        return pars

    def level_rows(self, u, X0) -> tuple[np.ndarray, np.ndarray]:
        """I_j(x_0) - c_j and their gradients (rows of the Jacobian) for the first integrals, then
        x_0[i] - c_i for the pinned states (x_0: the first node)."""
        k = len(self.level_names)
        if not k:
            return np.empty(0), np.empty((0, len(u)))
        rows = np.zeros((k, len(u)))
        values = np.empty(k)
        n_int = len(self.integral_names)
        if n_int:
            pars = self.runtime(u)
            values[:n_int] = self._integrals.values(X0, pars)
            rows[:n_int, self.x_start:self.x_start + self.n] = self._integrals.tensor(X0, pars, 1,
                                                                                      with_parameters=False)
        for j, i in enumerate(self._pin_index):
            values[n_int + j] = X0[i]
            rows[n_int + j, self.x_start + i] = 1.0
        target = np.array([self.levels.get(name, math.nan) for name in self.integral_names]
                          + list(self.pins.values()))
        if self.level_parameter:
            j = self.level_names.index(self.level_parameter)
            target[j] = u[self.t_index + 1]
            rows[j, self.t_index + 1] = -1.0
        return values - target, rows

    def _evaluate(self, u) -> dict:
        raise NotImplementedError

    def _remember_half(self, ev: dict) -> None:
        """The reference of the signed amplitude (set_reference of a subclass) and the largest orbit so far."""
        self._half_ref_norm = float(np.linalg.norm(ev["half"]))
        self._largest = max(self._largest, ev["size"])
        self._half_ref = ev["half"] / (self._half_ref_norm or 1.0)

    def floquet(self, ev: dict, n_trivial: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(multipliers, trivial mask) of an evaluation (:func:`.flows.floquet`; ``n_trivial`` default the
        system's)."""
        return floquet(ev["M"], ev["f0"], self.system.n_trivial if n_trivial is None else n_trivial,
                       self.eigen(ev))

    def eigen(self, ev: dict) -> tuple[np.ndarray, np.ndarray] | None:
        """(eigenvalues, eigenvectors) of the monodromy if the discretisation computes them itself."""
        return None

    def monodromy(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n, self.n), np.nan)
        return ev["M"]

    def state_jacobian(self, u) -> np.ndarray:
        ev = self._evaluate(u)
        if "error" in ev:
            return np.full((self.n - 1, self.n - 1), np.nan)
        return deflate(ev["M"], ev["f0"])

    def second_derivative(self, u, a, b):  # pragma: no cover - branch switching of cycles uses directions
        raise ParameterError("periodic-orbit problems switch branches along critical eigenvectors, "
                             "not by the algebraic bifurcation equations")

    # -- test functions on the nontrivial multipliers (the deflated monodromy's eigenvalues)
    def _nontrivial(self, mu: np.ndarray) -> np.ndarray:
        mu = np.asarray(mu)
        for _ in range(self.system.n_trivial - 1):
            if len(mu):
                mu = np.delete(mu, np.argmin(np.abs(mu - 1.0)))
        return mu

    def flow_multiplier_error(self, u) -> float:
        """|mu - 1| of the flow direction's multiplier: round-off for an exact monodromy, larger where the
        multipliers are ill-conditioned or the orbit is discretised (NaN where u cannot be evaluated)."""
        ev = self._evaluate(u)
        if "error" in ev:
            return math.nan
        mu, flow = self.floquet(ev, n_trivial=1)
        return float(np.abs(mu[flow][0] - 1.0))

    def tests(self, point) -> dict:
        mu = self._nontrivial(point.eigenvalues)
        i, j = np.triu_indices(len(mu), 1)
        tests = {"fold": float(point.tangent[self.parameters[0]]), "branch_point": _signed_product(mu - 1.0),
                 "period_doubling": _signed_product(mu + 1.0), "neimark_sacker": _signed_product(mu[i] * mu[j] - 1.0),
                 "hopf": self._hopf_test(point.u)}
        if self._events:
            tests["event"] = self.event_margin(point.u)[0]
        decided = multipliers_decide(mu, self.flow_multiplier_error(point.u))
        self._counts[float(point.arclength)] = int(np.sum(np.abs(mu) > 1.0)) if decided else None
        if len(self._counts) > COUNTS_KEPT:
            del self._counts[next(iter(self._counts))]
        if not decided:
            for kind in ("branch_point", "period_doubling", "neimark_sacker"):
                tests[kind] = math.nan
        if self.integral_names:  # conservative: pairs on the unit circle are generic (elliptic), not a bifurcation
            del tests["neimark_sacker"]
        return tests

    def event_margin(self, u) -> tuple[float, str]:
        """(min over the System's terminal events and the orbit's nodes of g(x_k) / max_k |g(x_k)|, the name of
        the event that attains it): positive while the orbit stays where no event ends a run (g > 0 for an event
        of direction negative, g < 0 for positive), zero where it reaches one. Collocation's nodes cover the orbit;
        shooting's are the segment starts."""
        X = self.split(u)[0]
        g = self.system.evaluate(self._event_function, np.ascontiguousarray(X.T), self.runtime(u))
        g = g * np.array([1.0 if e.direction == "negative" else -1.0 for e in self._events])[:, None]
        scaled = g.min(axis=1) / np.maximum(np.abs(g).max(axis=1), 1e-300)
        k = int(np.argmin(scaled))
        return float(scaled[k]), self._events[k].name

    def end_message(self, kind: str, u, where: str) -> str:
        """At an event end, the event's name and why the branch stops there."""
        if kind != "event":
            return super().end_message(kind, u, where)
        return (f"an orbit reaches the event {self.event_margin(u)[1]} of {self.system.name} at {where} (period "
                f"{self.split(u)[1]:.6g}): a run of the model ends there, so the branch does")

    def _hopf_test(self, u) -> float:
        """The signed amplitude where the orbit is below HOPF_NEAR times the largest of the branch so far (its
        size: the largest scaled distance of its nodes from their mean) or x_0 - x(T/2) lies along the
        reference's (|cos| >= HOPF_ALIGNED), else NaN: towards a Hopf end the orbits shrink along the critical
        eigenvector and flip; a large orbit whose shape turns changes the sign of the projection through the
        orthogonal direction (no Hopf point: not worth locating)."""
        ev = self._evaluate(u)
        if "error" in ev:
            return math.nan
        value = float(ev["half"] @ self._half_ref)
        aligned = abs(value) >= HOPF_ALIGNED * float(np.linalg.norm(ev["half"]))
        return value if aligned or ev["size"] <= HOPF_NEAR * self._largest else math.nan

    def _signed_amplitude(self, u) -> float:
        """(x_0 - x(T/2)) / scale along the reference orbit's: changes sign where the branch passes through a
        Hopf point (zero amplitude; beyond it the same orbits return shifted by half a period)."""
        ev = self._evaluate(u)
        return math.nan if "error" in ev else float(ev["half"] @ self._half_ref)

    def located_value(self, kind: str, point) -> float:
        mu = self._nontrivial(point.eigenvalues)
        if kind == "fold":
            return float(point.tangent[self.parameters[0]])
        if kind == "hopf":
            return self._signed_amplitude(point.u)
        if kind == "event":
            return self.event_margin(point.u)[0]
        real = mu[np.abs(mu.imag) <= 1e-9 * max(1.0, np.abs(mu).max(initial=1.0))].real
        if kind == "branch_point":
            return float(real[np.argmin(np.abs(real - 1.0))] - 1.0) if real.size else math.nan
        if kind == "period_doubling":
            negative = real[real < 0]
            return float(-negative[np.argmin(np.abs(negative + 1.0))] - 1.0) if negative.size else math.nan
        if kind == "neimark_sacker":
            pairs = mu[mu.imag > 1e-9 * max(1.0, np.abs(mu).max(initial=1.0))]
            return float(np.abs(pairs[np.argmin(np.abs(np.abs(pairs) - 1.0))]) - 1.0) if pairs.size else math.nan
        return self.tests(point)[kind]

    def accept(self, kind: str, point, value: float, options) -> bool:
        if kind in ("period_doubling", "neimark_sacker", "branch_point"):
            return math.isfinite(value) and abs(value) <= max(MULTIPLIER_TOL, options.locate_tol)
        if kind in ("fold", "hopf"):
            # at a Hopf end the parameter turns too (p - p_H ~ r^2): not a fold of cycles; and the projected
            # amplitude of a large orbit may change sign as its shape turns: a Hopf end needs amplitude zero
            ev = self._evaluate(point.u)
            small = "error" not in ev and float(np.linalg.norm(ev["half"])) <= 1e-3 * self._half_ref_norm
            if "error" in ev or small != (kind == "hopf"):
                return False
            if kind == "fold" and not self.level_names:  # a fold of cycles has a nontrivial multiplier 1
                mu = self._nontrivial(point.eigenvalues)
                gap = float(np.min(np.abs(mu - 1.0))) if mu.size else math.inf
                if gap > FOLD_MULTIPLIER_TOL:
                    counts = self._counts_beside(point, options)
                    if counts is None or counts[0] == counts[1]:
                        seen = ("the multipliers either side decide nothing" if counts is None else
                                f"{counts[0]} outside the unit circle on both sides")
                        return (f"the parameter turns but no nontrivial multiplier is 1 (nearest off by {gap:.2g}; "
                                f"{seen}): a numerical turn (raise the resolution), not a fold of cycles")
        return True

    def _counts_beside(self, point, options) -> tuple[int, int] | None:
        """The numbers of nontrivial multipliers outside the unit circle before and after ``point`` (a turn): on
        each side at the nearest of the orbits FOLD_PROBES (scaled arclength) along its tangent where they decide,
        else at the nearest orbit within ds_max whose multipliers decided when its test functions were evaluated
        (the bracket the turn was found in); None where a side has none."""
        near = {a - point.arclength: count for a, count in self._counts.items()
                if count is not None and 0 < abs(a - point.arclength) <= options.ds_max}
        sides = []
        for sign in (-1.0, 1.0):
            seen = [d for d in near if sign * d > 0]
            count = self._probe(point, sign, options)
            sides.append(near[min(seen, key=abs)] if count is None and seen else count)
        return None if None in sides else (sides[0], sides[1])

    def _probe(self, point, sign: float, options) -> int | None:
        """The count outside the unit circle at the nearest orbit FOLD_PROBES along ``point``'s tangent (sign -1:
        before it) whose multipliers decide (:func:`multipliers_decide`), else None."""
        for step in FOLD_PROBES:
            u = continuation._step_to(self, point, sign * step, options)
            if u is None:
                continue
            mu = self._nontrivial(self.state_eigenvalues(u))
            if np.all(np.isfinite(mu)) and multipliers_decide(mu, self.flow_multiplier_error(u)):
                return int(np.sum(np.abs(mu) > 1.0))
        return None

    def describe(self, kind: str, u) -> dict:
        ev = self._evaluate(u)
        if "error" in ev:
            return {}
        if kind == "event":
            return {"period": ev["T"], "event": self.event_margin(u)[1]}
        mu, trivial = self.floquet(ev)
        rest = mu[~trivial]
        target = {"fold": 1.0, "branch_point": 1.0, "period_doubling": -1.0}.get(kind)
        if target is not None:
            crit = rest[np.argmin(np.abs(rest - target))]
        else:
            pairs = rest[np.abs(rest.imag) > 1e-9]
            crit = pairs[np.argmin(np.abs(np.abs(pairs) - 1.0))] if pairs.size else complex(math.nan)
        data = {"period": ev["T"], "multiplier_real": float(np.real(crit)), "multiplier_imag": float(np.imag(crit))}
        if kind == "hopf":
            data["frequency"] = 2 * math.pi / ev["T"]
        if kind == "neimark_sacker":
            theta = abs(float(np.angle(crit)))
            data["angle"] = theta
            data["strong_resonance"] = float(any(abs(theta - 2 * math.pi / q) < 1e-3 for q in (1, 2, 3, 4)))
        return data


def newton(prob: OrbitProblem, u, newton_tol: float, max_iter: int) -> tuple[str, np.ndarray, int, np.ndarray]:
    """(status: converged, not_converged, nonfinite or guess; u; iterations; residual) of Gauss-Newton with the
    phase condition relative to the start u."""
    scale = prob.scale
    prob.set_reference(u)

    def norm(F):
        return float(np.linalg.norm(F)) if np.all(np.isfinite(F)) else math.inf

    F = prob.residual(u)
    if not np.isfinite(norm(F)):
        return "guess", u, 0, F
    it = 0
    for it in range(1, max_iter + 1):
        step = prob.linearise(u, scale).solve(-F)
        if not np.all(np.isfinite(step)):
            return "not_converged", u, it, F
        r0, lam = norm(F), min(1.0, MAX_NEWTON_STEP / max(np.max(np.abs(step)), 1e-300))
        while True:
            trial = u + lam * step * scale
            F_trial = prob.residual(trial)
            if norm(F_trial) <= max(r0, 1e-300) * (1 - 1e-4 * lam) or lam < 1e-4 or norm(F_trial) < 1e-12:
                break
            lam *= 0.5
        if not np.isfinite(norm(F_trial)):
            return "nonfinite", u, it, F
        u, F = trial, F_trial
        if lam * np.max(np.abs(step)) <= newton_tol * (1.0 + np.max(np.abs(u / scale))):
            converged = np.all(np.abs(F) <= 1e-9 * (1.0 + prob.linearise(u, np.ones(len(u))).magnitude(u)))
            return ("converged" if converged else "not_converged"), u, it, F
    return "not_converged", u, it, F


def orbit_size(states: np.ndarray, scale) -> float:
    """The largest distance of ``states`` (k, n) from their mean, in scaled states."""
    d = (states - states.mean(axis=0)) / np.asarray(scale)
    return float(np.sqrt((d * d).sum(axis=1)).max())


def multipliers_decide(nontrivial: np.ndarray, flow_error: float) -> bool:
    """Whether multipliers whose flow direction's is off 1 by ``flow_error`` (their error scale) decide stability and
    the test functions: the error is at most TRIVIAL_TOL, or at most DECIDING_SHARE of the distance of the
    ``nontrivial`` ones from the unit circle (where every one of them crosses) and at most DECIDING_CAP, or in log
    modulus, log(1 + error) at most DECIDING_SHARE of min |log |mu|| (a multiplier 1e-20 or 1e40 stays on its side
    of the circle under an error that moves the flow direction's by 50 %)."""
    if not len(nontrivial):
        return bool(flow_error <= TRIVIAL_TOL)
    modulus = np.abs(nontrivial)
    margin = float(np.min(np.abs(modulus - 1.0)))
    with np.errstate(divide="ignore"):
        log_margin = float(np.min(np.abs(np.log(modulus))))
    return bool(flow_error <= max(TRIVIAL_TOL, min(DECIDING_SHARE * margin, DECIDING_CAP))
                or math.log1p(flow_error) <= DECIDING_SHARE * log_margin)


def flow_multiplier_error(eigen: tuple, flow_direction: np.ndarray) -> float:
    """|mu - 1| of the multiplier whose eigenvector is the flow direction's (``eigen``: values, vectors)."""
    mu, flow = floquet(None, flow_direction, 1, eigen)
    return float(np.abs(mu[flow][0] - 1.0))


def _signed_product(values: np.ndarray) -> float:
    """Real part of prod(values) without over/underflow: sign times a bounded magnitude."""
    prod = complex(1.0)
    log_mag = 0.0
    for v in np.asarray(values, dtype=complex):
        a = abs(v)
        if a == 0:
            return 0.0
        prod *= v / a
        log_mag += math.log(a)
    return float(prod.real * math.exp(max(min(log_mag, 600.0), -600.0)))


@dataclass
class PeriodicOrbit:
    """A periodic orbit (status ``converged``) or the outcome of a Newton search that found none."""

    status: str  # a key of STATUS
    message: str
    system: System
    pars: np.ndarray
    states: np.ndarray  # (m, n) node states: shooting segment starts (m = segments); collocation x(0) (m = 1)
    period: float
    value: float | None  # the continuation parameter's value (None: no parameter)
    parameter: str | None
    residual: float  # max residual of the discretised orbit equations / scale
    iterations: int
    multipliers: np.ndarray  # complex (n,), by modulus descending
    trivial: np.ndarray  # bool (n,)
    times: np.ndarray  # (N,) sample times in [0, T)
    samples: np.ndarray  # (N, n)
    observables: np.ndarray  # (N, n_obs)
    method: str = "shooting"  # the discretisation: shooting or collocation
    discretisation_error: float | None = None  # collocation: estimated max error of x(t) / scale (shooting: None)
    mesh: np.ndarray | None = None  # collocation: the mesh (ntst + 1 times in [0, 1])
    flow_multiplier_error: float = math.nan  # |mu - 1| of the flow direction's multiplier: the multipliers' check
    multiplier_source: str = "shooting"  # the shooting monodromy, "collocation" (its condensed blocks) or "none"
    # (not computed: a singular block, the reason in the message)

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    @property
    def multipliers_reliable(self) -> bool:
        """Whether the multipliers pass their check (:func:`multipliers_decide`; else they decide no stability)."""
        return multipliers_decide(self.multipliers[~self.trivial], self.flow_multiplier_error)

    def classification(self) -> tuple[int, int]:
        """(stability flag, multipliers outside the unit circle): ``marginal`` and 0 where the multipliers fail
        their check."""
        return classify(self.multipliers, self.trivial) if self.multipliers_reliable else (STABILITY["marginal"], 0)

    @property
    def stability(self) -> int:
        return self.classification()[0]

    @property
    def n_unstable(self) -> int:
        return self.classification()[1]

    @property
    def amplitude(self) -> float:
        """``max_t |x(t) - mean x|`` in scaled units (x / state_scale)."""
        d = (self.samples - self.samples.mean(axis=0)) / np.asarray(self.system.state_scale)
        return float(np.sqrt((d * d).sum(axis=1)).max())

    @property
    def exponents(self) -> np.ndarray:
        """Floquet exponents log|mu| / T [1/s] (the growth rates of perturbations)."""
        with np.errstate(divide="ignore"):
            return np.log(np.abs(self.multipliers)) / self.period

"""The one declaration of a dynamical system x' = f(x; p) that every analysis of :mod:`.dynamics` takes.

A :class:`System` holds heyoka expressions: variables, right-hand sides, named runtime parameters (the
i-th parameter is ``hy.par[i]``), and optionally state names and scales, observables, first integrals,
terminal events and the number of trivial Floquet multipliers. It checks the declaration once (one
line naming any clash) and builds on demand, caching per instance, what the analyses need: the compiled
right-hand side and observables, derivative tensors of orders 1-3 (:mod:`.tensors`), and scalar, batch
and variational Taylor integrators. heyoka keeps the machine code in its disk cache as well, so a second
process starts fast; a second analysis of the same ``System`` in one process compiles nothing.

Integrators are templates: an analysis copies one (``copy.copy``) before it changes its state.
"""

from __future__ import annotations

import copy
import hashlib
import numbers
import threading
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from ..compilation import compiling
from ..errors import ParameterError
from .expressions import expand_integer_powers
from .tensors import Field

RESERVED = frozenset({
    "point", "eig", "eig_real", "eig_imag", "stability", "n_unstable", "max_real_eig", "arclength", "residual",
    "newton_iterations", "special_point", "special_kind", "special_label", "special_index", "special_value",
    "special_frequency", "special_l1", "special_degenerate", "special_smooth", "special_a", "rejection", "unlocated",
    "critical_product", "period", "floquet", "sample", "state", "orbit", "orbit_status", "amplitude",
    "multiplier_real", "multiplier_imag", "trivial", "time", "exponent",
    "exponents", "history", "history_time", "divergence_mean", "attractor", "outcome", "label", "crossing",
    "parameter", "value", "sample_time", "t", "tol"})
"""Names the generic datasets use for their own dimensions and variables: no state, parameter or
observable may take one (a dataset could not hold both)."""

_COMPILED: dict = {}  # (System.key, what) -> compiled object: shared by Systems of the same equations
_LOCK = threading.RLock()

DIRECTIONS = {"negative": hy.event_direction.negative, "positive": hy.event_direction.positive,
              "any": hy.event_direction.any}


@dataclass(frozen=True)
class Event:
    """A terminal event: the run ends where ``expression`` crosses zero in ``direction``; ``name`` becomes the
    run's status (e.g. ``fell``)."""

    name: str
    expression: object
    direction: str = "negative"

    def __post_init__(self):
        object.__setattr__(self, "expression", expand_integer_powers(self.expression))
        if self.direction not in DIRECTIONS:
            raise ParameterError(f"event {self.name!r}: direction {self.direction!r}; give one of "
                                 f"{', '.join(DIRECTIONS)}")


def _article(word: str) -> str:
    return ("an " if word[0] in "aeiou" else "a ") + word


def parameter_indices(expressions) -> set[int]:
    """The indices i of the hy.par[i] that ``expressions`` use."""
    return {int(str(p)[1:]) for p in hy.get_params(list(expressions))}


class System:
    """x' = f(x; p): heyoka ``variables`` and right-hand sides ``rhs``; ``parameters`` {name: default value}
    in the order of hy.par[0], hy.par[1], ...

    Optional: ``state_names`` (default the variables' names); ``state_scale`` (typical magnitudes: the metric
    of Newton steps and continuation, default 1); ``observables`` {name: expression or (expression, units)}:
    quantities of the state (stored along orbits, pinned by equilibrium problems); ``integrals`` {name:
    expression}: first integrals (their levels are pinned where orbits come in families); ``events``
    (:class:`Event`, terminal); ``n_trivial``: trivial Floquet multipliers (1 + independent integrals or
    families); ``units`` {state or parameter name: UDUNITS units}, ``time_units`` (default "1"): undeclared
    units are taken as dimensionless ("1") in the datasets; ``compact_mode``: heyoka's compact mode for large
    systems; ``strict_parameters`` (default True): every parameter must appear in an expression (False for a
    hybrid system's mode whose guards or jumps use parameters its equations do not).
    """

    def __init__(self, name: str, variables, rhs, parameters: dict | None = None, *, state_names=None,
                 state_scale=None, observables: dict | None = None, integrals: dict | None = None, events=(),
                 n_trivial: int = 1, units: dict | None = None, time_units: str = "1", compact_mode: bool = False,
                 description: str = "", strict_parameters: bool = True):
        if not isinstance(name, str) or not name:
            raise ParameterError("a System needs a name (a non-empty string), e.g. System('ab', ...)")
        self.name = name
        self.variables = tuple(variables)
        self.declared_rhs = tuple(hy.expression(f) if isinstance(f, int | float) else f for f in rhs)
        self.rhs = tuple(map(expand_integer_powers, self.declared_rhs))  # safe at zero bases (.expressions)
        if len(self.rhs) != len(self.variables) or not self.variables:
            raise ParameterError(f"system {name!r}: {len(self.variables)} variables but {len(self.rhs)} right-hand "
                                 "sides; give one right-hand side per variable")
        self.state_names = tuple(str(v) for v in self.variables) if state_names is None else tuple(state_names)
        if len(self.state_names) != self.n:
            raise ParameterError(f"system {name!r}: {len(self.state_names)} state names for {self.n} variables")
        self.parameters = dict(parameters or {})
        self.parameter_names = tuple(self.parameters)
        self.pars = np.array([float(v) for v in self.parameters.values()], dtype=float)
        self.state_scale = np.ones(self.n) if state_scale is None else np.array(state_scale, dtype=float)
        if self.state_scale.shape != (self.n,) or not np.all(self.state_scale > 0):
            raise ParameterError(f"system {name!r}: state_scale needs {self.n} positive numbers")
        self.observables = {k: (expand_integer_powers(e), u) for k, (e, u) in
                            ((k, v if isinstance(v, tuple) else (v, "")) for k, v in (observables or {}).items())}
        self.integrals = {k: expand_integer_powers(e) for k, e in (integrals or {}).items()}
        self.events = tuple(events)
        self.n_trivial = int(n_trivial)
        self.units = dict(units or {})
        self.time_units = str(time_units)
        self.compact_mode = bool(compact_mode)
        self.description = description
        self.strict_parameters = bool(strict_parameters)
        self._check_names()
        self._check_parameters()
        self._key = None

    # -- declaration checks
    def _check_names(self) -> None:
        groups = {"state": self.state_names, "parameter": self.parameter_names,
                  "observable": tuple(self.observables),
                  # a first integral may carry the name of the observable it is (the same expression)
                  "integral": tuple(k for k in self.integrals if k not in self.observables)}
        for k, e in self.integrals.items():
            if k in self.observables and str(self.observables[k][0]) != str(e):
                raise ParameterError(f"system {self.name!r}: the integral {k!r} differs from the observable {k!r}; "
                                     "give it another name or the same expression")
        seen: dict[str, str] = {}
        for kind, names in groups.items():
            for n in names:
                if not isinstance(n, str) or not n.isidentifier():
                    raise ParameterError(f"system {self.name!r}: {kind} name {n!r} is not an identifier; give names "
                                         "such as u1 or beta")
                if n in RESERVED:
                    raise ParameterError(f"system {self.name!r}: {kind} name {n!r} is reserved by the datasets "
                                         f"(they hold a {n!r} of their own); rename it")
                if n in seen:
                    raise ParameterError(f"system {self.name!r}: the name {n!r} is both {_article(seen[n])} and "
                                         f"{_article(kind)}; give distinct names")
                seen[n] = kind

    def _check_parameters(self) -> None:
        used_rhs = parameter_indices(self.rhs)
        used = used_rhs | parameter_indices([e for e, _u in self.observables.values()]) | \
            parameter_indices(list(self.integrals.values())) | parameter_indices([e.expression for e in self.events])
        n = len(self.parameter_names)
        beyond = sorted(i for i in used if i >= n)
        if beyond:
            raise ParameterError(f"system {self.name!r}: the expressions use hy.par[{beyond[0]}] but only {n} "
                                 f"parameter(s) are declared ({', '.join(self.parameter_names) or 'none'}); declare "
                                 "one name per hy.par index, in index order")
        unused = [i for i in range(n) if i not in used]
        if unused and self.strict_parameters:
            raise ParameterError(f"system {self.name!r}: parameter {self.parameter_names[unused[0]]!r} "
                                 f"(hy.par[{unused[0]}]) appears in no expression; drop it or use it (a hybrid mode "
                                 "whose guards or jumps use it: strict_parameters=False)")

    # -- names and parameter vectors
    @property
    def n(self) -> int:
        return len(self.variables)

    @property
    def key(self) -> str:
        """A fingerprint of the declaration but the default parameter values: its name, names and expressions
        (datasets store it; a stored branch is continued with the same System; compiled code is shared by it)."""
        if self._key is None:
            parts = [self.name, *self.state_names, *map(str, self.variables), *map(str, self.declared_rhs),
                     *self.parameter_names, *(f"{k}={e}" for k, (e, _u) in self.observables.items()),
                     *(f"{k}={e}" for k, e in self.integrals.items()),
                     *(f"{e.name}:{e.direction}={e.expression}" for e in self.events), str(self.compact_mode)]
            self._key = hashlib.sha256("|".join(parts).encode()).hexdigest()[:16]
        return self._key

    def with_defaults(self, pars=None, **values) -> System:
        """The same system with other default parameter values (``pars`` and/or by name); it shares the
        compiled code."""
        new = copy.copy(self)
        new.pars = self.with_pars(pars, **values)
        new.parameters = dict(zip(self.parameter_names, map(float, new.pars)))
        return new

    def with_events(self, name: str, events) -> System:
        """The same equations under ``name`` with the terminal ``events`` added after its own (e.g. the guards
        of a hybrid system's mode); compiled separately (its key differs)."""
        return System(name, self.variables, self.declared_rhs, self.parameters, state_names=self.state_names,
                      state_scale=self.state_scale, observables=self.observables, integrals=self.integrals,
                      events=(*self.events, *events), n_trivial=self.n_trivial, units=self.units,
                      time_units=self.time_units, compact_mode=self.compact_mode, description=self.description,
                      strict_parameters=False)

    def with_observables(self, name: str, observables: dict) -> System:
        """The same equations under ``name`` with ``observables`` {name: expression or (expression, units)} added
        after its own (e.g. a quantity's rate, :meth:`rate_of`, to section a run at its extrema)."""
        added = {}
        for key, value in dict(observables).items():
            expression, units = value if isinstance(value, tuple) and len(value) == 2 else (value, "")
            added[key] = (self._expression(expression, f"observable {key!r}"), str(units))
        return System(name, self.variables, self.declared_rhs, self.parameters, state_names=self.state_names,
                      state_scale=self.state_scale, observables={**self.observables, **added},
                      integrals=self.integrals, events=self.events, n_trivial=self.n_trivial, units=self.units,
                      time_units=self.time_units, compact_mode=self.compact_mode, description=self.description,
                      strict_parameters=self.strict_parameters)

    def rate_of(self, expression):
        """d/dt of ``expression`` (of the states and parameters) along the flow: grad(expression) . f."""
        gradient = self.gradient_expressions([self._expression(expression, "rate_of")])
        return expand_integer_powers(hy.sum([g * f for g, f in zip(gradient, self.rhs)]))

    def _expression(self, value, what: str):
        """``value`` as a heyoka expression (numbers become constants); a one-line error for anything else."""
        if isinstance(value, hy.expression):
            return value
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            return hy.expression(float(value))
        raise ParameterError(f"{what}: {value!r} is a {type(value).__name__}; give a heyoka expression of "
                             f"{self.name}'s variables ({', '.join(self.state_names)}) and hy.par[i]")

    def parameter_index(self, name: str) -> int:
        if name not in self.parameter_names:
            raise ParameterError(f"{self.name} has no parameter {name!r}; choose one of "
                                 f"{', '.join(self.parameter_names) or '(none)'}")
        return self.parameter_names.index(name)

    def state_index(self, name: str) -> int:
        if name not in self.state_names:
            raise ParameterError(f"{self.name} has no state {name!r}; choose one of {', '.join(self.state_names)}")
        return self.state_names.index(name)

    def with_pars(self, pars=None, **values) -> np.ndarray:
        """The runtime parameter vector (default values, or ``pars``: a vector, or {name: value} over the defaults)
        with some values replaced by name."""
        if isinstance(pars, dict):
            return self.with_pars(None, **{**pars, **values})
        try:
            out = self.pars.copy() if pars is None else np.array(pars, dtype=float).copy()
        except (TypeError, ValueError):
            raise ParameterError(f"pars = {pars!r}: give {len(self.pars)} numbers ({', '.join(self.parameter_names)})"
                                 " or a dict of them by name") from None
        if out.shape != self.pars.shape:
            raise ParameterError(f"{self.name} has {len(self.pars)} parameters ({', '.join(self.parameter_names)}), "
                                 f"not {out.size}")
        for name, value in values.items():
            out[self.parameter_index(name)] = float(value)
        return out

    def units_of(self, name: str) -> str:
        """UDUNITS units of a state, parameter or observable ("1" where none were declared)."""
        if name in self.observables:
            return self.observables[name][1] or "1"
        return self.units.get(name, "1")

    def per_time(self, units: str = "1") -> str:
        """``units`` per time unit, e.g. "rad s-1" (time in s), "rad" (dimensionless time)."""
        if self.time_units == "1":
            return units
        return f"{self.time_units}-1" if units == "1" else f"{units} {self.time_units}-1"

    def equations(self) -> list[str]:
        """The right-hand sides as text, e.g. "u1' = ..." (for the datasets' attributes: to read, not to eval)."""
        return [f"{n}' = {f}" for n, f in zip(self.state_names, self.declared_rhs)]

    def attrs(self, pars=None) -> dict:
        """The attributes generic datasets carry: name, fingerprint, names, equations, parameter values."""
        pars = self.pars if pars is None else np.asarray(pars, dtype=float)
        return {"system": self.name, "system_key": self.key, "state_names": " ".join(self.state_names),
                "parameter_names": " ".join(self.parameter_names),
                "system_equations": "; ".join(self.equations()),
                "system_parameters": "; ".join(f"{k} = {float(v)!r}" for k, v in zip(self.parameter_names, pars))}

    # -- compiled code (built on demand, cached for every System of these equations)
    def _cached(self, key, what: str, build):
        with _LOCK:
            full = (self.key, key)
            if full not in _COMPILED:
                with compiling(f"{what} of {self.name}"):
                    _COMPILED[full] = build()
            return _COMPILED[full]

    def compiled_count(self) -> int:
        """How many compiled objects exist for these equations (a second analysis should add none it reuses)."""
        with _LOCK:
            return sum(1 for k in _COMPILED if k[0] == self.key)

    def field(self, pins=(), parameters=()) -> Field:
        """The right-hand side followed by the observables named in ``pins``, with exact derivative tensors with
        respect to the states and the runtime parameters ``parameters`` (names or indices, in that order)."""
        pins = tuple(pins)
        for p in pins:
            if p not in self.observables:
                raise ParameterError(f"{self.name} has no observable {p!r} to pin; it has "
                                     f"{', '.join(self.observables) or 'none'}")
        indices = tuple(i if isinstance(i, int) else self.parameter_index(i) for i in parameters)
        outputs = [*self.rhs, *(self.observables[p][0] for p in pins)]
        return self._cached(("field", pins, indices), "the derivative tensors",
                            lambda: Field(outputs, self.variables, [hy.par[i] for i in indices]))

    def integrals_field(self) -> Field:
        """The first integrals (declaration order) with exact derivative tensors with respect to the states."""
        exprs = list(self.integrals.values())
        return self._cached(("integrals",), "the first integrals", lambda: Field(exprs, self.variables))

    def jacobian_function(self):
        """cfunc of the Jacobian d rhs / d x, row-major (n * n outputs), for batches of states."""
        def build():
            jac = hy.diff_tensors(list(self.rhs), diff_args=list(self.variables), diff_order=1).jacobian
            return hy.cfunc(list(np.asarray(jac).ravel()), list(self.variables))

        return self._cached(("jacobian",), "the Jacobian", build)

    def jacobian(self, states, pars=None) -> np.ndarray:
        """Exact Jacobians at states (n,) or (n, N): (n, n) or (N, n, n)."""
        x = np.asarray(states, dtype=float)
        out = self.evaluate(self.jacobian_function(), x.reshape(self.n, -1), self.pars if pars is None else pars)
        J = out.T.reshape(-1, self.n, self.n)
        return J[0] if x.ndim == 1 else J

    def linearisation_function(self, parameters=()):
        """cfunc of f, d f / d x (row-major) and d f / d p for the runtime ``parameters`` (names or indices; row-major,
        n * k) in one call over batches of states: n + n * n + n * k outputs (collocation)."""
        indices = tuple(i if isinstance(i, int) else self.parameter_index(i) for i in parameters)

        def build():
            args = [*self.variables, *(hy.par[i] for i in indices)]
            jac = np.asarray(hy.diff_tensors(list(self.rhs), diff_args=args, diff_order=1).jacobian)
            outputs = [*self.rhs, *jac[:, : self.n].ravel(), *jac[:, self.n:].ravel()]
            return hy.cfunc(outputs, list(self.variables))

        return self._cached(("linearisation", indices), "the linearisation", build)

    def rhs_function(self):
        """cfunc of the right-hand side over the states."""
        return self._cached(("rhs",), "the right-hand side", lambda: hy.cfunc(list(self.rhs), list(self.variables)))

    def observables_function(self):
        """cfunc of the observables (in declaration order) over the states, or None without observables."""
        if not self.observables:
            return None
        exprs = [e for e, _u in self.observables.values()]
        return self._cached(("observables",), "the observables", lambda: hy.cfunc(exprs, list(self.variables)))

    def function(self, label: str, expressions, what: str = "a function"):
        """cfunc of ``expressions`` (of this system's states and runtime parameters) over the states, compiled
        once per process for these equations and ``label`` (e.g. a guard's gradient, a jump's reset)."""
        exprs = [hy.expression(e) if isinstance(e, int | float) else e for e in expressions]
        key = ("function", label, tuple(map(str, exprs)))
        return self._cached(key, what, lambda: hy.cfunc(exprs, list(self.variables)))

    def gradient_expressions(self, expressions) -> list:
        """Exact Jacobian rows d e / d x of ``expressions``, row-major (len(expressions) * n expressions)."""
        jac = hy.diff_tensors(list(expressions), diff_args=list(self.variables), diff_order=1).jacobian
        return list(np.asarray(jac).ravel())

    def evaluate(self, function, states, pars) -> np.ndarray:
        """A cfunc of this system at states (n,) or (n, N) with pars (p,) or (p, N): (outputs,) or (outputs, N)."""
        x = np.asarray(states, dtype=float)
        if x.ndim not in (1, 2) or x.shape[0] != self.n or (x.ndim == 1 and x.size != self.n):
            raise ParameterError(f"system {self.name!r}: states of shape {x.shape}; give ({self.n},) or ({self.n}, N), "
                                 f"one state per column (transpose an (N, {self.n}) array of rows)")
        X = np.ascontiguousarray(x.reshape(self.n, -1))
        if function.nparams == 0:
            out = function(X)
        else:
            P = np.asarray(pars, dtype=float)
            P = np.repeat(P[:, None], X.shape[1], axis=1) if P.ndim == 1 else P
            out = function(X, pars=np.ascontiguousarray(P[: function.nparams]))
        return out[:, 0] if x.ndim == 1 else out

    def f(self, states, pars=None) -> np.ndarray:
        """The right-hand side at states (n,) or (n, N)."""
        return self.evaluate(self.rhs_function(), states, self.pars if pars is None else pars)

    def observe(self, states, pars=None) -> dict[str, np.ndarray]:
        """The observables at states (n,) or (n, N), by name."""
        cf = self.observables_function()
        if cf is None:
            return {}
        return dict(zip(self.observables, self.evaluate(cf, states, self.pars if pars is None else pars)))

    def taylor(self, tol: float, *, batch: int = 0, tangents: int = 0, parameters=(), events=False,
               nt_events=(), extra=(), compact_mode: bool | None = None):
        """A Taylor integrator template (copy it before use).

        batch: SIMD lanes (0: scalar); tangents: k first-order variations with respect to the first k initial
        states (Lyapunov vectors; ``parameters`` adds variations with respect to those runtime parameters,
        names or indices, after ``tangents`` = n for shooting); events: the System's terminal events (True:
        all; or a tuple of their names: those, in that order); nt_events: (expression, callback, direction)
        non-terminal events (heyoka calls the callback, copied with the integrator); extra: (variable, rhs)
        pairs appended to the system (quadratures such as a divergence integral); compact_mode: heyoka's
        compact mode (default the System's).
        The state holds x, then the variations (heyoka's var_ode_sys layout), then ``extra``; the integrator's
        ``pars`` hold the first ``len(ta.pars)`` runtime parameters (those up to the last one its equations use).
        """
        indices = tuple(i if isinstance(i, int) else self.parameter_index(i) for i in parameters)
        extra, nt_events = tuple(extra), tuple(nt_events)
        t_events = self.terminal_events(events)
        compact = self.compact_mode if compact_mode is None else bool(compact_mode)
        key = ("taylor", float(tol), int(batch), int(tangents), indices, tuple(e.name for e in t_events),
               tuple((str(x), type(c).__name__, d) for x, c, d in nt_events), tuple(map(str, extra)), compact)

        def build():
            sys = list(zip(self.variables, self.rhs))
            if tangents or indices:
                sys = hy.var_ode_sys(sys, [*self.variables[:tangents], *(hy.par[i] for i in indices)], order=1)
                equations = list(sys.sys)
                if extra:  # a plain integrator of the variational equations and the quadratures
                    sys = equations = equations + list(extra)
            else:
                sys = equations = sys + list(extra)
            size = len(equations)
            used = parameter_indices([f for _v, f in equations] + [e.expression for e in t_events]
                                     + [x for x, _c, _d in nt_events])
            n_par = max(used) + 1 if used else 0  # heyoka wants exactly the parameters the equations use
            kwargs = {"tol": float(tol), "compact_mode": compact}
            t_make = hy.t_event_batch if batch else hy.t_event
            nt_make = hy.nt_event_batch if batch else hy.nt_event
            if t_events:
                kwargs["t_events"] = [t_make(e.expression, direction=DIRECTIONS[e.direction]) for e in t_events]
            if nt_events:
                kwargs["nt_events"] = [nt_make(x, c, direction=DIRECTIONS[d]) for x, c, d in nt_events]
            if batch:
                return hy.taylor_adaptive_batch(sys, np.zeros((size, batch)), pars=np.zeros((n_par, batch)), **kwargs)
            return hy.taylor_adaptive(sys, np.zeros(size), pars=np.zeros(n_par), **kwargs)

        what = "the " + ("batch " if batch else "") + ("variational " if tangents or indices else "") + "integrator"
        return self._cached(key, what, build)

    @staticmethod
    def stopping_event(outcome, events) -> int | None:
        """Index into ``events`` (the terminal events the integrator got) of the one that stopped heyoka with
        ``outcome``; None for any other outcome (time limit, callback, non-finite state)."""
        index = -int(outcome) - 1
        return index if 0 <= index < len(events) else None

    def terminal_events(self, events) -> tuple:
        """The terminal events an integrator gets: True (all), False (none) or their names in order."""
        if events is True:
            return self.events
        if not events:
            return ()
        by_name = {e.name: e for e in self.events}
        unknown = [n for n in events if n not in by_name]
        if unknown:
            raise ParameterError(f"{self.name} has no event {unknown[0]!r}; it has {', '.join(by_name) or 'none'}")
        return tuple(by_name[n] for n in events)

    def __repr__(self) -> str:
        return (f"System({self.name!r}: {self.n} states {', '.join(self.state_names)}; parameters "
                f"{', '.join(self.parameter_names) or 'none'})")

"""Poincaré sections of the ODE models (Sect. 4.1) with heyoka non-terminal events.

A section is a named quantity of the state at a level, written ``"NAME=LEVEL"``:

* ``beta_dot=0`` -- the inclination rate (3.8) vanishes (turning points of beta);
* ``gamma=pi/2`` -- the disk passes the inverted orientation (gamma is unwrapped in ODE Model 1);
* ``alpha mod 2pi=0`` -- the precession angle passes 0 modulo 2 pi.

NAME is a state variable or an output of :data:`tippedisk_analysis.models.ode.OUTPUT_NAMES`;
LEVEL is a number, optionally with ``pi`` (``-pi/2``, ``3*pi/4``). The event function is
``q - LEVEL``, or ``sin(q - LEVEL)`` for ``mod 2pi`` sections, where only crossings with
``cos(q - LEVEL) > 0`` count (so the direction is that of q). The level is a runtime
parameter: one compiled integrator per (model, quantity, mod, direction, tol) serves all levels.

Crossings are located by heyoka's polynomial root finding on the Taylor expansion of the
step and the state there is the dense output at the event time (``update_d_output``), so
the section holds to about the integrator tolerance.
"""

from __future__ import annotations

import ast
import math
import operator
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..dynamics.poincare import crossings as generic_crossings
from ..dynamics.poincare import section_template
from ..errors import ParameterError
from ..defaults import FALL_ANGLE, SLIP_SMOOTHING, TAYLOR_TOL
from ..models import ode
from ..models.variables import quantities
from ..parameters import InitialState, Setup, to_dict
from ..results import describe, index_coordinate, make_attrs

__all__ = ["Section", "parse_section", "poincare_section", "crossings"]

DIRECTIONS = ("positive", "negative", "any")
LEVEL_INDEX = len(ode.PARAMETER_NAMES)  # hy.par index of the section level


@dataclass(frozen=True)
class Section:
    """``quantity (mod 2 pi if modulo) = level``, crossed in ``direction``."""

    quantity: str
    level: float
    modulo: bool = False
    direction: str = "positive"

    @property
    def label(self) -> str:
        q = f"{self.quantity} mod 2pi" if self.modulo else self.quantity
        return f"{q}={self.level:.17g}"


_OPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}


def parse_level(text: str) -> float:
    """A number or a small arithmetic expression with ``pi`` (e.g. ``-pi/2``)."""

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
            return -ev(node.operand) if isinstance(node.op, ast.USub) else ev(node.operand)
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        raise ValueError

    try:
        value = ev(ast.parse(text.strip(), mode="eval"))
    except (SyntaxError, ValueError, ZeroDivisionError):
        raise ParameterError(f"section level {text!r} is not a number; give e.g. 0, 1.2, pi/2 or -pi/2") from None
    if not math.isfinite(value):
        raise ParameterError(f"section level {text!r} is not finite")
    return value


def parse_section(spec: str, direction: str = "positive", model_name: str = "ode-euler") -> Section:
    """Parse ``"NAME=LEVEL"`` or ``"NAME mod 2pi=LEVEL"``."""
    if direction not in DIRECTIONS:
        raise ParameterError(f"direction {direction!r} unknown; give one of {', '.join(DIRECTIONS)}")
    if spec.count("=") != 1:
        raise ParameterError(f"section {spec!r} is not NAME=LEVEL; give e.g. beta_dot=0, gamma=pi/2 "
                             "or 'alpha mod 2pi=0'")
    name, level = (s.strip() for s in spec.split("="))
    modulo = False
    for suffix in ("mod 2pi", "mod 2*pi", "%2pi"):
        if name.replace(" ", "").endswith(suffix.replace(" ", "")):
            modulo = True
            name = name.replace(" ", "")[: -len(suffix.replace(" ", ""))]
            break
    names = quantities(model_name)
    if name not in names:
        raise ParameterError(f"section quantity {name!r} unknown for model {model_name}; choose one of "
                             f"{', '.join(names)}")
    return Section(name, parse_level(level), modulo, direction)


LIFT_OFF = {"lift_off": ("lambda_N", "negative")}  # watched, not terminal: the first time the contact would open


def compile_section(model_name: str, section: Section, tol: float):
    """The compiled section integrator of ``model_name`` (for a sweep's workers to load before they run)."""
    return section_template(ode.as_system(ode.MODELS[model_name]), section.quantity, direction=section.direction,
                            modulo=section.modulo, tol=float(tol), events=("fell",), watch=LIFT_OFF)


@dataclass
class Crossings:
    times: np.ndarray
    states: np.ndarray  # (n, n_state)
    status: str
    message: str
    t_final: float
    n_steps: int
    lift_off_time: float | None  # first zero of lambda_N (None: the contact held)


def crossings(section: Section, *, model_name: str = "ode-euler", setup: Setup | None = None,
              initial: InitialState | np.ndarray | None = None, t_transient: float = 0.0, t_end: float = 10.0,
              max_crossings: int | None = None, tol: float = TAYLOR_TOL, fall_angle: float = FALL_ANGLE,
              slip_smoothing: float = SLIP_SMOOTHING) -> Crossings:
    """The section's crossings by the ODE model's run from ``initial`` (an InitialState, or a full state vector of
    the model): the generic section of the model's System (:func:`tippedisk_analysis.dynamics.poincare.crossings`)
    with the fall terminal and the lift-off watched."""
    _check(t_transient, t_end, max_crossings, tol, fall_angle)
    setup, initial = setup or Setup(), initial if initial is not None else InitialState()
    model = ode.MODELS[model_name]
    x0 = initial if isinstance(initial, np.ndarray) else ode.initial_state_vector(model, setup, initial)
    cr = generic_crossings(ode.as_system(model), x0, section.quantity, section.level,
                           pars=ode.parameter_vector(setup, fall_angle, slip_smoothing), direction=section.direction,
                           modulo=section.modulo, t_end=t_end, transient=t_transient, max_crossings=max_crossings,
                           tol=tol, events=("fell",), watch=LIFT_OFF)
    n = len(cr.times)
    if cr.status == "completed" and cr.t_final < t_end:
        message = f"collected {n} crossing(s) by t = {cr.t_final:.6g} s"
    elif cr.status == "completed":
        message = f"reached t_end = {t_end:g} s with {n} crossing(s)"
    elif cr.status == "fell":
        message = f"the disk fell (tilt down to {fall_angle:g} rad) at t = {cr.t_final:.6g} s after {n} crossing(s)"
    else:
        message = f"integration stopped at t = {cr.t_final:.6g} s; try a smaller tol"
    lift_off = cr.first["lift_off"]
    if lift_off is not None:
        message += (f"; lambda_N < 0 from t = {lift_off:.6g} s: the disk would lift off, outside the bilateral "
                    "model's validity")
    return Crossings(cr.times, cr.states, cr.status, message, cr.t_final, cr.n_steps, lift_off)


def _check(t_transient, t_end, max_crossings, tol, fall_angle) -> None:
    if not (math.isfinite(t_end) and t_end > 0):
        raise ParameterError(f"t_end = {t_end!r} s must be positive; give t_end > 0")
    if not (math.isfinite(t_transient) and 0 <= t_transient < t_end):
        raise ParameterError(f"t_transient = {t_transient!r} s must lie in [0, t_end); give a shorter transient")
    if max_crossings is not None and (int(max_crossings) != max_crossings or max_crossings < 1):
        raise ParameterError(f"max_crossings = {max_crossings!r} must be a positive integer")
    if not (math.isfinite(tol) and 0 < tol < 1):
        raise ParameterError(f"tol = {tol!r} must lie in (0, 1); give e.g. 1e-14")
    if not (0 < fall_angle < math.pi / 2):
        raise ParameterError("fall_angle must lie in (0, pi/2) rad; give e.g. 0.1")


def poincare_section(section: str | Section = "beta_dot=0", *, direction: str = "positive",
                     model: str = "ode-euler", setup: Setup | None = None, initial: InitialState | None = None,
                     t_transient: float = 0.0, t_end: float = 10.0, max_crossings: int | None = None,
                     tol: float = TAYLOR_TOL, fall_angle: float = FALL_ANGLE,
                     slip_smoothing: float = SLIP_SMOOTHING) -> xr.Dataset:
    """Poincaré section of one trajectory as a Dataset (dim ``crossing``).

    Integrates from ``initial`` (Table 3 by default) until ``t_end`` [s], ``max_crossings``
    crossings after ``t_transient`` [s], or the fall, whichever comes first. Holds the time,
    the full state and the outputs (Euler rates, z_S, energies, ...) at each crossing.
    """
    from ..solvers import resolve

    model_name = resolve(model).name
    if model_name == "hybrid-euler":
        sec = section if isinstance(section, Section) else parse_section(section, direction, "ode-euler")
        return _hybrid_section(sec, setup or Setup(), initial or InitialState(), t_transient, t_end, max_crossings,
                               tol, fall_angle, slip_smoothing)
    if model_name not in ode.MODELS:
        raise ParameterError(f"Poincaré sections need an ODE model (ode-euler, ode-quaternion) or the hybrid model "
                             f"(hybrid-euler), not {model!r}")
    sec = section if isinstance(section, Section) else parse_section(section, direction, model_name)
    setup, initial = setup or Setup(), initial or InitialState()
    cr = crossings(sec, model_name=model_name, setup=setup, initial=initial, t_transient=t_transient,
                   t_end=t_end, max_crossings=max_crossings, tol=tol, fall_angle=fall_angle,
                   slip_smoothing=slip_smoothing)
    m = ode.MODELS[model_name]
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    data = dict(zip(m.state_names, cr.states.T))
    observed = ode.as_system(m).observe(cr.states.T, pars) if len(cr.times) else {}
    for name in ode.OUTPUT_NAMES:
        data.setdefault(name, observed.get(name, np.empty(0)))
    run = {"setup": setup, "initial": initial, "t_transient": t_transient, "t_end": t_end,
           "max_crossings": max_crossings, "tol": tol, "fall_angle": fall_angle, "slip_smoothing": slip_smoothing}
    ds = _section_dataset(sec, model_name, m.paper_name, cr.times, data, cr.status, cr.message, run,
                          t_final=cr.t_final, n_steps=cr.n_steps, valid=int(cr.lift_off_time is None),
                          lift_off_time=cr.lift_off_time)
    return describe(ds)


def _section_dataset(sec: Section, model_name: str, paper_model: str, times, data: dict, status: str,
                     message: str, run: dict, **attrs) -> xr.Dataset:
    """The dataset of kind ``poincare`` (dim ``crossing``) from the crossings' times and variables; ``run``:
    setup, initial, t_transient, t_end, max_crossings, tol, fall_angle, slip_smoothing (the configuration)."""
    data = {k: np.asarray(v, dtype=float) for k, v in data.items()}
    data["E_tot"] = data["E_kin"] + data["E_pot"]
    config = {
        "model": model_name, "setup": to_dict(run["setup"]), "initial": to_dict(run["initial"]),
        "section": {"quantity": sec.quantity, "level": sec.level, "modulo": int(sec.modulo),
                    "direction": sec.direction},
        "t_transient": run["t_transient"], "t_end": run["t_end"], "max_crossings": run["max_crossings"],
        "integrator": {"name": "heyoka.taylor_adaptive", "tol": run["tol"], "fall_angle": run["fall_angle"],
                       "slip_smoothing": run["slip_smoothing"]},
    }
    n = len(times)
    ds = xr.Dataset(
        {"time": ("crossing", np.asarray(times, dtype=float)), **{k: ("crossing", v) for k, v in data.items()}},
        coords={"crossing": index_coordinate("crossing", n, "crossing index")},
        attrs=make_attrs("poincare", config, status, message, model=model_name, paper_model=paper_model,
                         section=sec.label, direction=sec.direction, n_crossings=n, **attrs),
    )
    ds["n_crossings"] = ((), np.int64(n), {"units": "1", "long_name": "number of crossings stored"})
    ds["crossing"].attrs.update(units="1", long_name="crossing index (after the transient)")
    return ds


def _hybrid_section(sec: Section, setup: Setup, initial: InitialState, t_transient: float, t_end: float,
                    max_crossings: int | None, tol: float, fall_angle: float, slip_smoothing: float) -> xr.Dataset:
    """The section of a hybrid-euler run: the crossings located by events in the rolling or the sliding mode,
    with the mode at each crossing (as :func:`poincare_section`)."""
    from ..solvers import hybrid

    _check(t_transient, t_end, max_crossings, tol, fall_angle)
    cr = hybrid.section_crossings(setup, initial, sec.quantity, sec.level, modulo=sec.modulo,
                                  direction=sec.direction, t_transient=t_transient, t_end=t_end, tol=tol,
                                  fall_angle=fall_angle, slip_smoothing=slip_smoothing)
    n = len(cr["time"]) if max_crossings is None else min(max_crossings, len(cr["time"]))
    ds = _section_dataset(sec, "hybrid-euler", "event-driven Models 1/2", cr["time"][:n],
                          {name: v[:n] for name, v in cr["data"].items()}, cr["status"],
                          f"{cr['message']}; {n} crossing(s)",
                          {"setup": setup, "initial": initial, "t_transient": t_transient, "t_end": t_end,
                           "max_crossings": max_crossings, "tol": tol, "fall_angle": fall_angle,
                           "slip_smoothing": slip_smoothing},
                          t_final=cr["t_final"], n_steps=0, valid=int(cr["status"] != "lift_off"),
                          lift_off_time=cr["t_final"] if cr["status"] == "lift_off" else None)
    flags = {"flag_values": np.array(list(hybrid.MODES.values()), np.int8), "flag_meanings": " ".join(hybrid.MODES)}
    ds["mode"] = ("crossing", cr["mode"][:n], {"units": "1", "long_name": "contact mode at the crossing", **flags})
    for name, attrs in hybrid.VARIABLE_ATTRS.items():
        ds[name].attrs.update(attrs)
    return describe(ds)

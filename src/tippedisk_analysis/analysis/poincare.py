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
import copy
import functools
import math
import operator
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..dynamics.poincare import Recorder as _Recorder
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


def _quantity_expression(model: ode.OdeModel, variables, outputs, name: str):
    if name in model.state_names:
        return variables[model.state_names.index(name)]
    return outputs[ode.OUTPUT_NAMES.index(name)]


class _LiftOff:
    """nt_event callback: the first time lambda_N falls through 0 (the contact would open)."""

    def __init__(self):
        self.time = None

    def __call__(self, ta, time, d_sign):
        if self.time is None:
            self.time = float(time)


@dataclass(frozen=True)
class SectionIntegrator:
    model: ode.OdeModel
    integrator: object
    outputs: object  # cfunc of ode.OUTPUT_NAMES
    quantity: object  # cfunc of [q]
    q_index: int | None


@functools.lru_cache(maxsize=32)
def section_integrator(model_name: str, quantity: str, modulo: bool, direction: str, tol: float) -> SectionIntegrator:
    """The model's integrator (terminal event: fell) with the section and the first lift-off recorded (non-terminal
    events), from its System."""
    import heyoka as hy

    model = ode.MODELS[model_name]
    system = ode.as_system(model)
    variables, _sys, _fall, outputs = ode.system(model)
    q = _quantity_expression(model, variables, outputs, quantity)
    level = hy.par[LEVEL_INDEX]
    lambda_N = outputs[ode.OUTPUT_NAMES.index("lambda_N")]
    ta = system.taylor(tol, events=("fell",), nt_events=((hy.sin(q - level) if modulo else q - level, _Recorder(),
                                                          direction), (lambda_N, _LiftOff(), "negative")))
    q_index = model.state_names.index(quantity) if quantity in model.state_names else None
    return SectionIntegrator(model, ta, system.function("outputs", outputs, f"the outputs of {model.paper_name}"),
                             system.function(f"section {quantity}", [q]), q_index)


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
              initial: InitialState | None = None, t_transient: float = 0.0, t_end: float = 10.0,
              max_crossings: int | None = None, tol: float = TAYLOR_TOL, fall_angle: float = FALL_ANGLE,
              slip_smoothing: float = SLIP_SMOOTHING) -> Crossings:
    """Integrate from the initial state and collect the section crossings (raw arrays)."""
    import heyoka as hy

    _check(t_transient, t_end, max_crossings, tol, fall_angle)
    setup, initial = setup or Setup(), initial or InitialState()
    si = section_integrator(model_name, section.quantity, section.modulo, section.direction, float(tol))
    ta = copy.copy(si.integrator)
    pars = np.append(ode.parameter_vector(setup, fall_angle, slip_smoothing), section.level)
    ta.pars[:] = pars
    ta.time = 0.0
    ta.state[:] = ode.initial_state_vector(si.model, setup, initial)
    ta.reset_cooldowns()
    rec, lift_off = (event.callback for event in ta.nt_events)
    lift_off.time = None
    rec.t_transient, rec.level, rec.modulo = float(t_transient), section.level, section.modulo
    rec.q_index, rec.q_func, rec.pars = si.q_index, si.quantity, pars[: si.quantity.nparams]

    step_cb = None
    if max_crossings is not None:
        def step_cb(_ta):
            return len(rec.times) < max_crossings
    outcome, _, _, n_steps, *_ = ta.propagate_until(float(t_end), callback=step_cb)
    times, states = np.array(rec.times), np.array(rec.states).reshape(-1, len(si.model.state_names))
    if max_crossings is not None:
        times, states = times[:max_crossings], states[:max_crossings]
    n = len(times)
    if outcome == hy.taylor_outcome.time_limit:
        status, message = "completed", f"reached t_end = {t_end:g} s with {n} crossing(s)"
    elif max_crossings is not None and n >= max_crossings and outcome == hy.taylor_outcome.cb_stop:
        status, message = "completed", f"collected {n} crossing(s) by t = {ta.time:.6g} s"
    elif int(outcome) == -1:
        status = "fell"
        message = (f"the disk fell (tilt down to {fall_angle:g} rad) at t = {ta.time:.6g} s "
                   f"after {n} crossing(s)")
    else:
        status = "nonfinite"
        message = f"integration stopped ({outcome!r}) at t = {ta.time:.6g} s; try a smaller tol"
        keep = np.all(np.isfinite(states), axis=1)
        times, states = times[keep], states[keep]
    if lift_off.time is not None:
        message += (f"; lambda_N < 0 from t = {lift_off.time:.6g} s: the disk would lift off, outside the bilateral "
                    "model's validity")
    return Crossings(times, states, status, message, float(ta.time), int(n_steps), lift_off.time)


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
    from ..solvers import resolve, taylor

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
    si = section_integrator(model_name, sec.quantity, sec.modulo, sec.direction, float(tol))
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    outs = taylor.evaluate_outputs(si.outputs, cr.states, pars)
    data = dict(zip(m.state_names, cr.states.T))
    for name, values in zip(ode.OUTPUT_NAMES, outs):
        data.setdefault(name, values)
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

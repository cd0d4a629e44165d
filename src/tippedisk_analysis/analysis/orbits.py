"""Periodic orbits of the tippedisk: the reduced system (:func:`.reduced.system`) through the generic shooting
and branches of :mod:`tippedisk_analysis.dynamics`, with what is the disk's.

For mu > 0, eps > 0 and lambda_N > 0 the reduced system has no periodic orbits:
dE/dt = -mu lambda_N |gamma_T|^2 / (|gamma_T| + eps) <= 0, so along a closed orbit the slip vanishes identically,
the friction force vanishes, and the only such motions are the spinning equilibria (docs/continuation.md,
docs/periodic_orbits.md). The searches below run the machinery anyway, from a Hopf point or from a simulation,
and report what Newton finds: an equilibrium or no convergence, with the energy lost over the trial period as
the reason. Without friction (mu = 0) the disk is conservative and families of orbits exist (the end).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..dynamics import continuation
from ..dynamics.flows import TAYLOR_TOL, Flow, FlowError
from ..dynamics.orbit_branches import continue_orbits
from ..dynamics.orbit_datasets import branch_dataset, orbits_dataset
from ..dynamics.orbits import NEWTON_MAX_ITER, STATUS, find_orbit, integral_levels
from ..dynamics.orbit_base import PeriodicOrbit
from ..dynamics.shooting import ShootingProblem
from ..dynamics.system import System
from ..errors import ParameterError
from ..models import ode
from ..models.reduced import STATE_SCALE as TIPPEDISK_SCALE
from ..parameters import Setup, setup_from_dict, to_dict
from ..results import index_coordinate
from . import reduced

__all__ = ["tippedisk_system", "tippedisk_orbits_from_hopf", "tippedisk_orbits_from_run", "tippedisk_lyapunov_orbit",
    "tippedisk_lyapunov_family", "tippedisk_branch_dataset", "orbit_from_dataset"]


def tippedisk_system(setup: Setup | None = None) -> System:
    """The reduced tippedisk as a :class:`~tippedisk_analysis.dynamics.System` with ``setup``'s parameters as its
    defaults: with friction two trivial Floquet multipliers; without (mu = 0) the first integrals E_tot and L_z
    and three (:func:`.reduced.system`). Systems of one kind share their compiled code."""
    pars = ode.parameter_vector(setup)
    conservative = pars[ode.PARAMETER_NAMES.index("mu")] == 0.0
    return reduced.system(frictionless=conservative).with_defaults(pars)


def _energy_change(orbit: PeriodicOrbit) -> float | None:
    """E(x(T)) - E(x_0) along the (trial) orbit [J]: zero on a periodic orbit; None where the flow fails."""
    if orbit.status == "nonfinite":
        return None
    flow = Flow(orbit.system)
    try:
        end = flow.advance(orbit.states[0], orbit.period, orbit.pars)
    except FlowError:
        return None
    e = flow.observables(np.column_stack([orbit.states[0], end]), orbit.pars)[1]
    return float(e[1] - e[0])


def _energy_columns(orbits: list[PeriodicOrbit]) -> dict:
    """``energy_change`` of each orbit and ``energy_change_computed``: 0 where the flow failed over the period
    (the value there is a fill, not the 0 of a periodic orbit)."""
    changes = [_energy_change(orbit) for orbit in orbits]
    return {
        "energy_change": ("point", np.array([0.0 if c is None else c for c in changes]),
                          {"units": "J", "long_name": "E(x(T)) - E(x_0) over the period of the last iterate (0 on a "
                                                      "periodic orbit; a fill where energy_change_computed = 0)"}),
        "energy_change_computed": ("point", np.array([c is not None for c in changes], dtype=np.int8),
                                   {"long_name": "whether the flow over the period could be computed",
                                    "flag_values": np.array([0, 1], np.int8), "flag_meanings": "no yes"}),
    }


def _tippedisk_summary(orbits: list[PeriodicOrbit], what: str) -> tuple[str, str]:
    found = [o for o in orbits if o.converged]
    if found:
        return "completed", f"{what}: {len(found)} periodic orbit(s) found"
    counts = {s: sum(o.status == s for o in orbits) for s in STATUS if s != "converged"}
    parts = ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in counts.items() if v)
    return "no_orbit", (f"{what}: no periodic orbit ({parts}). With friction (mu > 0, eps > 0) the energy "
                        "decreases wherever the disk slips, so no motion but the spinning equilibria closes "
                        "(docs/periodic_orbits.md)")


def tippedisk_orbits_from_hopf(ds: xr.Dataset, label: str, amplitudes=(1e-3, 1e-2, 5e-2), *,
                               max_iter: int = NEWTON_MAX_ITER) -> xr.Dataset:
    """Newton for a periodic orbit of the reduced tippedisk from the Hopf point ``label`` of a continuation
    dataset (kind ``continuation``): guesses x_H + 2 r Re(q) (q the critical eigenvector, unit in scaled
    states) with period 2 pi / omega for each r in ``amplitudes``. Status ``completed`` if an orbit
    converged, else ``no_orbit`` (every point's ``orbit_status`` says what Newton found)."""
    from ..results import config_of
    from . import spin_continuation as sc

    index, kind = sc.special_point(ds, label)
    if kind != "hopf":
        raise ParameterError(f"{label} is a {kind} point; periodic orbits start at a Hopf point (HOPFn)")
    config = config_of(ds)
    setup = setup_from_dict(config["setup"])
    values = {name: float(ds[name].values[index]) for name in sc.PARAMETERS}
    if values["inertia"] != 1.0 or any(n in config.get("free", []) for n in ("eps", "mu", "e")):
        setup = sc._setup_with(setup, {k: v for k, v in values.items() if k != "omega"})
    system = tippedisk_system(setup)
    pars = np.array(system.pars)
    x_h = np.array([float(ds[name].values[index]) for name in reduced.STATE_NAMES])
    J = reduced.jacobian(x_h, pars)[0]
    scale = np.asarray(TIPPEDISK_SCALE)
    vals, vecs = np.linalg.eig(J / scale[:, None] * scale[None, :])  # in scaled states
    k = np.argmin(np.where(vals.imag > 1e-9, np.abs(vals.real), np.inf))
    omega, q = float(vals[k].imag), vecs[:, k] / np.linalg.norm(vecs[:, k])
    orbits = []
    for r in amplitudes:
        guess = x_h + 2 * (r * q).real * scale
        orbits.append(find_orbit(system, guess, 2 * math.pi / omega, pars, max_iter=max_iter))
    status, message = _tippedisk_summary(orbits, f"from {label} (Omega = {values['omega']:.8g} rad/s, frequency "
                                                  f"{omega:.6g} rad/s)")
    extra = {
        "guess_amplitude": ("point", np.asarray(amplitudes, float),
                            {"units": "1", "long_name": "r of the guess x_H + 2 r Re(q) (q unit in scaled states)"}),
        **_energy_columns(orbits),
    }
    cfg = {"source": "hopf", "source_label": label, "source_values": values, "setup": to_dict(setup),
           "amplitudes": list(map(float, amplitudes)), "hopf_frequency": omega, "hopf_state": x_h.tolist()}
    return orbits_dataset(orbits, status, message, cfg, extra=extra)


def tippedisk_returns(setup, initial, t_end: float, *, section: str = "beta_dot=0", tol: float = TAYLOR_TOL):
    """Poincaré returns of an ODE Model 1 run (:mod:`.poincare`): times, reduced states (n, 7), E_tot and
    W_friction at the crossings, and the run's status."""
    from . import poincare

    sec = poincare.parse_section(section)
    cr = poincare.crossings(sec, setup=setup, initial=initial, t_end=t_end, tol=tol)
    names = ode.EULER.state_names
    S = cr.states
    col = {name: S[:, names.index(name)] for name in names}
    X = reduced.reduced_from_full(col["alpha"], col["beta"], col["gamma"], col["x_dot"], col["y_dot"],
                                  col["omega_x"], col["omega_y"], col["omega_z"]).T
    return cr, X, col["W_friction"]


def tippedisk_orbits_from_run(run: xr.Dataset, *, crossing: int = -2, section: str = "beta_dot=0",
                              max_iter: int = NEWTON_MAX_ITER) -> xr.Dataset:
    """Newton for a periodic orbit of the reduced tippedisk from a Poincaré return of a simulation (a dataset
    of kind ``simulation`` of an ODE model; the run is repeated with ODE Model 1 and its section crossings
    located by events). Guess: the reduced state at crossing ``crossing`` and the return time to the next
    (gamma shifted by the multiple of 2 pi it turned). Holds the returns (dim ``crossing``): return time,
    energy and friction work per return, distance between successive returns."""
    from ..parameters import InitialState
    from ..results import config_of

    if run.attrs.get("kind") != "simulation":
        raise ParameterError(f"the dataset is of kind {run.attrs.get('kind')!r}; give a simulation written by "
                             "tippedisk simulate")
    config = config_of(run)
    if config.get("model") not in ode.MODELS:
        raise ParameterError(f"the run is of model {config.get('model')!r}; give a run of an ODE model "
                             "(ode-euler or ode-quaternion): the reduced system is ODE Model 1's")
    setup = setup_from_dict(config["setup"])
    initial = InitialState(**config["initial"])
    cr, X, W = tippedisk_returns(setup, initial, float(config["t_end"]), section=section)
    n = len(cr.times)
    if n < 2:
        raise ParameterError(f"the run has {n} crossing(s) of {section}; give a longer run (two returns needed)")
    if not -n <= crossing < n - 1 or crossing == -1:
        raise ParameterError(f"crossing = {crossing} must index a crossing with a successor (0 .. {n - 2}, or "
                             f"-2 .. -{n})")
    k = crossing % n
    system = tippedisk_system(setup)
    pars = np.array(system.pars)
    flow = Flow(system)
    E = flow.observables(X.T, pars)[1]
    shift = np.zeros(7)
    shift[1] = 2 * math.pi * round((X[k + 1, 1] - X[k, 1]) / (2 * math.pi))
    orbit = find_orbit(system, X[k], float(cr.times[k + 1] - cr.times[k]), pars, shift=shift, max_iter=max_iter)
    status, message = _tippedisk_summary([orbit], f"from the return at t = {cr.times[k]:.6g} s of the run "
                                                  f"({cr.status}, {n} crossings of {section})")
    dE = np.diff(E)
    message += (f"; energy change per return: last {dE[-1]:.3g} J, largest |dE| {np.abs(dE).max():.3g} J, "
                f"every return loses energy: {bool(np.all(dE <= 1e-12))}")
    scale = np.asarray(TIPPEDISK_SCALE)
    wrapped = X.copy()
    wrapped[:, 1] = np.angle(np.exp(1j * X[:, 1]))
    dist = np.linalg.norm(np.diff(wrapped, axis=0) / scale, axis=1)
    extra = {
        "return_time": ("crossing", cr.times, {"units": "s", "long_name": f"time of the crossing of {section}"}),
        "return_period": ("crossing", np.append(np.diff(cr.times), 0.0),
                          {"units": "s", "long_name": "time to the next return (0 at the last)"}),
        "return_energy": ("crossing", E, {"units": "J", "long_name": "total energy at the crossing"}),
        "return_energy_change": ("crossing", np.append(dE, 0.0),
                                 {"units": "J", "long_name": "E_tot at the next return minus E_tot here (0 at the "
                                                             "last)"}),
        "return_friction_work": ("crossing", np.append(np.diff(W), 0.0),
                                 {"units": "J", "long_name": "work of the friction force until the next return"}),
        "return_distance": ("crossing", np.append(dist, 0.0),
                            {"units": "1", "long_name": "|x_(k+1) - x_k| / state_scale between successive returns "
                                                        "(gamma modulo 2 pi)"}),
        "return_state": (("crossing", "state"), X, {"long_name": "reduced state at the crossing"}),
        **_energy_columns([orbit]),
    }
    cfg = {"source": "run", "run_config": config, "section": section, "crossing": int(k),
           "setup": to_dict(setup), "model_used": "ode-euler"}
    ds = orbits_dataset([orbit], status, message, cfg, extra=extra)
    ds = ds.assign_coords(crossing=index_coordinate("crossing", n, "crossing index"))
    return ds


# ============================================================================ the frictionless tippedisk
#
# With mu = 0 the disk is conservative (energy and the vertical angular momentum about S are first
# integrals) and its spinning equilibria are saddle-centres: near each, the Lyapunov centre theorem gives a
# family of periodic orbits for the elliptic pair (the other imaginary pair, +-i Omega, is the turning of
# S's horizontal velocity in the rotating frame). These are the only periodic orbits of the tippedisk here.


def tippedisk_lyapunov_orbit(setup, branch: str = "inverted", omega: float = 40.0, radius: float = 1e-3, *,
                             max_iter: int = NEWTON_MAX_ITER) -> PeriodicOrbit:
    """A periodic orbit of the frictionless reduced tippedisk (mu = 0) near the spinning equilibrium of
    ``branch`` at spin rate ``omega``: guess x* + 2 r Re(q) on the elliptic eigenpair (q unit in scaled
    states), period 2 pi / frequency, the levels of E_tot and L_z pinned at the guess's."""
    from . import stationary as st

    system = tippedisk_system(setup)
    if not system.integrals:
        raise ParameterError("periodic orbits of the tippedisk exist without friction only: give mu = 0 (with "
                             "mu > 0 the energy decreases wherever the disk slips, docs/periodic_orbits.md)")
    x = st.stationary_state(branch, [omega])[:, 0]
    scale = np.asarray(TIPPEDISK_SCALE)
    vals, vecs = np.linalg.eig(reduced.jacobian(x, np.asarray(system.pars))[0])
    elliptic = [i for i in range(len(vals)) if vals[i].imag > 1e-6 * abs(omega)
                and abs(vals[i].real) < 1e-8 * abs(vals[i]) and abs(vals[i].imag - abs(omega)) > 1e-6 * abs(omega)]
    if not elliptic:
        raise ParameterError(f"the {branch} equilibrium at Omega = {omega:g} rad/s has no elliptic eigenpair besides "
                             f"+-i Omega (eigenvalues {np.round(vals, 4)}); choose another spin rate")
    k = elliptic[0]
    q = vecs[:, k] / np.linalg.norm(vecs[:, k] / scale)
    return find_orbit(system, x + 2 * (radius * q).real, 2 * math.pi / vals[k].imag, max_iter=max_iter)


def tippedisk_full_model_check(orbit: PeriodicOrbit, setup, *, tol: float = TAYLOR_TOL,
                               section: str = "beta_dot=0") -> dict:
    """An orbit of the reduced tippedisk checked with ODE Model 1 (11 states): the lifted initial state
    (:func:`.reduced.full_from_reduced`) integrated over one period returns to the orbit (``return_error``:
    max |x(T) - x_0| / scale of the reduced states), and the period equals the return time of the section
    crossings located by :mod:`.poincare`'s event integrator (``section_period``)."""
    from ..defaults import FALL_ANGLE, SLIP_SMOOTHING
    from ..solvers import taylor
    from . import poincare

    x0 = orbit.states[0]
    full0 = reduced.full_from_reduced(x0)
    tr = taylor.integrate("ode-euler", setup, full0, orbit.period, orbit.period, tol, FALL_ANGLE, SLIP_SMOOTHING)
    names = ode.EULER.state_names
    end = {name: tr.states[-1, names.index(name)] for name in names}
    x1 = reduced.reduced_from_full(end["alpha"], end["beta"], end["gamma"], end["x_dot"], end["y_dot"],
                                   end["omega_x"], end["omega_y"], end["omega_z"])[:, 0]
    error = float(np.max(np.abs(x1 - x0) / np.asarray(TIPPEDISK_SCALE)))
    sec = poincare.parse_section(section)
    cr = poincare.crossings(sec, setup=setup, initial=full0, t_end=2.5 * orbit.period, tol=tol)
    times = cr.times
    if cr.t_final < 2.5 * orbit.period or len(times) < 2:
        raise ParameterError(f"the orbit crosses {section} fewer than twice in 2.5 periods; choose another section")
    return {"return_error": error, "section_period": float(times[1] - times[0]), "section_times": times,
            "period": orbit.period, "outcome": cr.status}


def tippedisk_lyapunov_family(setup, branch: str = "inverted", omega: float = 40.0, energy_max: float | None = None,
                              *, radius: float = 1e-3, options: continuation.Options | None = None):
    """The family of periodic orbits of the frictionless tippedisk born at the spinning equilibrium (Lyapunov
    centre theorem), continued in the energy level E_tot away from the equilibrium (towards the equilibrium
    the shooting system becomes singular at the centre: start close to it instead) at fixed L_z.
    Returns (Branch, ShootingProblem)."""
    orbit = tippedisk_lyapunov_orbit(setup, branch, omega, radius)
    if not orbit.converged:
        raise ParameterError(f"no start orbit: {orbit.message}")
    e0 = integral_levels(orbit.system, orbit.states[0], orbit.pars)["E_tot"]
    e1 = e0 + 0.1 if energy_max is None else float(energy_max)
    if not e1 > e0:
        raise ParameterError(f"energy_max = {e1:g} J must exceed the start orbit's energy {e0:.6g} J")
    br, prob = continue_orbits(orbit, "E_tot", bounds={"E_tot": (e0 - 1e-3 * abs(e0), e1)}, direction=1,
                               parameter_scale=0.01,
                               options=options or continuation.Options(ds=0.02, ds_max=0.1, max_points=200))
    return br, prob


def tippedisk_branch_dataset(prob: ShootingProblem, br: continuation.Branch, info: dict | None = None) -> xr.Dataset:
    """:func:`~tippedisk_analysis.dynamics.orbit_datasets.branch_dataset` of a tippedisk branch with ``valid``
    per orbit: lambda_N > 0 all along it (the bilateral contact model holds); orbits with lambda_N < 0 somewhere
    would lift off."""
    ds = branch_dataset(prob, br, info)
    lam = ds.observable_min.sel(observable="lambda_N").values
    valid = (lam > 0).astype(np.int8)
    ds["valid"] = ("point", valid, {"long_name": "1: lambda_N > 0 along the whole orbit (bilateral contact holds)",
                                    "flag_values": np.array([0, 1], np.int8), "flag_meanings": "lift_off valid"})
    name = prob.parameter
    if valid.all():
        ds.attrs["message"] += "; lambda_N > 0 on every orbit"
    else:
        first = int(np.argmin(valid))
        ds.attrs["message"] += (f"; lambda_N < 0 on the orbits from {name} = {float(ds[name][first]):.6g} on (min "
                                f"{lam.min():.3g} N): the contact would lift off there, outside the bilateral model "
                                "(see valid)")
    return ds


def system_of(ds: xr.Dataset) -> System:
    """The System a periodic-orbit dataset was computed with: the reduced tippedisk (at the dataset's setup) or
    a system of the textbook catalogue; DatasetError for a user's own system (pass it to
    :func:`tippedisk_analysis.dynamics.orbit_datasets.orbit_from_dataset` instead)."""
    from ..dynamics.systems import TEXTBOOK, textbook_system
    from ..errors import DatasetError
    from ..results import config_of

    name = str(ds.attrs.get("system", ""))
    if name.startswith("tippedisk_reduced"):
        return tippedisk_system(setup_from_dict(config_of(ds)["setup"]))
    for key in TEXTBOOK:
        if textbook_system(key).name == name:
            return textbook_system(key)
    raise DatasetError(f"system {name!r} of the dataset is neither the tippedisk nor a textbook system ("
                       f"{', '.join(TEXTBOOK)}); continue it in Python with the System it was computed with")


def orbit_from_dataset(ds: xr.Dataset, point: int, *, max_iter: int = NEWTON_MAX_ITER) -> PeriodicOrbit:
    """The orbit at ``point`` of a periodic-orbit dataset of the tippedisk or a textbook system, by Newton."""
    from ..dynamics.orbit_datasets import orbit_from_dataset as generic

    return generic(ds, point, system_of(ds), max_iter=max_iter)

"""The rolling tippedisk as a dynamical system (docs/rolling.md): the symmetry-reduced rolling model, its
stationary spins and their stability, and the post-inversion motion of Models 1/2 (a torus around an
elliptic periodic orbit, with its family over the energy and where rolling stays consistent).

The rolling model (:mod:`tippedisk_analysis.models.rolling`) does not depend on the position of G nor on the
precession angle alpha (rotational symmetry about the vertical), so (beta, gamma, omega) is a closed 5-state
system (:func:`reduced_system`). It is nonholonomic; it conserves the energy and, by the tests
(tests/test_rolling_analysis.py), no other candidate quantity (the vertical angular momentum about S or the
contact point, Jellett's L_C . n: they vary by percent). It is reversible (t -> -t with the angular velocity
reversed), which is why its periodic orbits come in families in the energy with elliptic multipliers
e^(+-i theta) and invariant tori around them, as in a Hamiltonian system, although it is none.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from .. import dynamics as dy
from ..errors import ParameterError
from ..models import rolling
from ..models.rolling import REDUCED_STATE_NAMES as STATE_NAMES
from ..models.rolling import reduced_system

__all__ = ["reduced_system", "spin_state", "spin_eigenvalues", "section", "identify", "Motion", "weighted_birkhoff",
    "central_orbit", "floquet_angle", "consistency", "motion_consistency", "rolling_start", "orbits_from_run",
    "family", "consistency_boundary"]

BRANCHES = {"noninverted": -1.0, "inverted": 1.0}  # sin(gamma) of the spin: S below / above G


def spin_state(branch: str, omega: float) -> np.ndarray:
    """The stationary rolling spin: the disk upright (beta = pi/2), S straight above or below G (gamma = +-pi/2),
    turning at ``omega`` about the vertical through C1, G and S (body components (sin gamma omega, 0, 0))."""
    if branch not in BRANCHES:
        raise ParameterError(f"unknown branch {branch!r}; choose one of {', '.join(BRANCHES)}")
    s = BRANCHES[branch]
    return np.array([0.5 * math.pi, s * 0.5 * math.pi, s * float(omega), 0.0, 0.0])


def spin_eigenvalues(branch: str, omegas, pars=None) -> np.ndarray:
    """Eigenvalues (len(omegas), 5) of the reduced rolling Jacobian at the spins, by real part descending."""
    system = reduced_system()
    out = []
    for w in np.atleast_1d(omegas):
        ev = np.linalg.eigvals(system.jacobian(spin_state(branch, w), pars))
        out.append(ev[np.lexsort((-ev.imag, -ev.real))])
    return np.array(out)


# ---------------------------------------------------------------------------- the post-inversion motion

SECTION_LEVEL = 0.5 * math.pi  # the section gamma = pi/2 (mod 2 pi), crossed upwards: S straight above G
SECTION_STATES = ("beta", "omega_x", "omega_y", "omega_z")  # the coordinates on the section (gamma is fixed)
FOURIER_HARMONICS = 5  # of the radius r(theta) fitted to the section curve


def section(state, *, t_end: float = 200.0, pars=None, tol: float = 1e-13) -> xr.Dataset:
    """The returns of the reduced rolling motion from ``state`` to gamma = pi/2 (mod 2 pi, upwards), over
    ``t_end`` [s]: a dataset of kind ``poincare`` (:func:`tippedisk_analysis.dynamics.poincare_section`)."""
    return dy.poincare_section(reduced_system(), np.asarray(state, dtype=float), "gamma", SECTION_LEVEL, pars=pars,
                               modulo=True, direction="positive", t_end=t_end, tol=tol)


@dataclass(frozen=True)
class Motion:
    """What the section of a rolling motion shows (:func:`identify`)."""

    kind: str  # "periodic orbit", "torus" or "unresolved"
    n_returns: int
    mean_return: float  # [s] mean time between returns
    rotation_number: float  # of the section map about the curve's centre, in (0, 1/2]; nan unless a torus
    rotation_estimates: tuple  # from the first N/4, N/2 and all N returns (their agreement is the test)
    curve_residual: float  # rms of the Fourier-fit radius residual relative to the mean radius
    spread: float  # largest distance of a return from the centre / state scale
    centre: np.ndarray  # mean of the returns (reduced state, gamma = pi/2)
    message: str


def _plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre and coordinates of the scaled section points in their principal plane."""
    system = reduced_system()
    scale = np.array([system.state_scale[system.state_index(k)] for k in SECTION_STATES])
    Y = points / scale
    centre = Y.mean(axis=0)
    _u, _s, vt = np.linalg.svd(Y - centre, full_matrices=False)
    return centre * scale, (Y - centre) @ vt[:2].T


def weighted_birkhoff(increments: np.ndarray) -> float:
    """The weighted Birkhoff average of a quasi-periodic sequence (bump weights exp(-1/(s(1-s)))): converges
    faster than any power of N on a smooth invariant curve, against 1/N for the plain mean."""
    n = len(increments)
    s = (np.arange(n) + 0.5) / n
    w = np.exp(-1.0 / (s * (1.0 - s)))
    return float(np.sum(w * increments) / np.sum(w))


def identify(sec: xr.Dataset, *, tol: float = 1e-5) -> Motion:
    """A periodic orbit (every return at one point), an invariant torus (the returns on a closed curve about
    a centre, turning by a rotation number that the first N/2 and all N returns give to ``tol``; the N/4
    estimate is reported beside them), or unresolved (too few returns, a scattered cloud, or no convergence:
    give a longer run)."""
    points = np.stack([sec[k].values for k in SECTION_STATES], axis=1)
    n = len(points)
    times = sec["time"].values
    mean_return = float(np.mean(np.diff(times))) if n > 1 else math.nan
    if n < 16:
        return Motion("unresolved", n, mean_return, math.nan, (), math.nan, math.nan,
                      np.full(5, math.nan), f"{n} returns; give a longer run (at least 16 returns)")
    centre4, P = _plane(points)
    centre = np.array([centre4[0], SECTION_LEVEL, *centre4[1:]])
    radius = np.hypot(P[:, 0], P[:, 1])
    spread = float(radius.max())
    if spread < tol:
        return Motion("periodic orbit", n, mean_return, math.nan, (), 0.0, spread, centre,
                      f"every return within {spread:.2g} of the mean: a periodic orbit of period {mean_return:.10g} s")
    theta = np.arctan2(P[:, 1], P[:, 0])
    increments = np.mod(np.diff(theta), 2 * math.pi) / (2 * math.pi)
    # folded to (0, 1/2]: the curve's orientation in the plane is a convention (rho and 1 - rho are one rotation)
    estimates = tuple(0.5 - abs(0.5 - weighted_birkhoff(increments[: max(8, len(increments) // d)]))
                      for d in (4, 2, 1))
    A = np.column_stack([np.ones(n)] + [f(k * theta) for k in range(1, FOURIER_HARMONICS + 1)
                                        for f in (np.cos, np.sin)])
    fit = np.linalg.lstsq(A, radius, rcond=None)[0]
    residual = float(np.sqrt(np.mean((A @ fit - radius) ** 2)) / radius.mean())
    agree = abs(estimates[2] - estimates[1])
    if agree < tol and residual < 1e-2 and radius.min() > 0.1 * radius.mean():
        kind = "torus"
        message = (f"{n} returns on a closed curve about the centre (radius {radius.min():.3g} .. {radius.max():.3g}, "
                   f"Fourier-{FOURIER_HARMONICS} residual {residual:.2g}), rotation number {estimates[-1]:.10f} "
                   f"(N/2 and N agree to {agree:.1g}; N/4: {estimates[0]:.10f}): an invariant torus")
    else:
        kind = "unresolved"
        message = (f"{n} returns: rotation estimates {', '.join(f'{e:.8f}' for e in estimates)} (spread {agree:.2g}), "
                   f"curve residual {residual:.2g}: neither a periodic orbit nor a torus to {tol:g}; give a longer run")
    return Motion(kind, n, mean_return, estimates[-1] if kind == "torus" else math.nan, estimates, residual, spread,
                  centre, message)


def on_energy_level(state, energy: float, pars=None) -> np.ndarray:
    """``state`` with its angular velocity scaled so that E_tot = ``energy`` [J] (E_kin is quadratic in omega)."""
    x = np.array(state, dtype=float)
    still = x.copy()
    still[2:] = 0.0
    e_now, e_pot = reduced_system().observe(np.column_stack([x, still]), pars)["E_tot"]
    if energy <= e_pot:
        raise ParameterError(f"the energy {energy:.6g} J is below the potential energy {e_pot:.6g} J of the state")
    x[2:] *= math.sqrt((energy - e_pot) / (e_now - e_pot))
    return x


def central_orbit(sec: xr.Dataset, *, pars=None, motion: Motion | None = None) -> dy.PeriodicOrbit:
    """An elliptic periodic orbit at a torus's centre: Newton from the mean of its returns, put on their energy
    level, with omega_x pinned at the mean's value. The orbits at one energy form a one-parameter family (the
    monodromy has a third multiplier 1), so this picks the member through the centre; tori started near it
    turn at its Floquet angle (docs/rolling.md), the torus itself at its own rotation number. ``motion``: what
    :func:`identify` said of ``sec``, if known."""
    motion = motion or identify(sec)
    if motion.kind == "unresolved":
        raise ParameterError(f"no centre to start from: {motion.message}")
    energy = float(np.mean(sec["E_tot"].values))
    guess = on_energy_level(motion.centre, energy, pars)
    return dy.find_orbit(reduced_system(), guess, motion.mean_return, pars, pinned=("omega_x",))


NO_ANGLE = -1.0  # the Floquet angle of an orbit whose multipliers are off the unit circle (0 is a resonance)


def floquet_angle(orbit: dy.PeriodicOrbit) -> float:
    """theta / 2 pi of the nontrivial multipliers e^(+-i theta) of an elliptic orbit, in (0, 1/2]; NO_ANGLE when
    they are not on the unit circle."""
    mu = orbit.multipliers[~orbit.trivial]
    if len(mu) != 2 or np.max(np.abs(np.abs(mu) - 1.0)) > 1e-6:
        return NO_ANGLE
    return float(abs(np.angle(mu[0])) / (2 * math.pi))


MARGIN_STEP = 1e-3  # [s] sampling of a motion for its smallest cone margin (error ~ 1e-4 N: margin'' ~ 1e3 N/s^2)


def _smallest_margin(system: dy.System, state, times: np.ndarray, pars) -> dict:
    """The smallest cone margin and normal force [N] on ``times`` along the motion from ``state``, with the time
    [s] and the state where the margin is smallest."""
    X = dy.Flow(system).trajectory(np.asarray(state, dtype=float), times, system.with_pars(pars))
    obs = system.observe(X.T, pars)
    k = int(np.argmin(obs["cone_margin"]))
    return {"min_cone_margin": float(obs["cone_margin"][k]), "min_lambda_N": float(np.min(obs["lambda_N"])),
            "time": float(times[k]), "state": X[k]}


def motion_consistency(state, duration: float, pars=None) -> dict:
    """:func:`consistency` along the rolling motion from ``state`` over ``duration`` [s] (samples every
    MARGIN_STEP)."""
    return _smallest_margin(reduced_system(), state, np.arange(0.0, duration, MARGIN_STEP), pars)


def consistency(orbit: dy.PeriodicOrbit, n_samples: int = 2000) -> dict:
    """The smallest cone margin ``mu lambda_N - |lambda_T|`` [N] and normal force lambda_N [N] along ``orbit``
    (``n_samples`` points over the period) and the time and state where the margin is smallest."""
    times = np.linspace(0.0, orbit.period, n_samples, endpoint=False)
    return _smallest_margin(orbit.system, orbit.states[0], times, orbit.pars)


# ---------------------------------------------------------------------------- from a run of Models 1/2

ROLLING_RUNS = ("hybrid-euler", "moreau-coulomb-euler", "moreau-coulomb-quaternion")
"""Runs whose motion rolls: the event-driven model and Moreau Models 1/2 (set-valued Coulomb at a point)."""
ROLLING_SLIP = 1e-3  # [m/s] a Moreau run rolls where its slip speed stays below this (its time step's level)
RETURNS_TIME = 500.0  # [s] of rolling motion whose returns identify the motion


def rolling_start(run: xr.Dataset) -> tuple[np.ndarray, np.ndarray, float]:
    """(reduced state, parameter vector, time) at the end of a run's last rolling stretch."""
    from ..parameters import setup_from_dict
    from ..results import config_of

    if run.attrs.get("kind") != "simulation":
        raise ParameterError(f"the dataset is of kind {run.attrs.get('kind')!r}; give a simulation written by "
                             "tippedisk simulate")
    model = config_of(run).get("model")
    if model not in ROLLING_RUNS:
        raise ParameterError(f"the run is of model {model!r}, whose contact does not roll without slip; give a run of "
                             f"{', '.join(ROLLING_RUNS)} (set-valued Coulomb friction: Models 1/2)")
    if "mode" in run:
        rolls = run["mode"].values == 0
    else:
        rolls = np.hypot(run["slip_x"].values, run["slip_y"].values) < ROLLING_SLIP
    if not rolls[-1]:
        raise ParameterError(f"the run does not end rolling (slip at t = {float(run.time[-1]):.6g} s); give a longer "
                             "run (Table 3: rolling from t = 0.43 s)")
    pars = rolling.parameter_vector(setup_from_dict(config_of(run)["setup"]))
    x = np.array([float(run[k][-1]) for k in STATE_NAMES])
    return x, pars, float(run.time[-1])


def orbits_from_run(run: xr.Dataset, *, returns_time: float = RETURNS_TIME) -> xr.Dataset:
    """The rolling motion at the end of a run of Models 1/2 (Moreau or hybrid): its returns to gamma = pi/2 over
    ``returns_time`` [s] of the reduced rolling model, what they show (:func:`identify`), and the periodic orbit
    they wind around with its Floquet multipliers and consistency (a dataset of kind ``periodic_orbits``)."""
    from ..dynamics.datasets import mixed_units
    from ..dynamics.orbit_datasets import orbits_dataset
    from ..results import config_of, index_coordinate

    if run.attrs.get("status") != "completed":
        raise ParameterError(f"the run ended {run.attrs.get('status')!r} ({run.attrs.get('message', '')}), so there is "
                             "no rolling motion at its end to analyse; give a run that reached its t_end")
    x, pars, t_run = rolling_start(run)
    sec = section(x, t_end=returns_time, pars=pars)
    motion = identify(sec)
    if sec.attrs["status"] != "completed":
        raise ParameterError(f"the rolling motion from the run's end does not go on: {sec.attrs['message']}")
    if motion.kind == "unresolved":
        raise ParameterError(f"{motion.message}")
    orbit = (central_orbit(sec, pars=pars, motion=motion) if motion.kind == "torus" else
             dy.find_orbit(reduced_system(), motion.centre, motion.mean_return, pars, pinned=("omega_x",)))
    c = consistency(orbit) if orbit.converged else {}
    along = motion_consistency(x, returns_time, pars)
    points = np.stack([sec[k].values for k in STATE_NAMES], axis=1)
    margin = sec["cone_margin"].values
    where = ", ".join(f"{k} {v:.4g}" for k, v in zip(STATE_NAMES[:2], along["state"]))
    message = (f"{motion.kind} from the rolling motion at t = {t_run:.6g} s of the run: {motion.message}; smallest "
               f"cone margin along the motion {along['min_cone_margin']:.4g} N ({along['time']:.4g} s after the "
               f"run's end, {where} rad; lambda_N >= {along['min_lambda_N']:.4g} N); {orbit.message}"
               + (f", Floquet angle / 2 pi {floquet_angle(orbit):.10f}, smallest cone margin on the orbit "
                  f"{c['min_cone_margin']:.4g} N" if c else ""))
    extra = {
        "return_time": ("crossing", sec["time"].values, {"units": "s", "long_name": "time of the return to gamma = "
                                                                                     "pi/2 (from the run's end)"}),
        "return_state": (("crossing", "state"), points, mixed_units("reduced rolling state at the return")),
        "return_cone_margin": ("crossing", margin,
                               {"units": "N", "long_name": "mu lambda_N - |lambda_T| at the return"}),
        "rotation_number": ((), motion.rotation_number if motion.kind == "torus" else 0.0,
                            {"units": "1", "long_name": "rotation number of the section map on the torus (0: an "
                                                        "orbit)"}),
        "motion_min_cone_margin": ((), along["min_cone_margin"],
                                   {"units": "N", "long_name": "smallest mu lambda_N - |lambda_T| along the motion "
                                                               "(samples every 1 ms over returns_time)"}),
        "motion_min_cone_margin_time": ((), along["time"], {"units": "s", "long_name": "when (from the run's end)"}),
        "motion_min_lambda_N": ((), along["min_lambda_N"], {"units": "N", "long_name": "smallest normal force "
                                                                                       "along the motion"}),
    }
    if c:  # a failed orbit has no cone margin (status no_orbit): the variable is left out, never filled with 0
        extra["orbit_min_cone_margin"] = ("point", np.array([c["min_cone_margin"]]),
                                          {"units": "N", "long_name": "smallest mu lambda_N - |lambda_T| along the "
                                                                      "orbit"})
    cfg = {"source": "rolling run", "run_config": config_of(run), "t_run": t_run, "returns_time": returns_time,
           "motion": motion.kind, "rotation_estimates": list(motion.rotation_estimates),
           "curve_residual": motion.curve_residual}
    status = "completed" if orbit.converged else "no_orbit"
    ds = orbits_dataset([orbit], status, message, cfg, extra=extra)
    return ds.assign_coords(crossing=index_coordinate("crossing", len(points), "return index"))


# ---------------------------------------------------------------------------- the family and its consistency

FAMILY_PARAMETERS = ("E_tot", "omega_x")  # the energy level (omega_x held) and the spin omega_x (energy held)


def family(orbit: dy.PeriodicOrbit, parameter: str, bounds: tuple, *, max_points: int = 40,
           options: dy.Options | None = None, n_samples: int = 64) -> xr.Dataset:
    """The orbits through ``orbit`` in the energy (``E_tot``, omega_x at the start held) or in the spin
    (``omega_x`` at the start, the energy held), both ways within ``bounds``, with the smallest cone margin and
    normal force along each orbit (where rolling stays consistent): a dataset of kind ``periodic_orbits``
    (``n_samples`` stored samples per orbit; the margins come from 2000)."""
    from ..dynamics.orbit_datasets import branch_dataset

    if parameter not in FAMILY_PARAMETERS:
        raise ParameterError(f"unknown family parameter {parameter!r}; choose one of {', '.join(FAMILY_PARAMETERS)}")
    options = options or dy.Options(ds=0.02, ds_max=0.2, max_points=max_points)
    br, prob = dy.continue_orbits(orbit, parameter, bounds={parameter: tuple(bounds)}, both_ways=True,
                                  options=options, pinned=("omega_x",))

    def margins(orbits):
        c = [consistency(o) for o in orbits]
        return {"min_cone_margin": ("point", np.array([x["min_cone_margin"] for x in c]),
                                    {"units": "N", "long_name": "smallest mu lambda_N - |lambda_T| along the orbit "
                                                                "(< 0: rolling needs more friction than the cone)"}),
                "min_lambda_N": ("point", np.array([x["min_lambda_N"] for x in c]),
                                 {"units": "N", "long_name": "smallest normal force along the orbit (< 0: lift-off)"}),
                "floquet_angle": ("point", np.array([floquet_angle(o) for o in orbits]),
                                  {"units": "1", "long_name": "theta / 2 pi of the elliptic multipliers e^(+-i theta)",
                                   "comment": f"{NO_ANGLE:g} (outside (0, 1/2]) where the nontrivial multipliers are "
                                              "off the unit circle: the orbit is unstable (see stability), no angle"})}

    return branch_dataset(prob, br, {"family": parameter, "pinned": ["omega_x"]}, n_samples, extra=margins)


def consistency_boundary(ds: xr.Dataset) -> list[float]:
    """Every family parameter value where the smallest cone margin crosses zero along the branch (linear
    interpolation between the bracketing orbits), in the order of the branch; empty if rolling stays
    consistent. Rolling is consistent where the margin is positive: between crossings it may become so
    again (the energy family: inconsistent below 0.36684 J, consistent again on [0.3583, 0.3602] J)."""
    parameter = ds.attrs["parameter"]
    value, margin = ds[parameter].values, ds["min_cone_margin"].values
    k = np.flatnonzero(np.sign(margin[:-1]) * np.sign(margin[1:]) < 0)
    return [float(v) for v in value[k] + (value[k + 1] - value[k]) * margin[k] / (margin[k] - margin[k + 1])]

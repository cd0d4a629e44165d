"""After the inversion: the slow passage of the free disk along the family of inverted spins (docs/inversion.md).

ODE Model 1 (:mod:`tippedisk_analysis.models.reduced`) from Table 3's start is run on past the inversion, and
each sample near the inverted spin is split into the inverted spin's two slow modes at the sample's own spin
alpha_dot: the nutation (the slower pair of (C2)) and the precession (the faster pair). The amplitude of a mode
is the modulus of its coordinate ``w . (x - x*(alpha_dot))``, with ``w`` the left eigenvector of the reduced
Jacobian at the spin x* (unit-norm right eigenvectors, the state's own units). Along a slow passage each
amplitude changes at the real part of its eigenvalue at the current spin: ln A(t1) - ln A(t0) is
the integral of Re lambda(alpha_dot(t)) dt, and the nutation's amplitude is smallest where the spin passes
omega_c (C4).

Where the energy goes (:func:`mode_energetics`): per squared amplitude and averaged over its phase, each mode
holds the energy kappa above the spin's, costs the friction power pi and raises the mean spin about the
vertical above the mean body rate omega_x by c; the spins' own energy grows as A Omega. So, to second order
in the amplitudes and with Omega the mean omega_x, A Omega dOmega/dt = sum_k (pi_k - 2 Re lambda_k kappa_k)
``|z_k|^2`` and <alpha_dot> = Omega + sum_k c_k ``|z_k|^2`` (C7). With the two modes' rates this closes into a
three-dimensional model of the stay, (C8) (:func:`amplitude_system`, :func:`amplitude_start`,
:func:`amplitude_run`).

``passage`` returns the run as a dataset (kind ``spin_passage``) with the amplitudes, the spin, the height of S
and these events: when S first passes r + 0.8 e (the inversion criterion, ``t_inverted``), when it falls back
below G again (z_S < r, ``t_fell_back``; -1 s where it did not happen), and how the run ended (``fell``,
``lift_off`` or ``horizon``). The modes are stored along dim ``near`` (coordinate ``near_time``): the samples
with S above r + 0.5 e between the two times, where the split into modes about the spin means something.
"""

from __future__ import annotations

import copy
import functools
import json
import math
import numbers

import heyoka as hy
import numpy as np
import xarray as xr

from ..dynamics import Event, System
from ..dynamics.branches import bounds_pair
from ..errors import ParameterError
from ..models import reduced
from ..parameters import InitialState, Setup, setup_from_dict, to_dict
from ..results import flat_parameters, make_attrs
from . import critical_spin, inversion
from .stationary import stationary_state

__all__ = ["passage_setup", "MODES", "modal_amplitudes", "mode_energetics", "energy_and_power", "modal_friction_power", "passage",
           "integrated_rate", "amplitude_system", "amplitude_start", "amplitude_run"]

MODES = ("nutation", "precession")  # the slower and the faster pair of the inverted spin (C2)
NEAR_SPIN = 0.5  # z_S > r + NEAR_SPIN e: the samples split into modes (S well above G)
SAMPLE_STEP = 0.05  # s, between samples (the nutation period is about 1 s)
NONE = -1.0  # t_inverted, t_fell_back [s] of a run in which it did not happen
MAX_SAMPLES = 2e6  # samples of one passage (16 s of ODE Model 1 states per 1e5)


MATCH = 0.25  # a pair is a rolling mode when it lies within this fraction of its frequency of (C3)'s eigenvalue


def _modes(system, spin: float, pars: np.ndarray, setup: Setup):
    """(spin state, eigenvalues, right eigenvectors, {mode: index}) of the inverted spin at ``spin`` [rad/s]:
    the pairs (upper half plane) whose frequencies match the rolling nutation and precession of (C2). A
    ParameterError where there is no such pair: below the collision of the rolling pairs, or at an eps so large
    for this spin that friction has changed them beyond recognition."""
    if not (isinstance(spin, numbers.Real) and math.isfinite(spin)):
        raise ParameterError(f"spin = {spin!r}: give a finite spin in rad/s")
    if setup.disk.e <= 0:
        raise ParameterError("e = 0: a balanced disk has no inverted spin to split into modes; give e > 0 [m]")
    rolling = critical_spin.rates(spin, setup.disk, setup.gravity, setup.friction.mu)
    if math.isnan(rolling["nu_nutation"]):
        raise ParameterError(f"at {spin:.4g} rad/s the rolling inverted spin has no nutation and precession pairs "
                             "(below their collision, 18.28 rad/s for Tables 1-2); give a faster spin")
    spin_x = stationary_state("inverted", [spin])[:, 0]
    eigenvalues, right = np.linalg.eig(system.jacobian(spin_x, pars))
    upper = np.flatnonzero(eigenvalues.imag > 1e-9)
    found, eps = {}, setup.friction.eps
    for mode in MODES:
        nu, damping = rolling[f"nu_{mode}"], eps * rolling[f"rate_{mode}"]
        k = upper[np.argmin(np.abs(eigenvalues[upper].imag - nu))] if upper.size else None
        if k is None or abs(eigenvalues[k] - (damping + 1j * nu)) > MATCH * nu:
            raise ParameterError(f"at {spin:.4g} rad/s and eps = {eps:g} m/s no pair of the inverted spin has the "
                                 f"rolling {mode}'s frequency {nu:.4g} rad/s (C2) and damping {damping:.3g} 1/s (C3): "
                                 "friction has changed the modes; give a smaller eps")
        found[mode] = int(k)
    if found["nutation"] == found["precession"]:
        raise ParameterError(f"at {spin:.4g} rad/s the nutation and precession cannot be told apart; give a faster spin")
    return spin_x, eigenvalues, right, found


def _split(system, x: np.ndarray, spin: float, pars: np.ndarray, setup: Setup) -> dict:
    """One state's modal amplitudes, rates and frequencies about the inverted spin at ``spin``."""
    spin_x, eigenvalues, right, pairs = _modes(system, spin, pars, setup)
    left = np.linalg.inv(right)
    d = x - spin_x
    d[1] = math.remainder(d[1], 2.0 * math.pi)  # gamma, about pi/2
    out = {}
    for mode, index in pairs.items():
        out[f"{mode}_amplitude"] = abs(left[index] @ d)
        out[f"{mode}_rate"] = eigenvalues[index].real
        out[f"{mode}_frequency"] = eigenvalues[index].imag
    return out


PHASES = 16  # phases of a mode averaged over in :func:`mode_energetics`
PROBES = {"energy": 1e-3, "power": 1e-5}
"""Modal amplitudes of the probes in :func:`mode_energetics`: the energy's quadratic term is found to O(1e-6)
(smaller probes lose it to round-off against E_tot); the power vanishes at the spin, so a small probe keeps
the ``|slip|^3`` term of (2.29) out of it."""


@functools.lru_cache(maxsize=None)
def _energy_cfuncs():
    """Compiled E_tot(x) and its power dE/dt = grad E . f (friction's: the only force that works in ODE
    Model 1)."""
    system = reduced.system()
    energy = system.observables["E_tot"][0]
    power = sum(g * f for g, f in zip(system.gradient_expressions([energy]), system.rhs))
    return system.function("E_tot", [energy]), system.function("power of E_tot", [power], "the power")


def energy_and_power(states: np.ndarray, setup: Setup | None = None) -> tuple[np.ndarray, np.ndarray]:
    """E_tot [J] and dE/dt [W] (the friction power) of ODE Model 1 states (7,) or (7, N) of ``setup``."""
    system, pars = reduced.system(), inversion.parameters("smooth", Setup() if setup is None else setup)
    e_fn, p_fn = _energy_cfuncs()
    return system.evaluate(e_fn, states, pars)[0], system.evaluate(p_fn, states, pars)[0]


def mode_energetics(spin: float, setup: Setup | None = None) -> dict[str, float]:
    """What each mode of the inverted spin at ``spin`` [rad/s] holds and costs, per squared modal amplitude
    ``|z|^2`` (z: the coordinate of :func:`modal_amplitudes`), averaged over the mode's phase:
    "<mode>_energy" [J] (E_tot above the spin's), "<mode>_friction_power" [W] (mean dE/dt: friction's work,
    <= 0), "<mode>_spin_offset" [rad/s] (the mean spin about the vertical alpha_dot above the mode's mean
    omega_x, which the probes keep at ``spin``) and "<mode>_rate" [1/s] (Re lambda); "spin_energy_slope"
    dE*/dOmega [J s] of the spins themselves."""
    setup = Setup() if setup is None else setup
    system, pars = reduced.system(), inversion.parameters("smooth", setup)
    spin_x, eigenvalues, right, pairs = _modes(system, spin, pars, setup)
    phases = np.exp(2j * math.pi * np.arange(PHASES) / PHASES)
    out = {}
    spin_energy = energy_and_power(spin_x, setup)[0]
    for mode, index in pairs.items():
        probes = {what: spin_x[:, None] + 2.0 * size * (phases[None, :] * right[:, index:index + 1]).real
                  for what, size in PROBES.items()}  # |z| = size; the mean of omega_x stays at spin
        energy = energy_and_power(probes["energy"], setup)[0]
        power = energy_and_power(probes["power"], setup)[1]
        vertical = system.observe(probes["energy"], pars)["alpha_dot"]
        out[f"{mode}_energy"] = float((energy - spin_energy).mean()) / PROBES["energy"] ** 2
        out[f"{mode}_friction_power"] = float(power.mean()) / PROBES["power"] ** 2
        out[f"{mode}_spin_offset"] = float((np.asarray(vertical) - spin).mean()) / PROBES["energy"] ** 2
        out[f"{mode}_rate"] = float(eigenvalues[index].real)
    step = 1e-4 * spin
    ends = stationary_state("inverted", [spin - step, spin + step])
    low, high = energy_and_power(ends, setup)[0]
    out["spin_energy_slope"] = float(high - low) / (2.0 * step)
    return out


AMPLITUDE_SPINS = (22.0, 40.0)  # rad/s: the spins the amplitude model's coefficients are fitted over
AMPLITUDE_FIT = (37, 12)  # spins sampled, degree of the Chebyshev series of each coefficient
RATES_AT = ("vertical", "omega_x")  # where (C8) evaluates the rates: the mean vertical spin W, or Omega
AMPLITUDE_STATES = ("omega_mean", "nutation_power", "precession_power")  # Omega [rad/s], |z_n|^2, |z_p|^2


def amplitude_system(setup: Setup | None = None, spins: tuple = AMPLITUDE_SPINS, rates_at: str = "vertical") -> System:
    """The stay as a three-dimensional ODE (C8): Omega, the mean body rate omega_x (the family coordinate of
    the inverted spins, here defined by the energy partition E = E*(Omega) + kappa_n N + kappa_p P), and the
    squared amplitudes N = ``|z_n|^2``, P = ``|z_p|^2`` of their nutation and precession:

        dN/dt = 2 Re lambda_n(W) N,   dP/dt = 2 Re lambda_p(W) P,
        A Omega dOmega/dt = (pi_n - 2 Re lambda_n(W) kappa_n) N + (pi_p - 2 Re lambda_p(W) kappa_p) P,

    W = Omega + c_n(Omega) N + c_p(Omega) P the mean spin about the vertical (observable ``alpha_dot_mean``; c:
    the spin offsets of :func:`mode_energetics`; pi, kappa, c taken at Omega). The drift uses the amplitudes' own
    rates, so the energy balance (C7) holds along the model. Assumptions: the state stays near the family of inverted spins
    (the linear modes describe it); the two modes' phases are averaged over (their frequencies, about 6 and
    29 rad/s, are not in resonance); the amplitude equations' rates are taken at W (``rates_at`` "vertical"; or
    "omega_x": at Omega). To second order in the amplitudes that choice makes no difference; it is a fit of one
    fourth-order term, which the stay's amplitudes make large (docs/inversion.md). The coefficients come from
    :func:`mode_energetics` on ``spins`` (Chebyshev series, checked at the midpoints; a ParameterError names a
    misfit); terminal events end a run in which Omega or W leaves them. All coefficients are O(eps), so in the
    slow time eps t the model does not depend on eps."""
    setup = Setup() if setup is None else setup
    low, high = bounds_pair(spins, "spins [rad/s]")
    if rates_at not in RATES_AT:
        raise ParameterError(f"rates_at = {rates_at!r}: choose one of {', '.join(RATES_AT)}")
    count, degree = AMPLITUDE_FIT
    grid = np.linspace(low, high, count)
    centre, half = 0.5 * (low + high), 0.5 * (high - low)
    rows = [mode_energetics(float(w), setup) for w in grid]
    checks = [mode_energetics(float(w), setup) for w in 0.5 * (grid[1:] + grid[:-1])[::4]]

    def coefficient(row, mode, what):
        if what in ("rate", "spin_offset"):
            return row[f"{mode}_{what}"]
        return row[f"{mode}_{what}"] / row["spin_energy_slope"]  # friction_power or energy over A Omega

    spin, nutation, precession = variables = hy.make_vars(*AMPLITUDE_STATES)
    u = (spin - centre) / half
    fits = {}
    for mode in MODES:
        for what in ("rate", "friction_power", "energy", "spin_offset"):
            values = np.array([coefficient(row, mode, what) for row in rows])
            coefficients = np.polynomial.chebyshev.chebfit((grid - centre) / half, values, degree)
            midpoints = 0.5 * (grid[1:] + grid[:-1])[::4]
            misfit = np.abs(np.polynomial.chebyshev.chebval((midpoints - centre) / half, coefficients)
                            - [coefficient(row, mode, what) for row in checks]).max()
            if misfit > 1e-3 * np.abs(values).max():
                raise ParameterError(f"the {mode} {what} of the amplitude model misfits by {misfit:.2g} over "
                                     f"{low:g}-{high:g} rad/s; give a narrower range of spins")
            fits[mode, what] = coefficients
    offset = {mode: _chebyshev_expression(fits[mode, "spin_offset"], u) for mode in MODES}
    vertical = spin + offset["nutation"] * nutation + offset["precession"] * precession
    at = {"omega_x": u, "vertical": (vertical - centre) / half}[rates_at]
    rate = {mode: _chebyshev_expression(fits[mode, "rate"], at) for mode in MODES}
    drift = {mode: _chebyshev_expression(fits[mode, "friction_power"], u)  # the amplitudes' own rates: (C7) holds
             - 2.0 * rate[mode] * _chebyshev_expression(fits[mode, "energy"], u) for mode in MODES}
    rhs = [drift["nutation"] * nutation + drift["precession"] * precession,
           2.0 * rate["nutation"] * nutation, 2.0 * rate["precession"] * precession]
    events = (Event("left_fitted_spins", (spin - low) * (high - spin), "negative"),  # terminal: no extrapolation
              Event("left_fitted_spins", (vertical - low) * (high - vertical), "negative"))
    system = System(f"tippedisk_stay_amplitudes_eps{setup.friction.eps:g}_{rates_at}", variables, rhs, {},
                    state_names=AMPLITUDE_STATES, units={"omega_mean": "rad s-1", "nutation_power": "1",
                                                         "precession_power": "1"}, time_units="s", events=events,
                    observables={"alpha_dot_mean": (vertical, "rad s-1")},
                    description=f"the stay near the inverted spins as amplitudes (C8), {low:g}-{high:g} rad/s")
    system.fitted_spins = (low, high)
    return system


def amplitude_run(start, times, setup: Setup | None = None, system: System | None = None) -> tuple:
    """Run the amplitude model (C8) of ``setup`` (or ``system``, an :func:`amplitude_system`) from ``start``
    (Omega [rad/s], N, P: :func:`amplitude_start` takes a passage's state into it) over ``times`` [s] (from 0):
    (states on the times reached, ending "end" or "left_fitted_spins")."""
    system = amplitude_system(setup) if system is None else system
    if not hasattr(system, "fitted_spins"):
        raise ParameterError("system: give one made by spin_passage.amplitude_system")
    try:
        start = np.asarray(start, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"start = {start!r}: give (Omega [rad/s], N, P)") from None
    if start.shape != (3,) or not np.all(np.isfinite(start)) or start[1] < 0 or start[2] < 0:
        raise ParameterError(f"start = {start}: give finite (Omega [rad/s], N >= 0, P >= 0)")
    low, high = system.fitted_spins
    vertical = float(system.observe(start, np.array([]))["alpha_dot_mean"])
    if not (low <= start[0] <= high and low <= vertical <= high):
        raise ParameterError(f"the start's Omega = {start[0]:.4g} and mean vertical spin {vertical:.4g} rad/s must lie "
                             f"in the fitted spins {low:g}-{high:g} rad/s; start nearer the spins")
    times = np.asarray(times, dtype=float)
    if not (times.ndim == 1 and times.size and times[0] == 0.0 and np.all(np.diff(times) > 0)):
        raise ParameterError("times: give increasing times [s] starting at 0")
    ta = copy.deepcopy(system.taylor(1e-12, events=True))
    ta.time = 0.0
    ta.state[:] = start
    result = ta.propagate_grid(times)
    states = np.asarray(result[-1])
    if not np.all(np.isfinite(states)):
        raise ParameterError("the amplitude model's run broke down (non-finite state); start nearer the spins")
    return states, "end" if result[0] == hy.taylor_outcome.time_limit else system.events[0].name


def _chebyshev_expression(coefficients, u):
    """sum c_k T_k(u) as an expression of u (Clenshaw's recurrence)."""
    b1, b2 = 0.0 * u, 0.0 * u
    for c in coefficients[:0:-1]:
        b1, b2 = 2.0 * u * b1 - b2 + float(c), b1
    return u * b1 - b2 + float(coefficients[0])


def amplitude_start(ds: xr.Dataset, time: float) -> np.ndarray:
    """The amplitude model's state at ``time`` [s] of a passage: the squared amplitudes there and the spin left
    by the energy partition, E*(Omega) = E_tot - kappa_n N - kappa_p P (E* = A Omega^2 / 2 + m g (r + e))."""
    setup = passage_setup(ds)
    times = ds.near_time.values
    k = int(np.argmin(np.abs(times - time))) if times.size and isinstance(time, numbers.Real) else None
    if k is None or not abs(times[k] - time) <= 0.5 * SAMPLE_STEP + 1e-9:
        raise ParameterError(f"time = {time!r} s is not a sample of the passage near the inverted spin; pick one of "
                             "its times (near_time)")
    spin = float(ds.spin.values[ds.near_spin.values == 1][k])
    energetics = mode_energetics(spin, setup)
    powers = [float(ds[f"{mode}_amplitude"].values[k]) ** 2 for mode in MODES]
    energy = float(ds.E_tot.values[ds.near_spin.values == 1][k])
    disk = setup.disk
    rest = energy - sum(energetics[f"{mode}_energy"] * p for mode, p in zip(MODES, powers)) - (
        disk.m * setup.gravity * (disk.r + disk.e))
    if rest <= 0:
        raise ParameterError(f"at {time} s the modes hold more than the kinetic energy; pick a later time")
    return np.array([math.sqrt(2.0 * rest / disk.A), *powers])


def modal_amplitudes(states: np.ndarray, spins: np.ndarray, setup: Setup | None = None) -> dict[str, np.ndarray]:
    """The nutation and precession amplitudes of ODE Model 1 states (N, 7) of ``setup`` about the inverted spin
    at their own spins alpha_dot (N,) [rad/s], with their eigenvalues there: {"<mode>_amplitude",
    "<mode>_rate" (Re lambda, 1/s), "<mode>_frequency" (Im lambda, rad/s)}."""
    setup = Setup() if setup is None else setup
    states, spins = np.asarray(states, dtype=float), np.atleast_1d(np.asarray(spins, dtype=float))
    if states.ndim != 2 or states.shape[1] != reduced.N_STATE or spins.shape != (len(states),):
        raise ParameterError(f"states of shape {states.shape} and spins of shape {spins.shape}: give states (N, "
                             f"{reduced.N_STATE}), one per row, and N spins")
    if not (np.all(np.isfinite(states)) and np.all(np.isfinite(spins))):
        raise ParameterError("states and spins must be finite numbers")
    system, pars = reduced.system(), inversion.parameters("smooth", setup)
    rows = [_split(system, x, spin, pars, setup) for x, spin in zip(states, spins)]
    keys = [f"{mode}_{what}" for mode in MODES for what in ("amplitude", "rate", "frequency")]
    return {k: np.array([row[k] for row in rows], dtype=float) for k in keys}


def passage(spin: float, *, setup: Setup | None = None, gamma0: float | None = None,
            slow_time: float = 3.0, tol: float = 1e-10) -> xr.Dataset:
    """Run ODE Model 1 from Table 3's start at initial spin ``spin`` [rad/s] for ``slow_time`` / eps [s] (or
    until it falls or lifts off) and split the samples near the inverted spin into its modes
    (:func:`modal_amplitudes`). Status ``completed`` when the run reached its end; ``not_inverted`` when S never
    passed r + 0.8 e (no passage to split); ``undecided`` when C1 lifted off (the bilateral model decides
    nothing from there, so the passage did not reach its end); ``nonfinite`` when the integration broke down (ending nonfinite; its finite samples are
    kept)."""
    setup = Setup() if setup is None else setup
    gamma0 = InitialState().gamma if gamma0 is None else float(gamma0)
    inversion.check_start(setup, gamma0)
    if not (math.isfinite(slow_time) and slow_time > 0):
        raise ParameterError(f"slow_time = {slow_time!r} (eps * t, m): give a positive number, e.g. 3")
    if not (math.isfinite(tol) and 0 < tol < 1e-3):
        raise ParameterError(f"tol = {tol!r}: give a Taylor tolerance between 0 and 1e-3 (default 1e-10)")
    if slow_time / setup.friction.eps / SAMPLE_STEP > MAX_SAMPLES:
        raise ParameterError(f"slow_time = {slow_time:g} m is {slow_time / setup.friction.eps:.3g} s at eps = "
                             f"{setup.friction.eps:g} m/s, more than {MAX_SAMPLES:.0e} samples; give a slow time of a "
                             "few metres (the stay lasts about 1)")
    eps, disk = setup.friction.eps, setup.disk
    system = reduced.system()
    pars = inversion.parameters("smooth", setup)
    t_end = slow_time / eps
    ta = copy.deepcopy(system.taylor(tol, events=True))
    ta.time = 0.0
    ta.state[:] = inversion.start_state("smooth", spin, setup, gamma0)
    ta.pars[:] = pars[: len(ta.pars)]
    times = np.linspace(0.0, t_end, int(math.ceil(t_end / SAMPLE_STEP)) + 1)
    result = ta.propagate_grid(times)
    states = result[-1]
    finite = np.all(np.isfinite(states), axis=1)
    kept = len(states) if finite.all() else int(np.argmin(finite))  # up to the first non-finite sample
    ending = _ending(result[0], system, broken=kept < len(states))
    states, times = states[:kept], times[:kept]
    observed = system.observe(states.T, pars)
    height = (np.asarray(observed["z_S"]) - disk.r) / disk.e  # z_S = r + height e
    spins = np.asarray(observed["alpha_dot"])
    up = np.flatnonzero(height > inversion.INVERSION_HEIGHT)
    t_inverted = times[up[0]] if up.size else NONE
    back = np.flatnonzero((times > t_inverted) & (height < 0.0)) if up.size else np.array([], int)
    t_back = times[back[0]] if back.size else NONE
    near = (height > NEAR_SPIN) & (times >= t_inverted) & ((times < t_back) if back.size else True) & bool(up.size)
    rows = {}
    for k in np.flatnonzero(near):
        try:
            rows[k] = _split(system, states[k], spins[k], pars, setup)
        except ParameterError:  # no nutation and precession at this spin (below their collision, or eps too large)
            near[k] = False
    keys = [f"{mode}_{what}" for mode in MODES for what in ("amplitude", "rate", "frequency")]
    modes = {key: np.array([rows[k][key] for k in sorted(rows)], dtype=float) for key in keys} if rows else {}
    info = dict(initial_spin=float(spin), gamma0=gamma0, ending=ending, t_end=float(times[-1]),
                t_inverted=float(t_inverted), t_fell_back=float(t_back))
    status = ("nonfinite" if ending == "nonfinite" else "undecided" if ending == "lift_off" else
              "completed" if up.size else "not_inverted")
    return _dataset(times, height, spins, np.asarray(observed["E_tot"]), near, modes, setup, status, info)


def _ending(outcome, system, broken: bool) -> str:
    """How a run ended: ``horizon``, the name of the terminal event, or ``nonfinite``."""
    if broken:
        return "nonfinite"
    if outcome == hy.taylor_outcome.time_limit:
        return "horizon"
    index = System.stopping_event(outcome, system.events)
    return "nonfinite" if index is None else system.events[index].name


def _dataset(times, height, spins, energy, near, modes, setup, status, info) -> xr.Dataset:
    units = {"amplitude": ("1", "modulus of the mode's coordinate (left eigenvector, unit-norm right)"),
             "rate": ("s-1", "real part of the mode's eigenvalue at the sample's spin"),
             "frequency": ("rad s-1", "imaginary part of the mode's eigenvalue at the sample's spin")}
    data = {"height": ("time", height, {"units": "1", "long_name": "height of S above G in units of e: "
                                        "(z_S - r) / e"}),
            "spin": ("time", spins, {"units": "rad s-1", "long_name": "spin about the vertical alpha_dot"}),
            "E_tot": ("time", energy, {"units": "J", "long_name": "total energy"}),
            "near_spin": ("time", near.astype("i1"), {"long_name": "whether the sample is split into modes",
                                                      "flag_values": np.array([0, 1], "i1"),
                                                      "flag_meanings": "away split_into_modes"})}
    for key, values in modes.items():
        mode, what = key.rsplit("_", 1)
        unit, long = units[what]
        data[key] = ("near", values, {"units": unit, "long_name": f"{mode}: {long}"})
    coords = {"time": ("time", times, {"units": "s", "long_name": "time"}),
              "near_time": ("near", times[near], {"units": "s", "long_name": "time of the samples split into "
                                                  "modes (S above r + 0.5 e, between inversion and fall-back)"})}
    ds = xr.Dataset(data, coords=coords)
    config = {"setup": to_dict(setup), "initial_spin": info["initial_spin"], "gamma0": info["gamma0"]}
    ending = f"the run ended: {info['ending']} at {info['t_end']:.2f} s"
    if status == "completed":
        back = (f"fell back below G at {info['t_fell_back']:.2f} s" if info["t_fell_back"] != NONE else
                "did not fall back below G")
        message = f"S passed r + {inversion.INVERSION_HEIGHT:g} e at {info['t_inverted']:.2f} s, {back}; {ending}"
    elif status == "undecided":
        before = "after" if info["t_inverted"] != NONE else "before"
        message = (f"C1 lifted off at {info['t_end']:.2f} s, {before} S passed r + {inversion.INVERSION_HEIGHT:g} e: "
                   "the bilateral model decides nothing from there")
    else:
        message = f"S never passed r + {inversion.INVERSION_HEIGHT:g} e; {ending}"
    ds.attrs = make_attrs("spin_passage", config, status, message, model=reduced.system().name,
                          **flat_parameters(setup), **info)
    return ds


def passage_setup(ds: xr.Dataset) -> Setup:
    """The :class:`Setup` a passage dataset was run with (its ``config``)."""
    kind = ds.attrs.get("kind") if isinstance(ds, xr.Dataset) else type(ds).__name__
    if kind != "spin_passage":
        raise ParameterError(f"not a passage dataset (kind {kind!r}); give one of spin_passage.passage")
    try:
        return setup_from_dict(json.loads(ds.attrs["config"])["setup"])
    except (KeyError, TypeError, ValueError):
        raise ParameterError("the passage dataset has no setup in its config; run spin_passage.passage again") from None


def modal_friction_power(ds: xr.Dataset, n_spins: int = 25) -> np.ndarray:
    """The friction power [W] of a passage's modes along dim ``near``: sum over the modes of
    "<mode>_friction_power" (:func:`mode_energetics`, on ``n_spins`` spins over the passage, interpolated) times
    the squared amplitude. Against the run's own dE/dt it says how much of the loss the linear modes explain."""
    setup = passage_setup(ds)
    if not (isinstance(n_spins, numbers.Integral) and n_spins >= 2):
        raise ParameterError(f"n_spins = {n_spins!r}: give an integer of at least 2")
    spins = ds.spin.values[ds.near_spin.values == 1]
    if spins.size == 0:
        raise ParameterError("the passage has no samples near the inverted spin (the start did not invert)")
    grid = np.linspace(spins.min(), spins.max(), n_spins) if np.ptp(spins) > 0 else spins[:1]
    table = [mode_energetics(float(w), setup) for w in grid]
    total = np.zeros(spins.size)
    for mode in MODES:
        coefficient = np.interp(spins, grid, [row[f"{mode}_friction_power"] for row in table])
        total += coefficient * ds[f"{mode}_amplitude"].values ** 2
    return total


def integrated_rate(ds: xr.Dataset, mode: str, t0: float, t1: float) -> tuple[float, float]:
    """(measured, predicted) change of ln amplitude of ``mode`` from t0 to t1 [s] of a passage: ln A(t1)/A(t0)
    against the integral of Re lambda(alpha_dot(t)) dt (trapezoid over the samples)."""
    if mode not in MODES:
        raise ParameterError(f"unknown mode {mode!r}; choose one of {', '.join(MODES)}")
    if not (math.isfinite(t0) and math.isfinite(t1) and t0 < t1):
        raise ParameterError(f"give finite times t0 < t1 [s], not [{t0}, {t1}]")
    times = ds.near_time.values
    inside = (times >= t0) & (times <= t1)
    if inside.sum() == 1 or (inside.sum() == 0 and times.size and times[0] <= t0 and t1 <= times[-1]):
        raise ParameterError(f"[{t0:g}, {t1:g}] s holds fewer than two samples ({SAMPLE_STEP:g} s apart); give a "
                             "longer window")
    if inside.sum() < 2 or not np.all(np.diff(np.flatnonzero(inside)) == 1) or (
            np.any(np.diff(times[inside]) > 1.5 * SAMPLE_STEP)):
        breaks = np.flatnonzero(np.diff(times) > 1.5 * SAMPLE_STEP)
        starts, ends = np.r_[0, breaks + 1], np.r_[breaks, times.size - 1]
        span = (", ".join(f"{times[i]:.2f}-{times[j]:.2f} s" for i, j in list(zip(starts, ends))[:4])
                + (", ..." if starts.size > 4 else "") if times.size else "none: the start did not invert")
        raise ParameterError(f"[{t0:g}, {t1:g}] s is not inside the passage near the inverted spin (its stretches: "
                             f"{span}); pick times inside one stretch")
    amplitude, rate = ds[f"{mode}_amplitude"].values[inside], ds[f"{mode}_rate"].values[inside]
    measured = math.log(amplitude[-1] / amplitude[0])
    predicted = float(np.trapezoid(rate, times[inside]))
    return measured, predicted

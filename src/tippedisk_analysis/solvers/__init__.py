"""One front, models registered by name: :func:`simulate`.

A registered model is a :class:`ModelInfo` whose ``run(setup, initial, t_end, **options)``
returns a dataset with the schema of :mod:`tippedisk_analysis.results`. Its contract:

1. validate its own options and raise :class:`ParameterError` naming the fix;
2. never store a non-finite value: end the run with a ``status`` instead;
3. store the configuration that produced the result (``config`` attribute).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import xarray as xr

from .. import defaults
from ..errors import ParameterError, UnknownModelError
from ..parameters import InitialState, Setup
from ..resources import check_memory
from . import moreau
from .moreau.models import QUATERNION


@dataclass(frozen=True)
class ModelInfo:
    name: str
    paper_name: str
    description: str
    aliases: tuple[str, ...]
    run: Callable[..., xr.Dataset]
    options: tuple[str, ...]  # keyword options ``run`` accepts


REGISTRY: dict[str, ModelInfo] = {}
_ALIASES: dict[str, str] = {}


def register(info: ModelInfo) -> ModelInfo:
    for key in (info.name, *info.aliases):
        if key in _ALIASES:
            raise ValueError(f"model name {key!r} registered twice")
        _ALIASES[key] = info.name
    REGISTRY[info.name] = info
    return info


def model_names() -> list[str]:
    """Every accepted model name and alias."""
    return sorted(_ALIASES)


def resolve(name: str) -> ModelInfo:
    """The model registered under ``name`` (or one of its aliases)."""
    key = str(name).strip().lower()
    if key not in _ALIASES:
        raise UnknownModelError(f"unknown model {name!r}; choose one of: {', '.join(REGISTRY)} "
                                f"(aliases: {', '.join(sorted(set(_ALIASES) - set(REGISTRY)))})")
    return REGISTRY[_ALIASES[key]]


def simulate(model: str = "ode-euler", t_end: float = 5.0, *, setup: Setup | None = None,
             initial: InitialState | None = None, **options) -> xr.Dataset:
    """Simulate the tippedisk with a registered model.

    setup: disk, friction, gravity (default: Tables 1-2, Sect. 6);
    initial: initial Euler angles and rates (default: Table 3);
    t_end [s]; further options depend on the model (e.g. ``dt_output``, ``tol``).
    Returns an ``xarray.Dataset`` on an output time grid, with ``status`` and ``message``.
    """
    if not isinstance(model, str):
        raise ParameterError(f"model = {model!r} is a {type(model).__name__}; give a model name such as 'ode-euler' "
                             "or 'm6' (tippedisk_analysis.model_names() lists them)")
    info = resolve(model)
    if not (isinstance(t_end, int | float) and not isinstance(t_end, bool) and math.isfinite(t_end) and t_end > 0):
        raise ParameterError(f"t_end = {t_end!r} s must be a positive number; give t_end > 0")
    setup = Setup() if setup is None else setup
    initial = InitialState() if initial is None else initial
    if not isinstance(setup, Setup):
        raise ParameterError(f"setup must be a Setup, not {type(setup).__name__}; give e.g. "
                             "Setup(disk=Disk(), friction=Friction(mu=0.3)) (tippedisk_analysis.Setup)")
    if not isinstance(initial, InitialState):
        raise ParameterError(f"initial must be an InitialState, not {type(initial).__name__}; give e.g. "
                             "InitialState(alpha_dot=40.0) (tippedisk_analysis.InitialState)")
    if "normalize_quaternion" in options and info.name not in moreau.MODELS:
        raise ParameterError(f"normalize_quaternion applies to the Moreau quaternion models ({_quaternion_names()}); "
                             f"{info.name} has no quaternion drift to correct", cli=f"--normalize-quaternion applies to "
                             f"the Moreau quaternion models ({_quaternion_names()}); drop it for {info.name}")
    if "normalize_quaternion" in options and moreau.MODELS[info.name].parameterization != QUATERNION:
        raise ParameterError(f"normalize_quaternion applies to the Moreau quaternion models ({_quaternion_names()}); "
                             f"{info.name} uses Euler angles", cli=f"--normalize-quaternion applies to the Moreau "
                             f"quaternion models ({_quaternion_names()}); {info.name} uses Euler angles: drop it")
    unknown = set(options) - set(info.options)
    if unknown:
        raise ParameterError(f"model {info.name!r} takes no option(s) {sorted(unknown)}; "
                             f"it takes {sorted(info.options)}")
    _check_positive(options, ("dt_output", "tol", "slip_smoothing", "dt"))
    if "tol" in options and not 1e-16 <= options["tol"] < 1:
        raise ParameterError(f"tol = {options['tol']!r} must lie in [1e-16, 1) (double precision resolves no less); "
                             "give e.g. 1e-13 (ODE) or 1e-8 (Moreau)")
    _check_memory(info, float(t_end), options)
    return info.run(setup, initial, float(t_end), **options)


BYTES_PER_SAMPLE = {"ode": 1200.0, "moreau": 2500.0}
"""Memory per stored sample: the raw rows or states, the schema variables (30-80 doubles) and their
copies in the dataset and the netCDF encoding (measured ~4x the dataset)."""


def estimate_samples(info: ModelInfo, t_end: float, options: dict) -> float:
    """Samples a run stores (ODE: t_end / dt_output; Moreau: steps / store_every)."""
    if info.name in moreau.MODELS:
        dt = options.get("dt", defaults.MOREAU_DT)
        store_every = options.get("store_every") or max(1, int(round(defaults.MOREAU_STORE_INTERVAL / dt)))
        return math.floor(t_end / dt) / store_every + 1
    return t_end / options.get("dt_output", 1e-3) + 2


def _check_memory(info: ModelInfo, t_end: float, options: dict) -> None:
    kind = "moreau" if info.name in moreau.MODELS else "ode"
    n = estimate_samples(info, t_end, options)
    finer = "store_every" if kind == "moreau" else "dt_output"
    check_memory(n * BYTES_PER_SAMPLE[kind], f"the {info.name} run storing {n:,.0f} samples",
                 f"use a shorter t_end or a coarser sampling (a larger {finer})",
                 cli_fix=f"use a shorter --t-end or a coarser sampling (a larger --{finer.replace('_', '-')})")


def _quaternion_names() -> str:
    return ", ".join(f"m{m.number}" for m in moreau.MODELS.values() if m.parameterization == QUATERNION)


def _check_positive(options: dict, names) -> None:
    for name in names:
        if name in options:
            value = options[name]
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ParameterError(f"{name} = {value!r} must be a positive number")


def _run_ode(model_name: str):
    def run(setup, initial, t_end, **options):
        from . import taylor  # heyoka is imported on first use only

        return taylor.run(model_name, setup, initial, t_end, **options)

    return run


_ODE_OPTIONS = ("dt_output", "tol", "fall_angle", "slip_smoothing")
register(ModelInfo("ode-euler", "ODE Model 1", "Euler angles, bilateral contact at C1, smooth Coulomb (heyoka)",
                   ("ode1",), _run_ode("ode-euler"), _ODE_OPTIONS))
register(ModelInfo("ode-quaternion", "ODE Model 2", "quaternions, bilateral contact at C1, smooth Coulomb (heyoka)",
                   ("ode2",), _run_ode("ode-quaternion"), _ODE_OPTIONS))


def _run_hybrid(setup, initial, t_end, **options):
    from . import hybrid  # heyoka is imported on first use only

    return hybrid.run(setup, initial, t_end, **options)


register(ModelInfo("hybrid-euler", "Models 1/2 (event-driven)", "Euler angles, bilateral contact at C1, "
                   "set-valued Coulomb: rolling and sliding switched by events (heyoka)", ("h1",), _run_hybrid,
                   (*_ODE_OPTIONS, "max_switches")))


def _run_moreau(model_name: str):
    def run(setup, initial, t_end, **options):
        return moreau.run(model_name, setup, initial, t_end, **options)  # numba loads on first use

    return run


for _name, _model in moreau.MODELS.items():
    register(ModelInfo(_name, _model.paper_name, _model.description, (f"m{_model.number}",), _run_moreau(_name),
                       moreau.OPTIONS))

"""Moreau's midpoint time-stepping scheme (Sect. 4, (4.1)-(4.7)) for the paper's Models 1-10.

One numba step loop serves all ten models of Table 4; the model picks the parameterization
(Euler angles (3.1)-(3.39) or quaternions (3.40)-(3.67)) and the dissipation mechanisms.

* :mod:`.models` -- the model table and run options (pure Python);
* :mod:`.layout` -- named indices of every array the loop shares with Python;
* :mod:`.step` -- the numba step loop; :mod:`.force_laws` -- one prox sweep per contact law;
* :mod:`.driver` -- initial state, parameters, validation, progress, :mod:`.checkpoint`;
* :mod:`.dataset` -- the xarray dataset of a run.

Force laws per closed contact: Signorini/Newton (2.20)-(2.21); set-valued Coulomb (2.22)/(2.28);
Coulomb-Contensou (2.24)-(2.27) as one Euclidean projection onto the friction ball; smooth
Coulomb (2.29) at the end-of-step slip (implicit in the slip, first order, relaxed); dry
pivoting (2.30) and contour friction (2.31) as interval projections.

Importing this package loads no numba code; :func:`run` compiles (or loads numba's cache) on first use.
"""

from __future__ import annotations

from .models import MODELS, OPTIONS, MoreauModel

__all__ = ["MODELS", "OPTIONS", "MoreauModel", "run"]


def run(model_name: str, setup, initial, t_end: float, **options):
    """Simulate a Moreau model (see :func:`.dataset.run`)."""
    from .dataset import run as run_dataset  # numba loads here, on first use

    return run_dataset(model_name, setup, initial, t_end, **options)

"""The paper's Moreau Models 1-10 (Table 4): parameterization and dissipation of each, and the run options.

Pure Python (no numba): the model registry of :mod:`tippedisk_analysis.solvers` reads it
without compiling anything.
"""

from __future__ import annotations

from dataclasses import dataclass

# friction law of the tangential direction
COULOMB, CONTENSOU, SMOOTH = 0, 1, 2
LAW_NAMES = {COULOMB: "set-valued Coulomb", CONTENSOU: "Coulomb-Contensou", SMOOTH: "smooth Coulomb"}
# orientation parameterization
EULER, QUATERNION = 0, 1


@dataclass(frozen=True)
class MoreauModel:
    name: str
    number: int
    parameterization: int  # EULER or QUATERNION
    law: int  # COULOMB, CONTENSOU or SMOOTH
    pivot_contour: bool  # dry pivoting (2.30) and contour friction (2.31)

    @property
    def paper_name(self) -> str:
        return f"Model {self.number}"

    @property
    def description(self) -> str:
        extra = " + pivoting + contour" if self.pivot_contour else ""
        par = "Euler angles" if self.parameterization == EULER else "quaternions"
        return f"Moreau time stepping, {par}, unilateral contacts C1-C3, {LAW_NAMES[self.law]}{extra} (numba)"


def _models() -> dict[str, MoreauModel]:
    laws = [("coulomb", COULOMB, False), ("contensou", CONTENSOU, False), ("smooth", SMOOTH, False),
            ("coulomb-pivot-contour", COULOMB, True), ("smooth-pivot-contour", SMOOTH, True)]
    out = {}
    for i, (label, law, pivot_contour) in enumerate(laws):
        for j, (par_label, par) in enumerate((("euler", EULER), ("quaternion", QUATERNION))):
            number = 2 * i + j + 1
            name = f"moreau-{label}-{par_label}"
            out[name] = MoreauModel(name, number, par, law, pivot_contour)
    return out


MODELS: dict[str, MoreauModel] = _models()
OPTIONS = ("dt", "tol", "store_every", "max_iter", "r_N", "r_T", "r_tau", "r_R", "normalize_quaternion",
           "fall_angle", "progress", "checkpoint", "contensou_torque_share")

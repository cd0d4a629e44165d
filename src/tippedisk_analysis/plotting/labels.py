"""One style across the figures: axis labels "quantity symbol [unit]" (units as in the text, rad/s), and
branches drawn stable solid, marginal dotted, unstable dashed."""

from __future__ import annotations

import re

# name: label without the unit
NAMES = {
    "omega": r"spin rate $\Omega$",
    "alpha_dot": r"$\dot\alpha$",
    "eps": r"smoothing $\varepsilon$",
    "mu": r"friction coefficient $\mu$",
    "e": "eccentricity $e$",
    "dgamma0": r"initial perturbation $\Delta\gamma_0$",
    "beta0": r"initial tilt $\beta_0$",
    "alpha": r"$\alpha$",
    "beta": r"$\beta$",
    "gamma": r"$\gamma$",
    "beta_dot": r"$\dot\beta$",
    "gamma_dot": r"$\dot\gamma$",
    "z_S": r"$z_S$",
    "z": r"$z_G$",
    "g_N1": r"$g_{N1}$",
    "lambda_N": r"$\lambda_N$",
    "E_kin": r"$E_\mathrm{kin}$",
    "E_pot": r"$E_\mathrm{pot}$",
    "E_tot": r"$E_\mathrm{tot}$",
    "time": "time $t$",
    "inertia": "inertia scale",
    "max_real_eig": r"max Re $s$",
    "omega_x": r"$\omega_x$",
    "omega_y": r"$\omega_y$",
    "omega_z": r"$\omega_z$",
}

UNITS = {"rad s-1": "rad/s", "m s-1": "m/s", "s-1": "1/s", "m s-2": r"m/s$^2$", "rad s-2": r"rad/s$^2$", "1": "-",
         "kg m2": r"kg m$^2$"}
ENDED_WELL = ("completed", "converged")  # statuses a figure's title leaves unsaid


def unit(units: str) -> str:
    """CF units as written in the figures: rad s-1 -> rad/s, 1 -> -."""
    return UNITS.get(units.strip(), units.strip())


def symbol(name: str) -> str:
    """The mathtext symbol of a quantity, e.g. symbol("eps") -> "$\\varepsilon$"; a name without one as it is."""
    found = re.findall(r"\$[^$]+\$", NAMES.get(name, ""))
    return found[-1] if found else name


def with_symbols(text: str) -> str:
    """Names of quantities in a text (a section "beta_dot=0") as their symbols ("$\\dot\\beta$=0")."""
    return re.sub(r"[A-Za-z_]\w*", lambda m: symbol(m.group(0)) if m.group(0) in NAMES else m.group(0), str(text))


def ending(status: str) -> str:
    """What a title says of a run's status: nothing when it ended well, else ", STATUS"."""
    return "" if not status or status in ENDED_WELL else f", {status}"


def is_tippedisk(ds) -> bool:
    """Whether a dataset is the tippedisk's (physical names, SI) rather than of a user's System, whose names
    (a parameter mu, a time t) mean whatever the user declared."""
    return not ds.attrs.get("system") or str(ds.attrs["system"]).startswith(("tippedisk", "rolling"))


def axis_label(name: str, units: str = "", physical: bool = True) -> str:
    """e.g. axis_label("omega", "rad s-1") -> "spin rate $\\Omega$ [rad/s]"; ``physical=False`` (a user's
    System): the name as declared."""
    text = NAMES.get(name, name.replace("_", " ")) if physical else name
    return f"{text} [{unit(units)}]" if units else text


STABILITY_STYLE = {0: "-", 1: ":", 2: "--"}  # flag values of stability.STABILITY_FLAGS


def runs(x, y, flag):
    """(x, y, flag) pieces of equal ``flag``, each with the first point of the next piece (no gaps)."""
    start = 0
    for i in range(1, len(x) + 1):
        if i == len(x) or flag[i] != flag[start]:
            yield x[start:i + (i < len(x))], y[start:i + (i < len(x))], int(flag[start])
            start = i

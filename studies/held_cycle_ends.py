"""The held-spin model's cycle branches to their ends (docs/inversion_held_spin.md, "Its cycles to their ends").

    tippedisk study held_cycle_ends [--output-dir DIR] [--quick]

The branches of periodic orbits born at HOPF1 (the precession turns growing) and HOPF2 (the nutation turns damped,
omega_c) of the inverted spin, continued in the held spin by collocation (error_tol 1e-8, period bound PERIOD_MAX)
at eps = 0.01 and 0.005 m/s and, at eps = 0.01 m/s, for e = 1.2 and 0.9 mm (Tables 1-2 otherwise, A, B, C about G
kept): every fold (LP) and branch point (BP), and the end: the model's cone event (EVENT: |lambda_T| reaches
0.95 mu lambda_N of the rolling forces, where the slow flow stops), the period bound with its infinite-period limit
(HC, HET or PB, dynamics/period_limits.py), or a parameter bound. Per orbit it stores how close the orbit comes to
the lower spin (S straight below G) and to the cone. Writes held_cycle_ends.nc, held_cycle_ends.png (the periods
over the spin) and held_cycle_ends_link.png (the HOPF2 branch against the spins of the inversion).
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr
from tippedisk_studies._common import prepare, save

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics.orbit_datasets import SPECIAL_KINDS
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.plotting import style
from tippedisk_analysis.results import make_attrs

CASES = {"eps 0.01": {"eps": 0.01}, "eps 0.005": {"eps": 0.005}, "e 1.2 mm": {"eps": 0.01, "e": 0.0012},
         "e 0.9 mm": {"eps": 0.01, "e": 0.0009}}
"""Runtime parameters changed from Tables 1-2 (eps [m/s], e [m])."""
QUICK = {"eps 0.01": {"eps": 0.01}}
SPINS = (20.0, 40.0)  # rad/s: the equilibrium branch and the orbit branches
QUICK_SPINS = (20.0, 27.0)
PERIOD_MAX = 6.0  # s
MAX_POINTS = 700
LOWER = held_spin.spin_state("lower")
INVERSION = {r"$\omega_c$ (C4)": 30.2325, r"held threshold, $\varepsilon$ 0.01": 31.4595, "(C5)": 32.9532,
             "full model threshold": 33.6908, "(C7)": 35.1599}
"""Spins [rad/s] of the inversion of the Tables 1-2 disk from docs/inversion_held_spin.md and
docs/inversion_criterion.md: omega_c, the held model's threshold from Table 3's start (eps 0.01 m/s), (C5), ODE
Model 1's threshold for r + 0.8 e at eps 0.1 m/s, (C7)."""
LOWER_HOMOCLINIC = {0.01: 30.86333994, 0.005: 30.81545051}
"""Held spins [rad/s] of the lower spin's homoclinic orbit (studies/lower_spin_homoclinic.py) by eps [m/s]."""


def lower_distance(system, samples: np.ndarray) -> float:
    """Least scaled distance of an orbit's samples from the lower spin (gamma taken modulo 2 pi)."""
    d = samples - LOWER
    d[:, 1] = (d[:, 1] + math.pi) % (2 * math.pi) - math.pi
    return float(np.min(np.linalg.norm(d / np.asarray(system.state_scale), axis=1)))


def branch(system, eq, label: str, spins) -> tuple[xr.Dataset, float]:
    """(the orbit branch from ``label``, its wall time [s])."""
    start = time.perf_counter()
    po = dy.orbit_branch(system, eq, label, bounds=spins, error_tol=1e-8, period_max=PERIOD_MAX,
                         max_points=MAX_POINTS, end_at_events=True)
    return po, time.perf_counter() - start


def rows_of(case: str, label: str, po: xr.Dataset, system) -> tuple[list, list, dict]:
    """(orbit rows, special-point rows, the branch's summary) of one branch."""
    cone = system.function("cone", [e.expression for e in system.events if e.name == "cone"])
    orbits = []
    for k in range(po.sizes["point"]):
        samples, pars = po.orbit[k].values, po.runtime_parameters[k].values
        g = system.evaluate(cone, samples.T.copy(), pars)[0]
        orbits.append({"case": case, "hopf": label, "spin": float(po.spin[k]), "period": float(po.period[k]),
                       "amplitude": 0.5 * float(np.ptp(samples[:, 1])), "n_unstable": int(po.n_unstable[k]),
                       "lower_distance": lower_distance(system, samples), "cone": float(g.min() / np.abs(g).max()),
                       "ntst": int(po.ntst[k])})
    kinds = {code: kind for kind, code in SPECIAL_KINDS.items()}
    special = [{"case": case, "hopf": label, "label": str(name), "kind": kinds[int(kind)], "spin": float(po.spin[i]),
                "period": float(po.period[i])}
               for name, kind, i in zip(po.special_label.values, po.special_kind.values, po.special_index.values)]
    summary = {"status": po.attrs["status"], "message": po.attrs["message"], "unlocated": po.attrs.get("unlocated", "")}
    return orbits, special, summary


def dataset(orbits: list, special: list, summaries: dict, cases: dict, times: dict) -> xr.Dataset:
    """Kind cycle_ends: every orbit (dimension ``orbit``: its case, Hopf point, spin, period, gamma's half range,
    multipliers outside the unit circle, distance from the lower spin, cone margin) and every special point
    (``special``); per branch its status, message and wall time in the attribute ``branches`` (JSON)."""
    def column(rows, key):
        return [r[key] for r in rows]

    data = {
        "case": ("orbit", column(orbits, "case"), {"long_name": "parameters changed from Tables 1-2"}),
        "hopf": ("orbit", column(orbits, "hopf"), {"long_name": "the Hopf point of the inverted spin the branch "
                                                                 "starts at"}),
        "spin": ("orbit", column(orbits, "spin"), {"units": "rad s-1", "long_name": "held spin"}),
        "period": ("orbit", column(orbits, "period"), {"units": "s", "long_name": "period"}),
        "amplitude": ("orbit", column(orbits, "amplitude"), {"units": "rad", "long_name": "half the range of gamma "
                                                                                           "over the orbit"}),
        "n_unstable": ("orbit", np.array(column(orbits, "n_unstable"), np.int32),
                       {"units": "1", "long_name": "nontrivial multipliers outside the unit circle"}),
        "ntst": ("orbit", np.array(column(orbits, "ntst"), np.int32),
                 {"units": "1", "long_name": "collocation mesh intervals (at most 640 = 16 times the start's)"}),
        "lower_distance": ("orbit", column(orbits, "lower_distance"), {
            "units": "1", "long_name": "least distance of the orbit from the lower spin (scaled states, gamma "
                                      "modulo 2 pi)"}),
        "cone_margin": ("orbit", column(orbits, "cone"), {
            "units": "1", "long_name": "min over the orbit of the cone event's function over its largest size: "
                                      "0 where the orbit reaches |lambda_T| = 0.95 mu lambda_N"}),
        "special_case": ("special", column(special, "case"), {"long_name": "case of the special point"}),
        "special_hopf": ("special", column(special, "hopf"), {"long_name": "branch of the special point"}),
        "special_label": ("special", column(special, "label"), {"long_name": "LP fold of cycles, BP branch point, "
                          "EVENT the cone reached, HC/HET/PB the period bound"}),
        "special_kind": ("special", column(special, "kind"), {"long_name": "kind of the special point"}),
        "special_spin": ("special", column(special, "spin"), {"units": "rad s-1", "long_name": "held spin"}),
        "special_period": ("special", column(special, "period"), {"units": "s", "long_name": "period"}),
    }
    branches = {f"{case}, {label}": {**summary, "seconds": round(times[(case, label)], 1)}
                for (case, label), summary in summaries.items()}
    message = "; ".join(f"{name}: {b['status']}, {b['message'].split('; ')[1] if '; ' in b['message'] else ''}"
                        for name, b in branches.items())
    ds = xr.Dataset(data)
    ds.attrs = make_attrs("cycle_ends", {"cases": cases, "spins": list(SPINS), "period_max": PERIOD_MAX,
                                         "error_tol": 1e-8, "max_points": MAX_POINTS}, "completed", message,
                          model=held_spin.system().name, title="Cycle branches of the held-spin model to their ends",
                          branches=json.dumps(branches))
    return ds


def _branch_lines(axis, ds, hopf: str, quantity: str, marks: bool = True) -> None:
    for j, case in enumerate(dict.fromkeys(ds.case.values)):
        on = (ds.case.values == case) & (ds.hopf.values == hopf)
        if not on.any():
            continue
        name = case.replace("eps", r"$\varepsilon$")
        axis.plot(ds.spin.values[on], ds[quantity].values[on], color=f"C{j}", lw=1.0, label=f"{hopf}, {name}")
        sp = (ds.special_case.values == case) & (ds.special_hopf.values == hopf)
        if marks and quantity == "period":
            for kind, marker in (("fold", "o"), ("branch_point", "x"), ("event", "s")):
                at = sp & (ds.special_kind.values == kind)
                axis.plot(ds.special_spin.values[at], ds.special_period.values[at], marker, color=f"C{j}", ms=5,
                          mfc="none", ls="none")


@style.styled
def figure(ds: xr.Dataset, path: Path) -> None:
    """Stacked: the periods of the HOPF1 branches over the held spin; those of the HOPF2 branches."""
    fig, axes = style.stacked(2, panel_height=4.0)
    for axis, hopf in zip(axes, ("HOPF1", "HOPF2")):
        _branch_lines(axis, ds, hopf, "period")
        axis.set(xlabel=r"held spin $\Omega$ [rad s$^{-1}$]", ylabel=r"period [s]",
                 title=f"{hopf} branches (circles LP, crosses BP, squares the cone)")
        if axis.get_legend_handles_labels()[0]:
            axis.legend(loc="upper left")
    save(fig, path)


@style.styled
def link_figure(ds: xr.Dataset, path: Path) -> None:
    """Stacked: gamma's half range on the Tables 1-2 disk's HOPF2 branches (the nutation cycles) over the held spin,
    with the spins of the inversion; every HOPF2 branch's distance from the lower spin."""
    fig, (top, bottom) = style.stacked(2, panel_height=4.0, extra=2.2)
    tables = ds.where(ds.case.isin(["eps 0.01", "eps 0.005"]), drop=True)
    _branch_lines(top, tables, "HOPF2", "amplitude", marks=False)
    _branch_lines(bottom, ds, "HOPF2", "lower_distance", marks=False)
    for j, (name, spin) in enumerate(INVERSION.items()):
        top.axvline(spin, color=f"C{j + 4}", ls="--", lw=1.0, label=name)
    for axis in (top, bottom):
        axis.axvline(LOWER_HOMOCLINIC[0.01], color="k", ls=":", lw=1.0,
                     label=r"lower spin's homoclinic orbit, $\varepsilon$ 0.01" if axis is top else None)
    top.set(xlabel=r"held spin $\Omega$ [rad s$^{-1}$]", ylabel=r"$\frac{1}{2}$ range of $\gamma$ [rad]",
            title="Tables 1-2: the nutation cycles (HOPF2) and the inversion")
    style.legend_below(top, 0.18, ncol=2)
    bottom.set(xlabel=r"held spin $\Omega$ [rad s$^{-1}$]", ylabel="distance from the lower spin",
               yscale="log", title="how close each HOPF2 cycle comes to the lower spin")
    if bottom.get_legend_handles_labels()[0]:
        bottom.legend(loc="lower right")
    save(fig, path)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> Path:
    """held_cycle_ends.png and held_cycle_ends_link.png again from the stored held_cycle_ends.nc."""
    ds = td.load(Path(data_dir) / "held_cycle_ends.nc")
    path = Path(figure_dir) / "held_cycle_ends.png"
    figure(ds, path)
    link_figure(ds, path.with_name("held_cycle_ends_link.png"))
    return path


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    cases, spins = (QUICK, QUICK_SPINS) if quick else (CASES, SPINS)
    system = held_spin.system()
    orbits, special, summaries, times = [], [], {}, {}
    for case, changed in cases.items():
        eq = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=spins,
                                   pars=system.with_pars(spin=spins[0], **changed), ds_max=1.0)
        hopfs = [str(label) for label in eq.special_label.values if str(label).startswith("HOPF")]
        print(f"{case}: the inverted spin's Hopf points " + ", ".join(
            f"{label} {float(eq.spin[eq.special_index.values[list(eq.special_label.values).index(label)]]):.6f}"
            for label in hopfs), flush=True)
        for label in hopfs:
            po, seconds = branch(system, eq, label, spins)
            rows, points, summary = rows_of(case, label, po, system)
            orbits += rows
            special += points
            summaries[(case, label)], times[(case, label)] = summary, seconds
            print(f"  {label}: {po.sizes['point']} orbits in {seconds:.1f} s; {summary['status']}: "
                  f"{summary['message']}", flush=True)
            print("    " + ", ".join(f"{p['label']} {p['spin']:.6f} (T {p['period']:.4f})" for p in points),
                  flush=True)
            last = rows[-1]
            print(f"    last orbit: spin {last['spin']:.6f}, period {last['period']:.4f} s, {last['n_unstable']} "
                  f"multiplier(s) outside, {last['lower_distance']:.3g} from the lower spin, cone margin "
                  f"{last['cone']:.3g}, ntst {last['ntst']}", flush=True)
    path = td.save(dataset(orbits, special, summaries, cases, times), out / "held_cycle_ends.nc")
    ds = td.load(path)
    figure(ds, path.with_name("held_cycle_ends.png"))
    link_figure(ds, path.with_name("held_cycle_ends_link.png"))
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])

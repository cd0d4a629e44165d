"""Sect. 6 table: every checkable statement of the paper's Sect. 6 with the paper's and the package's value.

Runs the Moreau models and ODE Model 2 at the paper's settings (Table 3, Sect. 6, dt = 1e-5 s, quaternions
normalised), stores a compact copy of each run (sect6_<run>.nc: angles, z_S, energies, g_N1; 1-ms samples
on [0, 5] s, 10-ms samples after; float32), computes the table from those copies only, and writes it as
sect6_table.md and a scorecard figure. The stored copies of a full run live in data/sect6/; the test
tests/test_paper_table.py recomputes the table from them and checks it against studies/README.md and
docs/paper.md. Fig. 13 and Fig. 17 statements read fig13_ode_inversion.nc and fig17_stroboscope.nc (their
own studies; data/).

    tippedisk study sect6_table [--output-dir DIR] [--quick]
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from tippedisk_studies._common import (CONTENSOU_VARIANT, amplitude, down_time, first_time, inversion_time,
                                       leave_time, onset_of_fast_oscillation, prepare, save, window)

import tippedisk_analysis as td
from tippedisk_analysis.results import config_of

# run key: (model, t_end [s], options)
RUNS = {
    "m1": ("m1", 5.0, {}),
    "m2": ("m2", 5.0, {}),
    "m2_unnormalized": ("m2", 5.0, {"normalize_quaternion": False}),
    "m3_law": ("m3", 5.0, {}),
    "m3_variant": ("m3", 5.0, CONTENSOU_VARIANT),
    "m4_law": ("m4", 25.0, {}),
    "m4_variant": ("m4", 25.0, CONTENSOU_VARIANT),
    "m5": ("m5", 5.0, {}),
    "m6": ("m6", 25.0, {}),
    "m8": ("m8", 5.0, {}),
    "m10": ("m10", 25.0, {}),
    "ode2": ("ode-quaternion", 25.0, {"dt_output": 1e-3}),
    "h1": ("h1", 5.0, {}),
}
KEPT = ("alpha", "beta", "gamma", "z_S", "E_kin", "E_pot", "E_tot", "g_N1", "mode")  # mode: h1 only
DOUBLE = ("E_tot",)  # kept in float64: a 1e-9 J energy criterion needs more than float32's 3e-8 J step
FINE_UNTIL, COARSE_EVERY = 5.0, 10  # 1-ms samples on [0, 5] s, every 10th (10 ms) after
R_MINUS_E, R_PLUS_E = td.Disk().r - td.Disk().e, td.Disk().r + td.Disk().e
VERDICTS = ("reproduced", "partly", "not reproduced")


def compact(ds):
    """The stored copy of a run: the variables of KEPT as float32 (DOUBLE as float64), 1-ms samples on [0, 5] s,
    10 ms after."""
    t = ds.time.values
    index = np.flatnonzero(t <= FINE_UNTIL + 1e-9)
    late = np.flatnonzero(t > FINE_UNTIL + 1e-9)
    keep = np.concatenate([index, late[COARSE_EVERY - 1::COARSE_EVERY]])
    small = ds[[v for v in KEPT if v in ds]].isel(time=keep)
    small = small.assign({k: v.astype(np.float32) for k, v in small.data_vars.items()
                          if v.dtype.kind == "f" and k not in DOUBLE})
    small = small.assign_coords(time=ds.time.values[keep])
    small.attrs = dict(ds.attrs, sampling="1-ms samples on [0, 5] s, 10-ms samples after; float32 but E_tot "
                                          "(studies/sect6_table.py)")
    return td.results.describe(small)


def simulate_runs(out: Path, quick: bool = False) -> dict:
    """Run every entry of RUNS (0.3 s when quick) and store its compact copy as <out>/sect6_<key>.nc."""
    runs = {}
    for key, (model, t_end, options) in RUNS.items():
        ds = td.simulate(model, 0.3 if quick else t_end, **options)
        td.save(compact(ds), out / f"sect6_{key}.nc")
        runs[key] = td.load(out / f"sect6_{key}.nc")
        print(f"{key:>16}: {ds.attrs['paper_model']} {ds.attrs['status']} ({ds.attrs.get('message', '')})")
    return runs


def load_runs(folder: Path) -> dict:
    """The stored compact copies of RUNS in ``folder`` (sect6_<key>.nc)."""
    return {key: td.load(Path(folder) / f"sect6_{key}.nc") for key in RUNS}


# ----------------------------------------------------------------------------- the statements


@dataclass(frozen=True)
class Row:
    figure: str
    statement: str
    paper: str
    package: str
    criterion: str
    verdict: str


def _fmt(x, spec=".3g", unit="") -> str:
    if x is None:
        return "never"
    if isinstance(x, float) and not math.isfinite(x):
        return "n/a"
    return f"{x:{spec}}{(' ' + unit) if unit else ''}"


def _since(t: float | None) -> str:
    return "never" if t is None else f"from {t:.2f} s"


def _judge(ok: bool, partly: bool = False) -> str:
    """The verdict of a row from its computed criterion (and the weaker one for "partly")."""
    return "reproduced" if ok else ("partly" if partly else "not reproduced")


def _mean(ds, name, t0, t1) -> float:
    values = window(ds, name, t0, t1)
    return float(np.mean(values)) if values.size else math.nan


def _at(ds, name, t) -> float:
    if float(ds.time[-1]) < t - 1e-9:
        return math.nan
    return float(ds[name].sel(time=t, method="nearest"))


def _ratio(ds, name="gamma") -> float:
    return amplitude(ds, 4, 5, name) / amplitude(ds, 1, 2, name)


def _rate(ds, t0, t1) -> float:
    """Mean dissipation rate -dE_tot/dt [W] on [t0, t1]."""
    return (_at(ds, "E_tot", t0) - _at(ds, "E_tot", t1)) / (t1 - t0)


ONSET_CRITERION = "first 1-s window with beta's dominant frequency > 4 Hz; within 0.5 s of the paper (partly: 1 s)"


def _onset_verdict(onset, paper) -> str:
    if onset is None:
        return "not reproduced"
    return _judge(abs(onset - paper) <= 0.5, partly=abs(onset - paper) <= 1.0)


def _saturated_gap(ds, paper):
    g25, g5 = _at(ds, "g_N1", 2.5), _at(ds, "g_N1", 5.0)
    ok = abs(g5 / paper - 1) < 0.2 and abs(g5 - g25) < 0.1 * abs(g5)
    return g25, g5, ok


def table_rows(runs: dict, fig13=None, fig17=None, rolling=None) -> list[Row]:
    """The rows of the Sect. 6 table, computed from the stored runs (see RUNS), the Fig. 13/17 datasets and the
    rolling torus of studies/rolling.py (rolling_orbit.nc)."""
    r = runs
    rows = []

    def add(row: Row) -> None:  # a number that is not finite is an error, never a silent "not reproduced"
        if re.search(r"\bnan\b|\binf\b|n/a", row.package, re.IGNORECASE):
            raise ValueError(f"Sect. 6 row {len(rows) + 1} ({row.statement[:60]}...): a number of the package is not "
                             f"finite ({row.package}); the stored runs are too short or damaged")
        rows.append(row)

    # --- Sect. 6.1, Figs. 7/8: set-valued Coulomb
    m1, m2, m2u = r["m1"], r["m2"], r["m2_unnormalized"]
    z1 = _mean(m1, "z_S", 1, 5)
    add(Row("7", "Model 1: z_S oscillates aperiodically about 0.044 m (mean on [1, 5] s)", "0.044 m",
            f"{z1:.5f} m", "|mean - 0.044| < 5e-4 m", _judge(abs(z1 - 0.044) < 5e-4)))
    zmax = float(window(m1, "z_S", 1, 5).max()) if window(m1, "z_S", 1, 5).size else math.nan
    add(Row("7", "Model 1: z_S does not reach r + e = 47.5 mm", "below r + e",
            f"max z_S on [1, 5] s = {zmax * 1e3:.2f} mm",
            "max < 47 mm", _judge(zmax < 0.047)))
    ag, ab = amplitude(m1, 1, 5), amplitude(m1, 1, 5, "beta")
    add(Row("7", "Model 1: gamma oscillates about pi/2 with a large amplitude, beta changes only slightly",
            "large / slight", f"gamma +-{ag:.2f} rad about {_mean(m1, 'gamma', 1, 5):.2f} rad; beta +-{ab:.2f} rad",
            "gamma amplitude > 1 rad, beta's < 0.3 x gamma's", _judge(ag > 1 and ab < 0.3 * ag)))
    early, late = _at(m1, "E_tot", 0) - _at(m1, "E_tot", 0.5), _at(m1, "E_tot", 0.5) - _at(m1, "E_tot", 5)
    add(Row("7", "Model 1: E_tot dissipates on [0, 0.5] s, almost constant after", "drop, then ~constant",
            f"{early * 1e3:.1f} mJ on [0, 0.5] s, {late * 1e3:.2g} mJ on [0.5, 5] s", "later loss < 0.1 x early loss",
            _judge(late < 0.1 * early)))
    gmin, gmax = float(m1.g_N1.min()), float(m1.g_N1.max())
    add(Row("8", "Model 1: g_N1 changes with high frequency between 0 and -2e-9 m", "[-2e-9, 0] m",
            f"[{gmin:.3g}, {gmax:.2g}] m", "-3e-9 < min < -1e-9, max < 1e-10",
            _judge(-3e-9 < gmin < -1e-9 and gmax < 1e-10)))
    drift = [_mean(m2, "g_N1", t, t + 1) for t in (0, 2, 4)]
    add(Row("8", "Model 2: g_N1 decreases monotonically (constraint drift, no correction of the gap)",
            "monotone decrease",
            f"1-s means at 0/2/4 s: {drift[0]:.2g} / {drift[1]:.2g} / {drift[2]:.2g} m; g_N1(5 s) = "
            f"{_at(m2, 'g_N1', 5):.3g} m (unnormalised quaternion: {_at(m2u, 'g_N1', 5):.3g} m)",
            "1-s means decrease", _judge(drift[0] > drift[1] > drift[2])))
    z2 = _mean(m2, "z_S", 1, 5)
    add(Row("7", "Models 1 and 2 (Euler angles, quaternions) behave alike", "alike", f"mean z_S on [1, 5] s: "
            f"{z1 * 1e3:.2f} / {z2 * 1e3:.2f} mm; gamma amplitude {ag:.2f} / {amplitude(m2, 1, 5):.2f} rad",
            "mean z_S within 0.2 mm", _judge(abs(z1 - z2) < 2e-4)))

    # --- Sect. 6.2, Figs. 9/10: Coulomb-Contensou, the law (1 mm) and the variant (no torque, 2.9 mm)
    for key, name in (("law", "law as stated"), ("variant", "variant")):
        m3 = r[f"m3_{key}"]
        t_inv = inversion_time(m3)
        add(Row("9", f"Model 3 ({name}): inversion on [0, 0.5] s, gamma rises to pi/2", "within 0.5 s",
                f"gamma within 0.2 rad of pi/2 at {_fmt(t_inv, '.3f', 's')}", "t <= 0.55 s",
                _judge(t_inv is not None and t_inv <= 0.55)))
        ratio = _ratio(m3)
        add(Row("9", f"Model 3 ({name}): damped oscillation, gamma = pi/2 asymptotically stable", "damped",
                f"gamma amplitude {amplitude(m3, 1, 2):.3f} rad on [1, 2] s, {amplitude(m3, 4, 5):.3f} rad on [4, 5] s "
                f"(ratio {ratio:.2f})", "ratio < 0.5", _judge(ratio < 0.5)))
        rb = _ratio(m3, "beta")
        add(Row("9", f"Model 3 ({name}): beta performs a damped oscillation about pi/2", "damped",
                f"beta amplitude ratio [4, 5] s / [1, 2] s = {rb:.2f}", "ratio < 0.7", _judge(rb < 0.7)))
        onset = onset_of_fast_oscillation(m3)
        add(Row("9", f"Model 3 ({name}): gamma and beta start to oscillate with high frequency at t ~ 2 s", "~2 s",
                f"onset of beta's > 4 Hz oscillation: {_since(onset)}", ONSET_CRITERION, _onset_verdict(onset, 2.0)))
        z5, zlow = _at(m3, "z_S", 5), float(window(m3, "z_S", 0, 0.5).min())
        add(Row("9", f"Model 3 ({name}): z_S drops slightly, then grows to r + e = 47.5 mm", "r + e",
                f"min z_S on [0, 0.5] s {zlow * 1e3:.2f} mm (start {R_MINUS_E * 1e3:.1f} mm); "
                f"z_S(5 s) = {z5 * 1e3:.2f} mm",
                "drops, and z_S(5 s) > 47 mm", _judge(zlow < R_MINUS_E and z5 > 0.047)))
        fast, slow = _rate(m3, 0, 0.5), _rate(m3, 2, 5)
        add(Row("9", f"Model 3 ({name}): E_tot falls fast during the inversion; then the rate drops but stays > 0",
                "drops, nonzero", f"{fast * 1e3:.1f} mW on [0, 0.5] s, {slow * 1e3:.2f} mW on [2, 5] s",
                "0 < later rate < 0.2 x early rate", _judge(0 < slow < 0.2 * fast)))
        g25, g5, ok = _saturated_gap(r[f"m4_{key}"], -1.36e-5)
        add(Row("10", f"Model 4 ({name}): the gap drift saturates at -1.36e-5 m", "-1.36e-5 m",
                f"g_N1 = {g25:.3g} m at 2.5 s, {g5:.3g} m at 5 s", "within 20 %, changes < 10 % over [2.5, 5] s",
                _judge(ok)))

    # --- Sect. 6.3, Figs. 11/12: smooth Coulomb
    m5, m6 = r["m5"], r["m6"]
    t_inv = inversion_time(m5)
    add(Row("11", "Model 5: inverts directly on [0, 0.5] s", "within 0.5 s",
            f"gamma within 0.2 rad of pi/2 at {_fmt(t_inv, '.3f', 's')}", "t <= 0.55 s",
            _judge(t_inv is not None and t_inv <= 0.55)))
    ratio, rb = _ratio(m5), _ratio(m5, "beta")
    add(Row("11", "Model 5: damped oscillation of gamma and beta about pi/2", "damped",
            f"amplitude ratio [4, 5] s / [1, 2] s: gamma {ratio:.2f}, beta {rb:.2f}", "gamma < 0.5, beta < 0.7",
            _judge(ratio < 0.5 and rb < 0.7)))
    onset = onset_of_fast_oscillation(m5)
    add(Row("11", "Model 5: small high-frequency oscillations start at t ~ 1 s", "~1 s",
            f"onset of beta's > 4 Hz oscillation: {_since(onset)}", ONSET_CRITERION, _onset_verdict(onset, 1.0)))
    z5, zlow = _at(m5, "z_S", 5), float(window(m5, "z_S", 0, 0.5).min())
    add(Row("11", "Model 5: z_S drops slightly, then grows asymptotically to r + e", "r + e",
            f"min z_S on [0, 0.5] s {zlow * 1e3:.2f} mm; z_S(5 s) = {z5 * 1e3:.2f} mm", "drops, and z_S(5 s) > 47 mm",
            _judge(zlow < R_MINUS_E and z5 > 0.047)))
    fast, slow = _rate(m5, 0, 0.5), _rate(m5, 2, 5)
    add(Row("11", "Model 5: E_tot falls fast during the inversion, slowly after", "fast, then slow",
            f"{fast * 1e3:.1f} mW on [0, 0.5] s, {slow * 1e3:.2f} mW on [2, 5] s", "later rate < 0.2 x early rate",
            _judge(0 < slow < 0.2 * fast)))
    band = float(window(m5, "g_N1", 1, 5).max() - window(m5, "g_N1", 1, 5).min()) if window(m5, "g_N1", 1, 5).size \
        else math.nan
    add(Row("12", "Model 5: g_N1 oscillates aperiodically in a band of width 1e-9 m", "1e-9 m",
            f"width on [1, 5] s = {band:.2g} m", "width in [0.5e-9, 2e-9] m", _judge(0.5e-9 <= band <= 2e-9)))
    g25, g5, ok = _saturated_gap(m6, -7.5e-6)
    add(Row("12", "Model 6: g_N1 decreases from 0 and saturates at -7.5e-6 m", "-7.5e-6 m",
            f"g_N1 = {g25:.3g} m at 2.5 s, {g5:.3g} m at 5 s", "within 20 %, changes < 10 % over [2.5, 5] s",
            _judge(ok)))

    # --- Sect. 6.4, Fig. 13: ODE Model 1 (data/fig13_ode_inversion.nc)
    if fig13 is not None:
        late = window(fig13, "gamma", 4, 5)
        add(Row("13", "ODE Model 1: gamma rises from -pi/2 and oscillates asymptotically about pi/2", "pi/2",
                f"gamma on [4, 5] s in [{late.min():.3f}, {late.max():.3f}] rad, amplitude ratio {_ratio(fig13):.2f}",
                "mean within 0.05 rad of pi/2, ratio < 0.5",
                _judge(abs(float(late.mean()) - math.pi / 2) < 0.05 and _ratio(fig13) < 0.5)))
        add(Row("13", "ODE Model 1: z_S grows from r - e to r + e", "42.5 -> 47.5 mm",
                f"{_at(fig13, 'z_S', 0) * 1e3:.2f} -> {_at(fig13, 'z_S', 5) * 1e3:.2f} mm",
                "ends within 0.1 mm of r + e",
                _judge(abs(_at(fig13, "z_S", 5) - R_PLUS_E) < 1e-4)))
        e0, e05 = _at(fig13, "E_tot", 0), _at(fig13, "E_tot", 0.5)
        add(Row("13", "ODE Model 1: E_tot dissipates 'from 0.28 J to 0.36 J' in t < 0.5 s, slowly after",
                "0.28 -> 0.36 J (as printed: a rise)", f"{e0:.3f} -> {e05:.3f} J on [0, 0.5] s",
                "start and end within 0.01 J of the printed values (partly: the end only)",
                _judge(abs(e0 - 0.28) < 0.01 and abs(e05 - 0.36) < 0.01, partly=abs(e05 - 0.36) < 0.01)))

    # --- Sect. 6.5, Fig. 14 (5 s)
    m8, m10, ode2, m4v, m4l = r["m8"], r["m10"], r["ode2"], r["m4_variant"], r["m4_law"]
    a2, a2l = amplitude(m2, 1, 2), amplitude(m2, 4, 5)
    add(Row("14", "Model 2: periodic oscillation about pi/2 with slightly increasing amplitude", "slightly increasing",
            f"gamma amplitude {a2:.3f} rad on [1, 2] s, {a2l:.3f} rad on [4, 5] s ({(a2l / a2 - 1) * 100:+.1f} %)",
            "amplitude grows by 0-10 %", _judge(1.0 < a2l / a2 < 1.1, partly=abs(a2l / a2 - 1) < 0.02)))
    a8, a8l = amplitude(m8, 1, 2), amplitude(m8, 4, 5)
    same = float(np.max(np.abs(window(m8, "gamma", 0, 0.5) - window(m2, "gamma", 0, 0.5))))
    add(Row("14", "Model 8: like Model 2 during the transient; afterwards the amplitude increases significantly",
            "significant increase", f"max |gamma_8 - gamma_2| on [0, 0.5] s = {same:.2g} rad; amplitude {a8:.3f} -> "
            f"{a8l:.3f} rad ({(a8l / a8 - 1) * 100:+.1f} %; Model 2: {(a2l / a2 - 1) * 100:+.1f} %)",
            "alike on [0, 0.5] s (< 0.1 rad); grows > 5 % and more than Model 2's",
            _judge(same < 0.1 and a8l / a8 > 1.05 and a8l / a8 > a2l / a2)))
    for m4, name in ((m4l, "law as stated"), (m4v, "variant")):
        ratio = _ratio(m4)
        add(Row("14", f"Model 4 ({name}): after [0, 0.3] s a decaying oscillation; the disk ends inverted", "decaying",
                f"gamma amplitude ratio [4, 5] s / [1, 2] s = {ratio:.2f}, gamma(5 s) = {_at(m4, 'gamma', 5):.2f} rad",
                "ratio < 0.5", _judge(ratio < 0.5)))
    r6 = _ratio(m6)
    add(Row("14", "Model 6: qualitatively like Model 4", "alike", f"ratio {r6:.2f} (Model 4: law {_ratio(m4l):.2f}, "
            f"variant {_ratio(m4v):.2f})", "both ratios < 0.5", _judge(r6 < 0.5 and _ratio(m4v) < 0.5,
                                                                       partly=r6 < 0.5)))
    t6, t10 = inversion_time(m6), inversion_time(m10)
    d10 = float(np.max(np.abs(window(m10, "gamma", 0, 0.5) - window(m6, "gamma", 0, 0.5))))
    add(Row("14", "Model 10: the additional dissipation affects the inversion slightly", "slightly",
            f"gamma within 0.2 rad of pi/2 at {_fmt(t6, '.3f', 's')} (Model 6) / {_fmt(t10, '.3f', 's')} (Model 10); "
            f"max |gamma_10 - gamma_6| on [0, 0.5] s = {d10:.2g} rad", "times within 0.05 s, difference < 0.1 rad",
            _judge(t6 is not None and t10 is not None and abs(t6 - t10) < 0.05 and d10 < 0.1)))
    d1 = float(np.max(np.abs(window(m6, "gamma", 0, 1) - window(ode2, "gamma", 0, 1))))
    d5 = float(np.max(np.abs(window(m6, "gamma", 0, 5) - window(ode2, "gamma", 0, 5))))
    add(Row("14", "Model 6 vs ODE Model 2: gamma differs by about +-1e-3 rad", "+-1e-3 rad",
            f"max |difference| {d1:.3g} rad on [0, 1] s, {d5:.3g} rad on [0, 5] s", "<= 1.5e-3 rad on [0, 5] s",
            _judge(d5 <= 1.5e-3)))
    E = {k: _at(r[k], "E_tot", 5) for k in ("m2", "m6", "m8", "m10")}
    add(Row("14", "Pivoting and contour friction dissipate more (E_tot)", "Models 8, 10 below 2, 6",
            f"E_tot(5 s): Model 8 {E['m8']:.4f} < Model 2 {E['m2']:.4f} J; Model 10 {E['m10']:.4f} < Model 6 "
            f"{E['m6']:.4f} J", "both inequalities", _judge(E["m8"] < E["m2"] and E["m10"] < E["m6"])))

    # --- Sect. 6.5, Fig. 15 (25 s)
    for m4, name in ((m4l, "law as stated"), (m4v, "variant")):
        t_left, t_down = leave_time(m4), down_time(m4)
        grow = amplitude(m4, 9, 10) > amplitude(m4, 4, 5)
        add(Row("15", f"Model 4 ({name}): vibration about pi/2 grows after the inversion; the disk falls at t ~ 17 s",
                "~17 s", f"no longer inverted (|gamma - pi/2| > pi/2) {_since(t_left)}; z_S < 20 mm {_since(t_down)}; "
                f"amplitude [4, 5] s {amplitude(m4, 4, 5):.2f} -> [9, 10] s "
                f"{amplitude(m4, 9, 10):.2f} rad", "grows, and leaves within 17 +- 2 s",
                _judge(grow and t_left is not None and abs(t_left - 17) <= 2,
                       partly=grow and t_left is not None and abs(t_left - 17) <= 4)))
    t6, to = leave_time(m6), leave_time(ode2)
    add(Row("15", "Model 6 and ODE Model 2 behave alike: converge to pi/2, then fall", "alike, fall",
            f"no longer inverted {_since(t6)} (Model 6) / {_since(to)} (ODE Model 2)",
            "both leave within 25 s, 0.5 s apart", _judge(t6 is not None and to is not None and abs(t6 - to) < 0.5)))
    a4, a24 = amplitude(m10, 4, 5), amplitude(m10, 24, 25)
    add(Row("15", "Model 10: after t ~ 5 s a periodic oscillation of constant amplitude", "constant",
            f"gamma amplitude {a4:.3f} rad on [4, 5] s, {amplitude(m10, 14, 15):.3f} on [14, 15] s, {a24:.3f} on "
            f"[24, 25] s", "ratio [24, 25] / [4, 5] in [0.8, 1.25]",
            _judge(0.8 <= a24 / a4 <= 1.25, partly=leave_time(m10) is None)))
    t10 = leave_time(m10)
    stays = f"inverted for all {float(m10.time[-1]):.0f} s" if t10 is None else _since(t10)
    others = [t for t in (leave_time(m4v), t6, to) if t is not None]
    add(Row("15", "Model 10 stays inverted longer than Models 4, 6 and ODE Model 2", "longest",
            f"Model 10: {stays}; "
            f"others leave at {', '.join(_fmt(t, '.2f', 's') for t in others) or 'never'}",
            "Model 10 leaves last (or never)", _judge(bool(others) and (t10 is None or t10 > max(others)))))

    # --- Sect. 6.5 / 7: no lift-off, and Fig. 17
    lift = max(float(window(r[k], "g_N1", 0, 1).max()) for k in RUNS if k != "ode2")
    add(Row("14", "Time stepping: C1 does not detach from the support during the inversion", "g_N1 <= 0",
            f"max g_N1 on [0, 1] s over all Moreau runs = {lift:.2g} m", "< 1e-9 m", _judge(lift < 1e-9)))
    if fig17 is not None:
        t_half = first_time(fig17, fig17.gamma.values >= 0.5 * math.pi)
        add(Row("17", "ODE Model 1 at alpha_dot = -50 rad/s inverts within the stroboscopic sequence (Fig. 16's "
                      "experiment itself is not available to compare with)", "inverts",
                f"gamma reaches pi/2 at {_fmt(t_half, '.2f', 's')} of {float(fig17.time[-1]):.2f} s",
                "gamma reaches pi/2 within the run", _judge(t_half is not None)))
    # --- explained by the rolling analysis (studies/rolling.py): the event-driven model (h1) shows Model 1's
    # constant energy: after the last stick the disk rolls
    m1, h1 = r["m1"], r["h1"]
    slides = h1.time.values[h1["mode"].values > 0.5]
    t_stick = float(slides[-1]) if slides.size else 0.0
    e_h1, e_m1 = _at(h1, "E_tot", 5), _at(m1, "E_tot", 5)
    late_energy = window(h1, "E_tot", 0.5, 5)
    drift = float(np.ptp(late_energy)) if late_energy.size else math.nan
    add(Row("7", "Model 1: E_tot almost constant after 0.5 s (explained: after its last stick the disk rolls "
                 "without slip, and rolling conserves energy)", "~constant",
            f"event-driven model h1: slides until {t_stick:.3f} s, then rolls; E_tot(5 s) {e_h1:.5f} J (Model 1 "
            f"{e_m1:.5f} J); range of h1's E_tot on [0.5, 5] s {drift:.2g} J",
            "h1 rolls from before 0.5 s on, |E_h1 - E_M1| < 1e-3 J at 5 s, h1's range < 1e-9 J",
            _judge(t_stick < 0.5 and abs(e_h1 - e_m1) < 1e-3 and drift < 1e-9)))
    if rolling is not None:
        kind = config_of(rolling).get("motion", "")
        rho, period = float(rolling["rotation_number"]), float(rolling["period"][0])
        returns = np.diff(rolling["return_time"].values)
        add(Row("14", "Models 1/2: a periodic oscillation about pi/2 after the inversion (explained: the rolling "
                      "motion's returns to gamma = pi/2 lie on a closed curve, an invariant torus)", "periodic",
                f"{kind}: rotation number {rho:.6f} of the returns, return time {returns.mean():.4f} s "
                f"(+-{returns.std():.1e} s); an elliptic orbit at its centre, T = {period:.4f} s",
                "periodic: every return at one point; quasi-periodic (partly): on a closed curve",
                _judge(kind == "periodic orbit", partly=kind == "torus")))
    return rows


# ----------------------------------------------------------------------------- output

HEADER = "| # | Fig. | statement of Sect. 6 | paper | package | criterion | verdict |\n|---|---|---|---|---|---|---|"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def markdown(rows: list[Row]) -> str:
    """The table as markdown (one line per row, numbered)."""
    lines = [HEADER]
    for k, row in enumerate(rows, 1):
        cells = (row.figure, row.statement, row.paper, row.package, row.criterion)
        lines.append(f"| {k} | " + " | ".join(_cell(c) for c in cells) + f" | **{row.verdict}** |")
    return "\n".join(lines)


SHORT_HEADER = "| # | Fig. | statement | paper | package | verdict |\n|---|---|---|---|---|---|"


def markdown_short(rows: list[Row]) -> str:
    """The rows not reproduced in full (partly, not reproduced), without the criterion column,
    numbered as in the full table."""
    lines = [SHORT_HEADER]
    for k, row in enumerate(rows, 1):
        if row.verdict != "reproduced":
            cells = (row.figure, row.statement, row.paper, row.package)
            lines.append(f"| {k} | " + " | ".join(_cell(c) for c in cells) + f" | **{row.verdict}** |")
    return "\n".join(lines)


def summary(rows: list[Row]) -> str:
    counts = {v: sum(r.verdict == v for r in rows) for v in VERDICTS}
    return ", ".join(f"{counts[v]} {v}" for v in VERDICTS)


def scorecard(rows: list[Row]):
    colors = {"reproduced": "tab:green", "partly": "gold", "not reproduced": "tab:red"}
    fig, ax = plt.subplots(figsize=(11, 0.24 * len(rows) + 1.2), constrained_layout=True)
    for k, row in enumerate(rows):
        ax.barh(k, 1, color=colors[row.verdict])
        ax.text(0.01, k, f"{k + 1}. Fig. {row.figure}: {row.statement}"[:120], va="center", fontsize=7)
    ax.set_yticks([])
    ax.set_xticks([])
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_title("Sect. 6 statements: " + summary(rows) + " (green / yellow / red)", fontsize=9)
    return fig


def update_readmes(root: Path | None = None) -> str:
    """Recompute the table from data/ and write it into the marked blocks of studies/README.md and docs/paper.md
    (what tests/test_paper_table.py checks). Returns the summary line."""
    root = Path(root) if root else Path(__file__).resolve().parents[1]
    data = root / "data"
    with np.errstate(all="ignore"):
        rows = table_rows(load_runs(data / "sect6"), td.load(data / "fig13_ode_inversion.nc"),
                          td.load(data / "fig17_stroboscope.nc"), td.load(data / "rolling" / "rolling_orbit.nc"))
    blocks = {root / "studies" / "README.md": ("sect6-table", markdown(rows) + "\n\n" + summary(rows)),
              root / "docs" / "paper.md": ("sect6-summary", summary(rows) + "\n\n" + markdown_short(rows))}
    for path, (name, body) in blocks.items():
        text = path.read_text()
        begin, end = f"<!-- {name}:begin -->\n", f"\n<!-- {name}:end -->"
        head, rest = text.split(begin, 1)
        path.write_text(head + begin + body + end + rest.split(end, 1)[1])
    return summary(rows)


def _find(out: Path, name: str, data_folder: str = ""):
    """A dataset of another study: from the output folder if that study ran there, else from data/
    (its ``data_folder`` there)."""
    for folder in (out, Path(__file__).resolve().parents[1] / "data" / data_folder):
        if (folder / name).is_file():
            print(f"reading {folder / name}")
            return td.load(folder / name)
    return None


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    runs = simulate_runs(out, quick)
    if quick:  # 0.3-s runs exercise the models, but the statements need their windows (1 to 25 s)
        runs = load_runs(Path(__file__).resolve().parents[1] / "data" / "sect6")
        print("quick: the runs above are 0.3 s long; the table below is computed from the stored full runs "
              "(data/sect6)")
    fig13, fig17 = (_find(out, name) for name in ("fig13_ode_inversion.nc", "fig17_stroboscope.nc"))
    rolling = _find(out, "rolling_orbit.nc", "rolling")
    rows = table_rows(runs, fig13, fig17, rolling)
    text = markdown(rows)
    (out / "sect6_table.md").write_text(f"{text}\n\n{summary(rows)}\n\nNot reproduced in full:\n\n"
                                        f"{markdown_short(rows)}\n")
    save(scorecard(rows), out / "sect6_scorecard.png")
    print(text)
    print(summary(rows))
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

"""Shared plumbing of the Moreau study scripts: output folder, run-and-store, figure saving, the
Coulomb-Contensou variant, and the measures that the studies print and the Sect. 6 table uses."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from tippedisk_analysis import Friction, Setup, results, simulate
from tippedisk_analysis.plotting import style
from tippedisk_analysis.solvers.moreau.models import MODELS, QUATERNION

# ----------------------------------------------------------------------------- the Coulomb-Contensou variant
SPIN_0 = 40.0  # alpha_dot of Table 3 [rad/s]
VARIANT_CONTACT_RADIUS = 3.0 * math.pi * Friction().eps / (8.0 * SPIN_0)
"""eps_i = 3 pi eps / (8 omega) = 2.945 mm: the radius at which the Coulomb-Contensou law near pure pivoting,
|lambda_T| = mu lambda_N (3 pi / 8) |gamma_T| / (eps_i omega), has the slope of the paper's regularised law
(2.29) with eps = 0.1 m/s at the Table 3 spin of 40 rad/s. The paper motivates (2.29) by Coulomb-Contensou
friction for |gamma_tau| >> |gamma_T| (Sect. 2.2); this is that equivalence, not a fit
(docs/contensou_investigation.md, Sect. 5)."""

CONTENSOU_VARIANT = {"setup": Setup(friction=Friction(contact_radius=VARIANT_CONTACT_RADIUS)),
                     "contensou_torque_share": 0.0}
"""Options of the diagnostic Coulomb-Contensou variant that reproduces Figs. 9, 10, 15: the ball couples
spin and sliding (contact radius 2.945 mm), but the pivoting torque is not applied to the disk. Not a
consistent friction law (the ball's pivoting impulse does no work); the law as stated, (2.24)-(2.27),
gives no damped inversion for any contact radius."""

VARIANT_LABEL = "variant: no pivoting torque, eps_i = 2.9 mm"
LAW_LABEL = "law (2.24)-(2.27), eps_i = 1 mm"


def prepare(output_dir: str) -> Path:
    """The output folder, created if missing."""
    path = Path(output_dir)
    path.mkdir(parents=True, exist_ok=True)
    return path


def file_tag(model: str, tag: str = "", **options) -> str:
    """The file-name tag of a run: quaternion Moreau runs say whether they were normalised."""
    parts = [tag] if tag else []
    name = {f"m{m.number}": m for m in MODELS.values()}.get(model) or MODELS.get(model)
    if name is not None and name.parameterization == QUATERNION:
        parts.append("normalized" if options.get("normalize_quaternion", True) else "unnormalized")
    return "_".join(parts)


def run(out: Path, model: str, t_end: float, tag: str = "", **options):
    """Simulate ``model`` (Table 3 initial state, Sect. 6 parameters); store
    <out>/<model>_<t_end>s[_tag][_normalized|_unnormalized].nc."""
    ds = simulate(model, t_end, **options)
    suffix = file_tag(model, tag, **options)
    results.save(ds, out / f"{ds.attrs['model']}_{t_end:g}s{'_' + suffix if suffix else ''}.nc")
    print(f"{ds.attrs['paper_model']:>12} {ds.attrs['model']:<36} {ds.attrs['status']}: {ds.attrs['message']}"
          + (f" (wall {ds.attrs['wall_time']:.2f} s)" if "wall_time" in ds.attrs else ""))
    return ds


def save(fig, path: Path) -> None:
    """``fig`` to ``path`` at 120 dpi, closed; a PNG records its smallest text and width as plot_dataset's do."""
    metadata = {"Description": style.describe(fig)} if Path(path).suffix == ".png" else None
    fig.savefig(path, dpi=120, metadata=metadata)
    plt.close(fig)
    print(f"figure: {path}")


def finish(fig, axes, path: Path, fontsize: float | None = 8) -> None:
    """A legend (``fontsize`` [pt]; None: the rc style's) and a light grid on each of ``axes``, then :func:`save`."""
    for a in axes:
        a.legend(fontsize=fontsize)
        a.grid(alpha=0.3)
    save(fig, path)


# ----------------------------------------------------------------------------- measures (Sect. 6 statements)


def window(ds, name: str, t0: float, t1: float) -> np.ndarray:
    t = ds.time.values
    return ds[name].values[(t >= t0 - 1e-9) & (t <= t1 + 1e-9)]


def window_mean(ds, name: str, t0: float, t1: float) -> float:
    """Mean of ``name`` over [t0, t1] s (clipped to the run: quick runs are shorter)."""
    t0 = min(t0, 0.2 * float(ds.time[-1]))
    return float(np.mean(window(ds, name, t0, t1)))


def amplitude(ds, t0: float, t1: float, name: str = "gamma") -> float:
    """Half the range of ``name`` on [t0, t1] s: the oscillation amplitude of Sect. 6's "damped" statements."""
    values = window(ds, name, t0, t1)
    return 0.5 * float(values.max() - values.min()) if values.size else math.nan


def first_time(ds, condition: np.ndarray, after: float = 0.0) -> float | None:
    """First stored time after ``after`` at which ``condition`` holds, or None."""
    t = ds.time.values
    hit = condition & (t > after)
    return float(t[np.argmax(hit)]) if hit.any() else None


def fmt_time(t: float | None) -> str:
    """A time for printing: seconds with 3 decimals, or "never"."""
    return "never" if t is None else f"{t:.3f}"


def inversion_time(ds, tolerance: float = 0.2) -> float | None:
    """First time gamma comes within ``tolerance`` rad of pi/2 (Sect. 6: "gamma rises to pi/2")."""
    return first_time(ds, np.abs(ds.gamma.values - 0.5 * math.pi) < tolerance)


def leave_time(ds, after: float = 1.0) -> float | None:
    """First time after ``after`` s at which the disk is no longer inverted: |gamma - pi/2| > pi/2, i.e. S
    below the level of G (the paper's "falls down" in the gamma graphs of Fig. 15)."""
    return first_time(ds, np.abs(ds.gamma.values - 0.5 * math.pi) > 0.5 * math.pi, after)


def down_time(ds, height: float = 0.02) -> float | None:
    """First time S is below ``height`` [m] (20 mm: the disk tilted below ~25 deg)."""
    return first_time(ds, ds.z_S.values < height)


def dominant_frequency(ds, name: str, t0: float, t1: float) -> float:
    """Frequency [Hz] of the largest Fourier peak of ``name`` on [t0, t1] s after removing a cubic trend."""
    t = ds.time.values
    sel = (t >= t0) & (t <= t1)
    x, y = t[sel] - t0, ds[name].values[sel]
    y = y - np.polyval(np.polyfit(x, y, 3), x)
    power = np.abs(np.fft.rfft(y)) ** 2
    freq = np.fft.rfftfreq(y.size, float(np.median(np.diff(x))))
    return float(freq[1 + np.argmax(power[1:])])


def onset_of_fast_oscillation(ds, name: str = "beta", threshold: float = 4.0, start: float = 0.5,
                              length: float = 1.0, step: float = 0.25) -> float | None:
    """Start of the first ``length``-s window (from ``start`` s in ``step``-s steps) in which ``name`` oscillates
    fastest at more than ``threshold`` Hz: the "oscillations with high frequency start at t ~ ..." of
    Sects. 6.2/6.3 (the nutation at the spin frequency, ~5 Hz, replacing the ~2 Hz swing of the inversion)."""
    t_end = float(ds.time[-1])
    t0 = start
    while t0 + length <= t_end + 1e-9:
        if dominant_frequency(ds, name, t0, t0 + length) > threshold:
            return t0
        t0 += step
    return None


# ----------------------------------------------------------------------------- Euler/quaternion pairs


def model_pair(out: Path, euler: str, quaternion: str, figure_numbers: tuple[int, int], t_end: float = 5.0,
               angle_styles: str = "fig07", gap_reference: float | None = None, options: dict | None = None,
               tag: str = "", figure_suffix: str = "", title: str | None = None):
    """Run an Euler/quaternion pair of Moreau models for t_end (the quaternion one normalised, as the paper
    prescribes, and unnormalised for the drift panel); draw both in the paper's simulation figure and the
    gaps of all three. Returns the three datasets (Euler, quaternion, quaternion unnormalised)."""
    from tippedisk_analysis import plotting

    options = options or {}
    e = run(out, euler, t_end, tag=tag, **options)
    q = run(out, quaternion, t_end, tag=tag, **options)
    qu = run(out, quaternion, t_end, tag=tag, normalize_quaternion=False, **options)
    ne, nq = e.attrs["paper_model"], q.attrs["paper_model"]
    suffix = f"_{figure_suffix}" if figure_suffix else ""
    save(plotting.simulation_figure(e, companion=q, angle_styles=angle_styles, title=title),
         out / f"fig{figure_numbers[0]:02d}_model{ne.split()[-1]}{suffix}.png")
    panels = {f"{ne} (E)": e, f"{nq} (Q, normalised: the paper's scheme)": q,
              f"{nq} (Q, unnormalised: drift study)": qu}
    references = ({f"{nq} (Q, normalised: the paper's scheme)": (gap_reference, f"paper: {gap_reference:.3g} m")}
                  if gap_reference is not None else None)
    fig = plotting.gap_figure(panels, references=references)
    if title:
        fig.suptitle(title, fontsize=10)
    save(fig, out / f"fig{figure_numbers[1]:02d}_gap{suffix}.png")
    return e, q, qu

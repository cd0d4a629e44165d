"""Shared plumbing of the Moreau study scripts: output folder, run-and-store, figure saving."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from tippedisk_analysis import results, simulate


def prepare(output_dir: str) -> Path:
    """The output folder, created if missing."""
    path = Path(output_dir)
    path.mkdir(parents=True, exist_ok=True)
    return path


def run(out: Path, model: str, t_end: float, tag: str = "", **options):
    """Simulate ``model`` (Table 3 initial state, Sect. 6 parameters); store <out>/<model>_<t_end>s[_tag].nc."""
    ds = simulate(model, t_end, **options)
    results.save(ds, out / f"{ds.attrs['model']}_{t_end:g}s{'_' + tag if tag else ''}.nc")
    print(f"{ds.attrs['paper_model']:>12} {ds.attrs['model']:<36} {ds.attrs['status']}: {ds.attrs['message']}"
          + (f" (wall {ds.attrs['wall_time']:.2f} s)" if "wall_time" in ds.attrs else ""))
    return ds


def save(fig, path: Path) -> None:
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print(f"figure: {path}")


def window_mean(ds, name: str, t0: float, t1: float) -> float:
    """Mean of ``name`` over [t0, t1] s (clipped to the run: quick runs are shorter)."""
    t0 = min(t0, 0.2 * float(ds.time[-1]))
    sel = (ds.time >= t0) & (ds.time <= t1)
    return float(np.mean(ds[name].values[sel.values]))


def model_pair(out: Path, euler: str, quaternion: str, figure_numbers: tuple[int, int], t_end: float = 5.0):
    """Run an Euler/quaternion pair of Moreau models for t_end (the quaternion one with and without
    normalisation), draw the first as the paper's simulation figure and the gaps of all three.
    Returns the three datasets (Euler, quaternion, quaternion normalised)."""
    from tippedisk_analysis import plotting

    e, q = run(out, euler, t_end), run(out, quaternion, t_end)
    qn = run(out, quaternion, t_end, normalize_quaternion=True, tag="normalized")
    ne, nq = e.attrs["paper_model"], q.attrs["paper_model"]
    save(plotting.simulation_figure(e), out / f"fig{figure_numbers[0]:02d}_model{ne.split()[-1]}.png")
    save(plotting.gap_figure({f"{ne} (E)": e, f"{nq} (Q)": q, f"{nq} (Q, normalised)": qn}),
         out / f"fig{figure_numbers[1]:02d}_gap.png")
    return e, q, qn


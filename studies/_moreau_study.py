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
    sel = (ds.time >= t0) & (ds.time <= t1)
    return float(np.mean(ds[name].values[sel.values]))

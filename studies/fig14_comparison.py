"""Fig. 14: quaternion models with different dissipation (Models 2, 4, 6, 8, 10) and ODE Model 2, 5 s.

Paper: Model 2 (red) oscillates about pi/2 with slightly growing amplitude, Model 8 (black, *) likewise
with a significantly growing one; Models 4, 6 (blue), 10 (black, o) invert and settle; Model 6 and ODE
Model 2 (orange, dashed) differ by about +-1e-3 rad in gamma; pivoting and contour friction dissipate
more. Quaternion models are normalised after each step (Sect. 3.2). Model 4 is drawn twice: the
Coulomb-Contensou variant of Figs. 9/10 (green) and the law as stated (green, thin dotted).

    tippedisk study fig14_comparison [--output-dir DIR] [--quick]
"""

import sys

import numpy as np
from tippedisk_studies._common import CONTENSOU_VARIANT, amplitude, prepare, run, save

from tippedisk_analysis import plotting
from tippedisk_analysis.plotting.simulation import PAPER_MODEL_STYLES

VARIANT = "Model 4 (variant, Figs. 9/10)"
LAW = "Model 4, law as stated (1 mm)"


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    t_end = 0.3 if quick else 5.0
    runs = {"Model 2": run(out, "m2", t_end), VARIANT: run(out, "m4", t_end, tag="variant", **CONTENSOU_VARIANT),
            LAW: run(out, "m4", t_end, tag="law"), "Model 6": run(out, "m6", t_end), "Model 8": run(out, "m8", t_end),
            "Model 10": run(out, "m10", t_end), "ODE Model 2": run(out, "ode-quaternion", t_end, dt_output=1e-3)}
    styles = dict(PAPER_MODEL_STYLES["fig14"])
    styles[VARIANT] = styles.pop("Model 4")
    styles[LAW] = {"color": "tab:green", "ls": ":", "lw": 0.7}
    save(plotting.comparison_figure(runs, styles=styles), out / "fig14_comparison.png")
    d = runs["Model 6"].gamma.values - runs["ODE Model 2"].gamma.values
    print(f"gamma(Model 6) - gamma(ODE Model 2): max |.| = {np.max(np.abs(d)):.3g} rad on [0, {t_end:g}] s "
          "(paper ~1e-3 rad)")
    for label, ds in runs.items():
        amps = f", gamma amplitude {amplitude(ds, 1, 2):.3f} -> {amplitude(ds, 4, 5):.3f} rad" if not quick else ""
        print(f"{label:>30}: E_tot(t_end) = {float(ds.E_tot[-1]):.5f} J, gamma(t_end) = {float(ds.gamma[-1]):.3f} rad"
              + amps)
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

"""Fig. 15: long-term behaviour on [0, 25] s: Models 4, 6, 10 and ODE Model 2.

Paper: Model 4 (green) oscillates with growing amplitude about pi/2 and falls near t = 17 s; Model 6
and ODE Model 2 behave alike, converge to pi/2 and then fall; Model 10 (blue) stays inverted longest,
with an oscillation of constant amplitude after ~5 s. Quaternion models are normalised after each step
(Sect. 3.2). Model 4 is drawn twice: the Coulomb-Contensou variant of Figs. 9/10 and the law as stated.
Marked: the first time after 1 s that the disk is no longer inverted (|gamma - pi/2| > pi/2, S below G).

    tippedisk study fig15_long_term [--output-dir DIR] [--quick]
"""

import sys

from tippedisk_studies._common import CONTENSOU_VARIANT, amplitude, down_time, leave_time, prepare, run, save

from tippedisk_analysis import plotting
from tippedisk_analysis.plotting.simulation import PAPER_MODEL_STYLES

VARIANT = "Model 4 (variant, Figs. 9/10)"
LAW = "Model 4, law as stated (1 mm)"


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    t_end = 0.3 if quick else 25.0
    runs = {VARIANT: run(out, "m4", t_end, tag="variant", **CONTENSOU_VARIANT), LAW: run(out, "m4", t_end, tag="law"),
            "Model 6": run(out, "m6", t_end), "Model 10": run(out, "m10", t_end),
            "ODE Model 2": run(out, "ode-quaternion", t_end, dt_output=1e-3)}
    styles = dict(PAPER_MODEL_STYLES["fig15"])
    styles[VARIANT] = styles.pop("Model 4")
    styles[LAW] = {"color": "tab:green", "ls": ":", "lw": 0.7, "alpha": 0.5, "zorder": 1}
    events = {label: (t, "not inverted") for label, ds in runs.items() if (t := leave_time(ds)) is not None}
    save(plotting.comparison_figure(runs, styles=styles, events=events, zoom=0.8, zoom_exclude=(LAW,),
                                     wrap=True, marker_spacing=1.0),
         out / "fig15_long_term.png")
    for label, ds in runs.items():
        left, down = leave_time(ds), down_time(ds)
        print(f"{label:>30}: " + (f"no longer inverted (|gamma - pi/2| > pi/2) from t = {left:.2f} s" if left else
                                  f"inverted for all {t_end:g} s")
              + (f", z_S < 20 mm from t = {down:.2f} s" if down else "")
              + (f"; gamma amplitude on [4, 5] s {amplitude(ds, 4, 5):.3f} rad, on [24, 25] s "
                 f"{amplitude(ds, 24, 25):.3f} rad" if not quick else ""))
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

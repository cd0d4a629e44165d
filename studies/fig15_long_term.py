"""Fig. 15: long-term behaviour on [0, 25] s: Models 4, 6, 10 and ODE Model 2.

Paper: Model 4 oscillates with growing amplitude about pi/2 and falls near t = 17 s; Model 6 and
ODE Model 2 behave alike and decay; Model 10 stays inverted longer (constant-amplitude oscillation).
"""

import numpy as np
from _moreau_study import output_dir, run, save

from tippedisk_analysis import plotting

out = output_dir(__doc__)
runs = {f"Model {m[1:]}": run(out, m, 25.0) for m in ("m4", "m6", "m10")}
runs["ODE Model 2"] = run(out, "ode-quaternion", 25.0, dt_output=1e-3)
save(plotting.comparison_figure(runs), out / "fig15_long_term.png")
for label, ds in runs.items():
    fallen = ds.time.values[np.abs(ds.gamma.values - np.pi / 2) > 1.0]
    after = fallen[fallen > 1.0]
    print(f"{label:>12}: gamma leaves pi/2 +- 1 rad at t = {after[0]:.2f} s" if after.size else
          f"{label:>12}: stays within pi/2 +- 1 rad after 1 s; gamma(end) = {float(ds.gamma[-1]):.3f} rad")

"""Figs. 9/10: Coulomb-Contensou friction, Models 3 (Euler) and 4 (quaternions), 5 s.

Paper: inversion on [0, 0.5] s (gamma rises to pi/2), damped oscillation, z_S -> r + e;
quaternion gap drift saturating near -1.36e-5 m.

    tippedisk study fig09_10_coulomb_contensou [--output-dir DIR] [--quick]
"""

import sys

import numpy as np
from tippedisk_studies._common import model_pair, prepare


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    m3, m4, m4n = model_pair(out, "m3", "m4", (9, 10), t_end=0.3 if quick else 5.0)
    t_inv = float(m3.time[np.argmax(m3.gamma.values > np.pi / 2 - 0.2)])
    print(f"Model 3: gamma first within 0.2 rad of pi/2 at t = {t_inv:.3f} s (paper: within 0.5 s); "
          f"z_S(5 s) = {float(m3.z_S[-1]):.5f} m (r + e = 0.0475 m)")
    print(f"Model 4: g_N1 min = {float(m4.g_N1.min()):.3g} m, g_N1(5 s) = {float(m4.g_N1[-1]):.3g} m "
          "(paper: saturates near -1.36e-5 m)")
    print(f"Model 4 with quaternion normalisation: g_N1 min = {float(m4n.g_N1.min()):.3g} m, g_N1(5 s) = {float(m4n.g_N1[-1]):.3g} m")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

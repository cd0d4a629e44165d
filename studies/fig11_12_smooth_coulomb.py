"""Figs. 11/12: smooth Coulomb friction (2.29), Models 5 (Euler) and 6 (quaternions), 5 s.

Paper: direct inversion on [0, 0.5] s, damped oscillation about gamma = pi/2, z_S -> r + e;
quaternion gap drift near -7.5e-6 m.

    tippedisk study fig11_12_smooth_coulomb [--output-dir DIR] [--quick]
"""

import sys

import numpy as np
from tippedisk_studies._common import model_pair, prepare


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    m5, m6, m6n = model_pair(out, "m5", "m6", (11, 12), t_end=0.3 if quick else 5.0)
    t_inv = float(m5.time[np.argmax(m5.gamma.values > np.pi / 2 - 0.2)])
    print(f"Model 5: gamma first within 0.2 rad of pi/2 at t = {t_inv:.3f} s; z_S(5 s) = {float(m5.z_S[-1]):.5f} m")
    print(f"Model 6: g_N1 min = {float(m6.g_N1.min()):.3g} m, g_N1(5 s) = {float(m6.g_N1[-1]):.3g} m "
          "(paper: near -7.5e-6 m)")
    print(f"Model 6 with quaternion normalisation: g_N1 min = {float(m6n.g_N1.min()):.3g} m, g_N1(5 s) = {float(m6n.g_N1[-1]):.3g} m")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

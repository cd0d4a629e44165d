"""Figs. 11/12: smooth Coulomb friction (2.29), Models 5 (Euler) and 6 (quaternions), 5 s.

Paper: direct inversion on [0, 0.5] s, damped oscillation about gamma = pi/2, z_S -> r + e;
quaternion gap drift saturating near -7.5e-6 m. Fig. 11 shows Model 5 with Model 6 (markers) in the
paper's Fig. 11 styles (gamma blue dotted, beta red dashed).

    tippedisk study fig11_12_smooth_coulomb [--output-dir DIR] [--quick]
"""

import sys

from tippedisk_studies._common import amplitude, fmt_time, inversion_time, model_pair, prepare


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    t_end = 0.3 if quick else 5.0
    m5, m6, m6u = model_pair(out, "m5", "m6", (11, 12), t_end=t_end, angle_styles="fig11", gap_reference=-7.5e-6)
    print(f"Model 5: gamma first within 0.2 rad of pi/2 at t = {fmt_time(inversion_time(m5))} s; "
          f"z_S(t_end) = {float(m5.z_S[-1]) * 1e3:.2f} mm (r + e = 47.5 mm)")
    if not quick:
        print(f"Model 5: gamma amplitude {amplitude(m5, 1, 2):.3f} rad on [1, 2] s -> {amplitude(m5, 4, 5):.3f} rad "
              "on [4, 5] s")
    print(f"Model 6: g_N1(t_end) = {float(m6.g_N1[-1]):.3g} m normalised (paper: near -7.5e-6 m), "
          f"{float(m6u.g_N1[-1]):.3g} m unnormalised")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

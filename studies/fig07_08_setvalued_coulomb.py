"""Figs. 7/8: set-valued Coulomb friction, Models 1 (Euler) and 2 (quaternions), Table 3 start, 5 s.

Paper: z_S oscillates aperiodically about 0.044 m on [1, 5] s (Model 1) instead of reaching r + e;
the Euler gap g_N1 chatters between 0 and -2e-9 m; the quaternion gap drifts down monotonically.

    tippedisk study fig07_08_setvalued_coulomb [--output-dir DIR] [--quick]
"""

import sys

from tippedisk_studies._common import model_pair, prepare, window_mean


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    m1, m2, m2n = model_pair(out, "m1", "m2", (7, 8), t_end=0.3 if quick else 5.0)
    print(f"Model 1: mean z_S on [1, 5] s = {window_mean(m1, 'z_S', 1, 5):.5f} m (paper ~0.044 m); "
          f"g_N1 in [{float(m1.g_N1.min()):.3g}, {float(m1.g_N1.max()):.3g}] m (paper [-2e-9, 0])")
    print(f"Model 2: g_N1(5 s) = {float(m2.g_N1[-1]):.3g} m (drift), gamma(5 s) = {float(m2.gamma[-1]):.3f} rad")
    print(f"Model 2 with quaternion normalisation: g_N1 min = {float(m2n.g_N1.min()):.3g} m, g_N1(5 s) = {float(m2n.g_N1[-1]):.3g} m")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

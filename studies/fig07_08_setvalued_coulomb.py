"""Figs. 7/8: set-valued Coulomb friction, Models 1 (Euler) and 2 (quaternions), Table 3 start, 5 s.

Paper: z_S oscillates aperiodically about 0.044 m on [1, 5] s (Model 1) instead of reaching r + e;
the Euler gap g_N1 chatters between 0 and -2e-9 m; the quaternion gap drifts down monotonically.
Fig. 7 shows Model 1 with Model 2 (markers); Fig. 8 the gaps (Model 2 normalised as the paper
prescribes, and unnormalised as a drift study).

    tippedisk study fig07_08_setvalued_coulomb [--output-dir DIR] [--quick]
"""

import sys

from tippedisk_studies._common import amplitude, model_pair, prepare, window_mean


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    t_end = 0.3 if quick else 5.0
    m1, m2, m2u = model_pair(out, "m1", "m2", (7, 8), t_end=t_end)
    late = (1.0, t_end) if not quick else (0.1, t_end)
    print(f"Model 1: mean z_S on [1, 5] s = {window_mean(m1, 'z_S', 1, 5):.5f} m (paper ~0.044 m); "
          f"g_N1 in [{float(m1.g_N1.min()):.3g}, {float(m1.g_N1.max()):.3g}] m (paper [-2e-9, 0])")
    print(f"Model 1: gamma amplitude on [{late[0]:g}, {late[1]:g}] s = {amplitude(m1, *late):.3f} rad, "
          f"beta amplitude = {amplitude(m1, *late, name='beta'):.3f} rad")
    print(f"Model 2: mean z_S on [1, 5] s = {window_mean(m2, 'z_S', 1, 5):.5f} m; g_N1(t_end) = "
          f"{float(m2.g_N1[-1]):.3g} m (normalised; drift, the paper applies no gap correction)")
    print(f"Model 2 unnormalised: g_N1(t_end) = {float(m2u.g_N1[-1]):.3g} m, |p| - 1 = "
          f"{float(m2u.quaternion_norm_error[-1]):.2g}")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

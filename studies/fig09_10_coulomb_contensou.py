"""Figs. 9/10: Coulomb-Contensou friction, Models 3 (Euler) and 4 (quaternions), 5 s: the law as stated and
the diagnostic variant that reproduces the paper's figures.

Paper: inversion on [0, 0.5] s (gamma rises to pi/2), damped oscillation, z_S -> r + e; quaternion gap
drift saturating near -1.36e-5 m. The law (2.24)-(2.27) gives none of this for any contact radius
(docs/contensou_investigation.md); at the default 1 mm gamma keeps swinging by +-1.4 rad. The variant
(contensou_torque_share = 0, contact radius 3 pi eps / (8 Omega) = 2.9 mm) keeps the coupling of spin
and sliding in the friction ball but applies no pivoting torque: not a consistent friction law, but
its curves match Figs. 9/10. Both are drawn: fig09_model3.png / fig10_gap.png (variant, the paper's
figures) and fig09_model3_law.png / fig10_gap_law.png (the law as stated).

    tippedisk study fig09_10_coulomb_contensou [--output-dir DIR] [--quick]
"""

import sys

from tippedisk_studies._common import (CONTENSOU_VARIANT, LAW_LABEL, VARIANT_LABEL, amplitude, fmt_time,
                                       inversion_time, model_pair, prepare)


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    t_end = 0.3 if quick else 5.0
    for tag, suffix, options, label in (("variant", "", CONTENSOU_VARIANT, VARIANT_LABEL),
                                        ("law", "law", {}, LAW_LABEL)):
        m3, m4, m4u = model_pair(out, "m3", "m4", (9, 10), t_end=t_end, options=options, tag=tag, figure_suffix=suffix,
                                 gap_reference=-1.36e-5, title=f"Models 3/4, Coulomb-Contensou, {label}")
        print(f"Models 3/4, {label}:")
        print(f"  Model 3: gamma first within 0.2 rad of pi/2 at t = {fmt_time(inversion_time(m3))} s "
              "(paper: within 0.5 s); "
              f"z_S(t_end) = {float(m3.z_S[-1]) * 1e3:.2f} mm (r + e = 47.5 mm)")
        if not quick:
            print(f"  Model 3: gamma amplitude {amplitude(m3, 1, 2):.3f} rad on [1, 2] s -> {amplitude(m3, 4, 5):.3f} "
                  f"rad on [4, 5] s (Fig. 9: damped, ratio < 0.5: {amplitude(m3, 4, 5) / amplitude(m3, 1, 2):.2f})")
        print(f"  Model 4: g_N1(t_end) = {float(m4.g_N1[-1]):.3g} m normalised (paper: saturates near -1.36e-5 m), "
              f"{float(m4u.g_N1[-1]):.3g} m unnormalised")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

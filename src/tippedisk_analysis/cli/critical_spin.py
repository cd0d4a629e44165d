"""``tippedisk critical-spin``: the critical spin in closed form, the initial spin (C5) gives from it, with
--simulate the full model's threshold, and with --top (C7), which counts friction's work, against the full model's
threshold for reaching the top (docs/inversion.md)."""

from __future__ import annotations

import json
import math

from .common import add_disk, disk_from_args, finite_float
from .registry import command

TOP = 0.99  # (z_S - r) / e: the level (C7) is compared at


def _arguments(p) -> None:
    p.add_argument("--gamma0", type=finite_float,
                   help="gamma(0) of the Table 3 start [rad], the angle itself, in [-pi, pi] (default -pi/2 + 0.1 = "
                        "-1.4708: S 0.1 rad from straight below G; other commands' --dgamma0 is that 0.1)")
    p.add_argument("--mu", type=finite_float, help="friction coefficient [-] (0.3; omega_c does not depend on it)")
    p.add_argument("--eps", type=finite_float,
                   help="smoothing of (2.29) [m/s] (0.1; the prediction does not depend on it; with --simulate: "
                        "the full model's eps, horizon 150 s x max(1, 0.1/eps))")
    p.add_argument("--simulate", action="store_true",
                   help="also find the full model's threshold by bisection (ODE Model 1: seconds to a minute at eps "
                        "0.1, longer at small eps), how high S gets at the predicted spin, and whether the slow "
                        "flow holds at the threshold (eps 0.01)")
    p.add_argument("--top", action="store_true",
                   help="also the initial spin that reaches the top with friction's work counted (C7, the slow flow "
                        "at eps 0.01: seconds) against the full model's threshold for r + 0.99 e (bisection at the "
                        "full model's eps)")
    p.add_argument("--json", action="store_true",
                   help='print one JSON object: {"omega_critical": ..., "initial_spin_threshold": ..., ...} in rad/s')
    add_disk(p)


@command("critical-spin", "the critical spin omega_c in closed form and the initial spin a start needs to invert",
         _arguments)
def critical_spin(args) -> int:
    import dataclasses

    from ..analysis import critical_spin as cs
    from ..analysis import inversion, inversion_energy
    from ..parameters import Friction, InitialState, Setup

    friction = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    setup = Setup(disk=disk_from_args(args), friction=dataclasses.replace(Friction(), **friction))
    gamma0 = InitialState().gamma if args.gamma0 is None else args.gamma0
    inversion.check_start(setup, gamma0)  # before any work
    found = cs.omega_critical(setup.disk, setup.gravity, setup.friction.mu)
    out = {"omega_critical": None, "initial_spin_threshold": None, "status": found.status, "message": found.message,
           "saddle_spins": list(found.saddle_spins), "gamma0": gamma0, "mu": setup.friction.mu,
           "eps": setup.friction.eps}
    if found.status == "completed":
        out["omega_critical"] = found.omega_critical
        out["initial_spin_threshold"] = cs.initial_spin_threshold(found.omega_critical, setup, gamma0)
        out["nutation_frequency"] = found.nu_nutation
        out["check_relative_nutation_rate"] = cs.check_against_jacobian(found.omega_critical, setup)
        out["check_spin"] = cs.check_spin(found.omega_critical, setup.disk, setup.gravity)
        top = cs.window_top(found.saddle_spins, found.omega_critical)
        if math.isfinite(top):  # the window closes: a start with its top's rolling energy arrives at a saddle
            out["initial_spin_at_window_top"] = cs.initial_spin_threshold(top, setup, gamma0)
    if args.simulate:
        low = 0.8 * out["initial_spin_threshold"] if out["initial_spin_threshold"] else 15.0
        th = inversion.spin_threshold(setup=setup, gamma0=gamma0, bracket=(low, 2.0 * low), scan=11, xtol=1e-3)
        out["full_model_threshold"] = th.spin if th.status == "completed" else None
        out["full_model_status"] = th.status
        out["full_model_message"] = th.message
        if out["initial_spin_threshold"]:
            out["height_at_prediction"] = inversion.highest_point(out["initial_spin_threshold"], setup=setup,
                                                                  gamma0=gamma0).height
        if th.status == "completed":
            check = inversion.check_reduction(th.high, setup, gamma0)
            out["reduction_holds"] = check.holds
            out["reduction_check"] = {"eps": inversion.REDUCTION_EPS, "spin": th.high,
                                      "slow_flow_height": check.slow.height, "slow_flow_ending": check.slow.status,
                                      "slow_flow_end_time": check.slow.t_end, "full_model_height": check.full.height}
    if args.top and out["initial_spin_threshold"]:
        work = inversion_energy.spin_with_friction_work(setup, gamma0)
        out["initial_spin_with_friction_work"] = work.spin if work.status == "completed" else None
        out["friction_work"] = work.run.work if work.status == "completed" else None
        out["friction_work_status"], out["friction_work_message"] = work.status, work.message
        low = out["initial_spin_threshold"]
        reach = inversion.spin_threshold(setup=setup, gamma0=gamma0, bracket=(low, 1.3 * low), scan=11, xtol=1e-3,
                                         height=TOP)
        out["full_model_top_threshold"] = reach.spin if reach.status == "completed" else None
        out["full_model_top_message"] = reach.message
    if args.json:
        print(json.dumps(out))
    else:
        print(_text(out))
    failed = (found.status != "completed" or (args.simulate and out["full_model_status"] != "completed")
              or (args.top and out.get("full_model_top_threshold") is None))
    return 1 if failed else 0


def _text(out: dict) -> str:
    if out["omega_critical"] is None:
        lines = [f"no critical spin: {out['message']}"]
    else:
        lines = [f"omega_c = {out['omega_critical']:.4f} rad/s: {out['message']} (formula (C4), independent of mu "
                 "and eps)",
                 f"initial spin threshold (C5) = {out['initial_spin_threshold']:.4f} rad/s for gamma0 = "
                 f"{out['gamma0']:.4f} rad (the start's rolling energy equals the inverted spin's at omega_c; not a "
                 "bound: friction's work on the way up and the lenient criterion r + 0.8 e nearly cancel)",
                 f"check: at omega_c the slow flow's Jacobian (heyoka, small eps) gives the nutation a real part "
                 f"{out['check_relative_nutation_rate']:.1e} of the one at {out['check_spin']:.4f} rad/s (0 when the "
                 "formula holds)"]
        if "initial_spin_at_window_top" in out:
            lines.insert(2, f"the window closes: from an initial spin of {out['initial_spin_at_window_top']:.4f} rad/s "
                            "on (C5 at its top) the start has the rolling energy of an inverted spin that is a saddle "
                            "(losses neglected)")
    if "full_model_status" in out:
        full, predicted = out["full_model_threshold"], out["initial_spin_threshold"]
        if full is None:
            lines.append(f"full model (ODE Model 1, eps {out['eps']:g} m/s, mu {out['mu']:g}): "
                         f"{out['full_model_status']}: {out['full_model_message']}")
        elif predicted is None:
            lines.append(f"full model (ODE Model 1, eps {out['eps']:g} m/s, mu {out['mu']:g}): inverts above "
                         f"{full:.4f} rad/s")
        else:
            diff = full - predicted
            lines.append(f"full model (ODE Model 1, eps {out['eps']:g} m/s, mu {out['mu']:g}): inverts above "
                         f"{full:.4f} rad/s, {diff:+.4f} rad/s ({100 * diff / predicted:+.2f} % of the prediction) "
                         "above it")
        if "height_at_prediction" in out:
            lines.append(f"at the predicted spin S gets to r + {out['height_at_prediction']:.3f} e (the criterion: "
                         "r + 0.8 e; docs/inversion.md, How high S gets)")
        if "reduction_check" in out:
            c = out["reduction_check"]
            verdict = ("holds: the start stays in the friction cone" if out["reduction_holds"] else
                       f"does not hold: the slow flow ended ({c['slow_flow_ending']}) at {c['slow_flow_end_time']:.2f}"
                       " s, the start slides in its first swing")
            lines.append(f"the slow flow at {c['spin']:.4f} rad/s, eps {c['eps']:g} m/s, gets S to "
                         f"r + {c['slow_flow_height']:.3f} e, ODE Model 1 to r + {c['full_model_height']:.3f} e: the "
                         f"reduction {verdict}")
    if out.get("initial_spin_with_friction_work") is not None:
        c7, reach = out["initial_spin_with_friction_work"], out["full_model_top_threshold"]
        versus = (f"; ODE Model 1 (eps {out['eps']:g} m/s) gets S to r + {TOP} e above {reach:.4f} rad/s "
                  f"((C7) {100 * (c7 / reach - 1):+.2f} % off it)" if reach is not None else
                  f"; ODE Model 1's threshold for r + {TOP} e: {out['full_model_top_message']}")
        lines.append(f"with friction's work along the slow flow (C7, {1e3 * out['friction_work']:.4g} mJ up to "
                     f"omega_c): {c7:.4f} rad/s reaches the top" + versus)
    elif "friction_work_status" in out:
        lines.append(f"with friction's work (C7): {out['friction_work_status']}: {out['friction_work_message']}")
    return "\n".join(lines)

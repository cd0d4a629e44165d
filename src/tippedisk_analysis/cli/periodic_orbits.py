"""``tippedisk periodic-orbits``: periodic orbits by shooting or collocation, their Floquet multipliers and branches.

On the tippedisk (``--from-hopf``, ``--from-run``) Newton searches for an orbit of the reduced system and
reports what it found; with friction there is none (docs/periodic_orbits.md). Exit status: 0 an orbit
(or a completed branch); 3 no periodic orbit (the dataset is written: per point ``orbit_status`` says
whether Newton converged to an equilibrium or did not converge, with the residual and the energy lost over
the trial period); 1 a numerical failure (non-finite flow, a branch ended by the corrector); 2 bad input
(nothing written). ``--system`` demonstrates the method on the textbook systems of the tests. ``--method``: a
branch from a Hopf point uses collocation by default (docs/dynamics.md), a single orbit and a branch from an
orbit shooting.
"""

from __future__ import annotations

import math

from ..errors import ParameterError
from ..files import show
from .common import add_disk, add_output, disk_from_args, disk_options_given, finite_float, output_path, positive_int
from .registry import command

EXIT_NO_ORBIT = 3
ORBIT_SYSTEMS = ("vanderpol", "hopf", "bautin", "roessler", "torus", "homoclinic", "duffing", "ab")
"""The catalogue systems with an orbit or Hopf start (dynamics.TEXTBOOK; a test holds the two equal: --help
imports no heyoka)."""


def _arguments(p) -> None:
    source = p.add_argument_group("start (give exactly one)")
    source.add_argument("--from-hopf", metavar="FILE:LABEL", help="a Hopf point of a continuation dataset, e.g. "
                                                                  "c.nc:HOPF1 (tippedisk continue, or a branch of a "
                                                                  "textbook system: its orbit branch, to --to)")
    source.add_argument("--from-run", metavar="FILE", help="a simulation (tippedisk simulate): of an ODE model, Newton "
                        "from a Poincaré return; of Models 1/2 (m1, m2, h1), the rolling motion at its end: its "
                        "returns to gamma = pi/2, torus or orbit, and the orbit they wind around")
    source.add_argument("--system", help=f"a textbook system: {', '.join(ORBIT_SYSTEMS)}")
    source.add_argument("--from-orbit", metavar="FILE:POINT", help="an orbit of a periodic_orbits dataset, e.g. "
                                                                    "b.nc:5 (corrected, then continued with --to)")
    source.add_argument("--frictionless", metavar="BRANCH:OMEGA", help="the tippedisk without friction (mu = 0): "
                        "the family of orbits born at a spinning equilibrium, e.g. inverted:40, continued in the "
                        "energy to --to E_MAX [J] (default E + 0.1 J)")
    tip = p.add_argument_group("tippedisk options")
    tip.add_argument("--amplitudes", default="0.001,0.01,0.05",
                     help="--from-hopf: guess radii r of x_H + 2 r Re(q) (default 0.001,0.01,0.05)")
    tip.add_argument("--crossing", type=int, default=-2, help="--from-run: the return to start from (default -2, "
                                                              "the last but one)")
    tip.add_argument("--section", default="beta_dot=0", help="--from-run: section NAME=LEVEL (default beta_dot=0)")
    tip.add_argument("--returns-time", type=finite_float,
                     help="--from-run of Models 1/2: seconds of rolling motion whose returns are analysed "
                          "(default 500)")
    tip.add_argument("--max-iter", type=positive_int, default=25, help="Newton steps (default 25)")
    book = p.add_argument_group("--system / --from-orbit options")
    book.add_argument("--to", type=finite_float, help="continue the branch in the system's parameter to this value")
    book.add_argument("--parameter", help="--from-orbit: the continuation parameter (default the dataset's)")
    book.add_argument("--hopf-radius", type=finite_float, help="orbit radius of a Hopf start (default 0.05; "
                                                                "--frictionless: 1e-3); --radius is the disk's rim")
    book.add_argument("--period-max", type=finite_float, help="stop the branch at this period (homoclinic approach)")
    book.add_argument("--method", choices=("collocation", "shooting"),
                      help="the discretisation (default: collocation for a branch from a Hopf point, else shooting)")
    book.add_argument("--ntst", type=positive_int, help="collocation: mesh intervals (default 40; more where the "
                                                        "error estimate asks)")
    book.add_argument("--ncol", type=positive_int, help="collocation: Gauss points per interval, 2-7 (default 4)")
    book.add_argument("--segments", type=positive_int, help="shooting segments (default 1, or the dataset's)")
    book.add_argument("--phase", choices=("poincare", "integral"),
                      help="shooting: phase condition (default: integral for a branch from a Hopf point, else "
                           "poincare)")
    book.add_argument("--max-points", type=positive_int, default=200, help="branch points per direction (200)")
    add_output(p)
    add_disk(p)


@command("periodic-orbits", "periodic orbits by shooting or collocation: Floquet multipliers, branches (no orbit "
                            "on the tippedisk with friction: exit 3)", _arguments)
def periodic_orbits(args) -> int:
    from .. import results
    from ..analysis import orbits

    starts = [s for s in (args.from_hopf, args.from_run, args.system, args.from_orbit, args.frictionless) if s]
    if len(starts) != 1:
        raise ParameterError("give exactly one of --from-hopf FILE:LABEL, --from-run FILE, --system NAME, "
                             "--from-orbit FILE:POINT, --frictionless BRANCH:OMEGA")
    output = output_path(args)
    disk_given = disk_options_given(args)
    if disk_given and not args.frictionless:
        source = "--system (a textbook system has no disk)" if args.system else "the start dataset (it fixes the disk)"
        raise ParameterError(f"{', '.join(disk_given)} with {source}: the disk options belong to --frictionless; drop "
                             "them (the orbit radius of a Hopf start is --hopf-radius; --radius is the disk's rim)")
    if args.from_hopf:
        path, _, label = args.from_hopf.rpartition(":")
        if not path or not label:
            raise ParameterError(f"--from-hopf {args.from_hopf!r} is not FILE:LABEL; give e.g. c.nc:HOPF1")
        try:
            amplitudes = [float(a) for a in args.amplitudes.split(",")]
        except ValueError:
            raise ParameterError(f"--amplitudes {args.amplitudes!r}: give numbers separated by commas") from None
        if not amplitudes or any(not a > 0 for a in amplitudes):
            raise ParameterError("--amplitudes must be positive numbers, e.g. 0.001,0.01")
        source = results.load(path)
        if "setup" in results.config_of(source):
            ds = orbits.tippedisk_orbits_from_hopf(source, label, amplitudes, max_iter=args.max_iter)
        else:
            ds = _generic_hopf_branch(args, source, path, label)
    elif args.from_run:
        ds = _from_run(args, results.load(args.from_run))
    elif args.from_orbit:
        path, _, point = args.from_orbit.rpartition(":")
        try:
            index = int(point)
        except ValueError:
            raise ParameterError(f"--from-orbit {args.from_orbit!r} is not FILE:POINT; give e.g. b.nc:5") from None
        source = results.load(path)
        orbit = orbits.orbit_from_dataset(source, index, max_iter=args.max_iter)
        parameter = args.parameter or source.attrs.get("parameter") or ""
        ds = _orbit_or_branch(args, orbit, parameter, {"source": "dataset", "file": path, "point": index})
    elif args.frictionless:
        ds = _frictionless(args)
    else:
        ds = _textbook(args)
    results.save(ds, output)
    print(f"{show(output)}: {ds.attrs['message']}")
    if ds.attrs["status"] == "no_orbit":
        return EXIT_NO_ORBIT
    from ..dynamics.continuation import RESULTS

    return 0 if ds.attrs["status"] in RESULTS else 1


def _frictionless(args):
    import numpy as np

    from ..analysis import orbits
    from ..dynamics import continuation
    from ..parameters import Friction, Setup, to_dict

    branch, _, omega = args.frictionless.partition(":")
    try:
        omega = float(omega)
    except ValueError:
        raise ParameterError(f"--frictionless {args.frictionless!r} is not BRANCH:OMEGA; "
                             "give e.g. inverted:40") from None
    if not math.isfinite(omega):
        raise ParameterError(f"--frictionless {args.frictionless!r}: the spin rate must be finite; give e.g. "
                             "inverted:40")
    setup = Setup(disk=disk_from_args(args), friction=Friction(mu=0.0))
    radius = 1e-3 if args.hopf_radius is None else args.hopf_radius
    if not radius > 0:
        raise ParameterError(f"--hopf-radius {radius:g} must be positive")
    options = continuation.Options(ds=0.02, ds_max=0.1, max_points=args.max_points)
    try:
        br, prob = orbits.tippedisk_lyapunov_family(setup, branch, omega, args.to, radius=radius, options=options)
    except np.linalg.LinAlgError:
        raise ParameterError(f"--frictionless {args.frictionless!r}: the linearisation at that spin is not finite "
                             "(beyond what the model can evaluate); give a spin rate of physical size, e.g. "
                             "inverted:40") from None
    return orbits.tippedisk_branch_dataset(prob, br, {"source": "frictionless", "branch": branch, "omega": omega,
                                                      "setup": to_dict(setup)})


def _textbook(args):
    from .. import dynamics as dy

    tb = dy.TEXTBOOK.get(args.system)
    if tb is None or not tb.start:
        names = ", ".join(k for k, v in dy.TEXTBOOK.items() if v.start)
        raise ParameterError(f"unknown system {args.system!r} for periodic orbits; choose one of {names}")
    system = dy.textbook_system(args.system)
    radius = 0.05 if args.hopf_radius is None else args.hopf_radius
    if not radius > 0:
        raise ParameterError(f"--hopf-radius {radius:g} must be positive")
    if "hopf" in tb.start and args.to is not None and args.hopf_radius is None:
        return _textbook_hopf_branch(args, system, tb)
    method, discretisation = _discretisation(args, "shooting", 1, "poincare")
    if "hopf" in tb.start:
        value, state = tb.start["hopf"]
        orbit, _g = dy.orbit_from_hopf(system, tb.parameter, value, state, radius=radius, method=method,
                                       **discretisation)
    else:
        value, state, period = tb.start["orbit"]
        pars = system.with_pars(**{tb.parameter: value})
        if args.system == "roessler":
            state, period = dy.simulation_guess(system, state, pars, index=1, level=0.0, transient=200.0)
        orbit = dy.find_orbit(system, state, period, pars, method=method, **discretisation)
        orbit.value, orbit.parameter = value, tb.parameter
    config = {"source": "textbook", "start": {k: list(map(float, v[1])) for k, v in tb.start.items()},
              "facts": tb.facts}
    return _orbit_or_branch(args, orbit, tb.parameter, config)


def _textbook_hopf_branch(args, system, tb):
    """The branch born at a textbook system's Hopf point, started along the Hopf tangent (as AUTO-07p)."""
    from ..dynamics.orbit_branches import hopf_branch

    value, state = tb.start["hopf"]
    if args.to == value:
        raise ParameterError(f"--to {args.to:g} equals the Hopf value {tb.parameter} = {value:g}")
    from ..dynamics.discretisations import DEFAULT_METHOD

    method, discretisation = _discretisation(args, DEFAULT_METHOD, 4, "integral")
    return hopf_branch(system, state, system.with_pars(**{tb.parameter: value}), tb.parameter,
                       bounds=(min(value, args.to), max(value, args.to)), method=method, period_max=args.period_max,
                       options=_branch_options(args, method), config={"source": "textbook", "facts": tb.facts,
                                                                      "to": args.to}, **discretisation)


def _generic_hopf_branch(args, source, path: str, label: str):
    """--from-hopf on a branch of a generic System: a catalogue system is rebuilt by name (its fingerprint must
    match the file's); a user's System cannot be (equations stored in a file are never evaluated)."""
    from .. import dynamics as dy
    from ..results import config_of

    name, key = source.attrs.get("system", ""), source.attrs.get("system_key", "")
    if name not in dy.TEXTBOOK or dy.textbook_system(name).key != key:
        raise ParameterError(f"{path} holds a branch of the system {name!r}, which the command line cannot rebuild "
                             "(equations in a file are never evaluated); continue it in Python: dy.orbit_branch("
                             f"system, td.load({path!r}), {label!r}, bounds=(low, high))")
    parameter = source.attrs.get("parameters", "")
    low, high = config_of(source).get("bounds", {}).get(parameter, (None, None))
    if args.to is not None:
        index, _kind = dy.special_point(source, label)
        value = float(source[parameter].values[index])
        low, high = min(value, args.to), max(value, args.to)
    if low is None:
        raise ParameterError(f"{path} stores no bounds of {parameter!r}; give --to")
    from ..dynamics.discretisations import DEFAULT_METHOD

    method, discretisation = _discretisation(args, DEFAULT_METHOD, 4, "integral")
    return dy.orbit_branch(dy.textbook_system(name), source, label, bounds=(low, high), method=method,
                           period_max=args.period_max, options=_branch_options(args, method), **discretisation)


def _discretisation(args, default: str, segments: int, phase: str) -> tuple[str, dict]:
    """(method, its options) from --method, --ntst, --ncol, --segments and --phase (--segments or --phase poincare
    without --method: shooting)."""
    method = args.method or ("shooting" if args.segments or args.phase == "poincare" else default)
    if method == "shooting":
        if args.ntst or args.ncol:
            raise ParameterError("--ntst and --ncol are collocation options; drop them or give --method collocation")
        return method, {"segments": args.segments or segments, "phase": args.phase or phase}
    if args.segments or args.phase == "poincare":
        raise ParameterError("--segments and --phase poincare are shooting options; drop them or give --method "
                             "shooting")
    return method, {"ntst": args.ntst, "ncol": args.ncol}


def _branch_options(args, method: str):
    from ..dynamics import continuation
    from ..dynamics.discretisations import BRANCH_OPTIONS

    return continuation.Options(**(BRANCH_OPTIONS[method] | {"max_points": args.max_points}))


def _orbit_or_branch(args, orbit, parameter: str, config: dict):
    """The orbit alone, or (with --to) its branch in ``parameter``."""
    from .. import dynamics as dy
    from ..dynamics import continuation

    if args.to is None:
        status = "completed" if orbit.converged else ("no_orbit" if orbit.status in ("equilibrium", "not_converged")
                                                      else "failed")
        return dy.orbits_dataset([orbit], status, orbit.message, config)
    if not orbit.converged:
        raise ParameterError(f"no start orbit for the branch: {orbit.message}")
    if not parameter:
        raise ParameterError("give --parameter (the continuation parameter)")
    start = float(orbit.pars[orbit.system.parameter_index(parameter)])
    orbit.parameter, orbit.value = parameter, start
    if args.to == start:
        raise ParameterError(f"--to {args.to:g} equals the start value of {parameter}")
    bounds = {parameter: (min(start, args.to), max(start, args.to))}
    method, discretisation = _discretisation(args, orbit.method, 0, "poincare")
    if method == "shooting" and not args.segments:
        discretisation.pop("segments")  # the orbit's own
    options = (continuation.Options(ds=0.02, ds_max=0.1, max_points=args.max_points) if method == "shooting"
               else _branch_options(args, method))
    br, prob = dy.continue_orbits(orbit, parameter, bounds=bounds, direction=1 if args.to > start else -1,
                                  method=method, period_max=args.period_max, options=options, **discretisation)
    return dy.branch_dataset(prob, br, {**config, "to": args.to})


def _from_run(args, run):
    from ..analysis import orbits, rolling
    from ..results import config_of

    model = config_of(run).get("model") if run.attrs.get("kind") == "simulation" else None
    if model in rolling.ROLLING_RUNS:
        if args.section != "beta_dot=0" or args.crossing != -2:
            raise ParameterError("--section and --crossing belong to ODE runs; a rolling run's returns are to "
                                 "gamma = pi/2 (give --returns-time)")
        returns_time = rolling.RETURNS_TIME if args.returns_time is None else args.returns_time
        if not returns_time > 0:
            raise ParameterError(f"--returns-time {returns_time:g} must be positive, e.g. 500")
        return rolling.orbits_from_run(run, returns_time=returns_time)
    if args.returns_time is not None:
        raise ParameterError(f"--returns-time is the rolling analysis of a run of Models 1/2 "
                             f"({', '.join(rolling.ROLLING_RUNS)}); the run is of model {model!r}, which does not "
                             "roll: drop --returns-time")
    return orbits.tippedisk_orbits_from_run(run, crossing=args.crossing, section=args.section, max_iter=args.max_iter)

"""``tippedisk fit DATA``: an ODE model's parameters and initial states fitted to a recorded motion -> a netCDF
dataset of kind ``fit`` (``--json``: {name: {"value", "stderr"}} as the only output on stdout)."""

from __future__ import annotations

import dataclasses
import json
import sys

from ..files import show
from .common import add_output, disk_from_args, finite_float, output_path, positive_int, tolerance
from .registry import command
from .simulate import INITIAL, add_start_and_physics


def _arguments(p) -> None:
    p.add_argument("data", help="the record: CSV (header row: time and columns named as the model's states or "
                                "outputs, e.g. gamma, beta, z_S; empty cells for missing samples) or netCDF")
    p.add_argument("--model", default="ode-euler", help="ode-euler (default), ode-quaternion (exact Jacobian) or "
                                                        "any other model (finite differences, parameters only)")
    p.add_argument("--free", required=True,
                   help="comma-separated names to fit: parameters (mu, eps, e, m, ...) and/or initial states "
                        "(omega_z, beta, ...), e.g. mu,eps")
    add_output(p)
    p.add_argument("--json", action="store_true",
                   help='print {name: {"value", "stderr"}} as the only output on stdout (messages on stderr)')
    p.add_argument("--sigma", type=finite_float,
                   help="noise of every sample in its column's units (default: estimated from the residuals)")
    p.add_argument("--tol", type=tolerance, help="heyoka tolerance of the runs (default 1e-12)")
    p.add_argument("--max-nfev", type=positive_int, help="model runs per horizon (default 200)")
    add_start_and_physics(p, "initial state at the first sample (Table 3 defaults; values not freed are kept)",
                          "friction and gravity (Sect. 6 defaults; the start of freed values)")


@command("fit", "fit an ODE model's parameters and initial states to a recorded motion", _arguments)
def fit(args) -> int:
    from .. import results
    from ..analysis.fit import fit as fit_disk
    from ..analysis.fit import read_record
    from ..errors import ParameterError
    from ..parameters import Friction, InitialState, Setup

    free = [name.strip() for name in args.free.split(",") if name.strip()]
    if not free:
        raise ParameterError("--free names nothing; give e.g. --free mu,eps")
    output = output_path(args)
    times, observed = read_record(args.data)
    fric_kw = {k: v for k, v in (("mu", args.mu), ("eps", args.eps)) if v is not None}
    init_kw = {field: getattr(args, option.replace("-", "_")) for option, field, _ in INITIAL
               if getattr(args, option.replace("-", "_")) is not None}
    setup = Setup(disk=disk_from_args(args), friction=dataclasses.replace(Friction(), **fric_kw),
                  **({"gravity": args.gravity} if args.gravity is not None else {}))
    options = {k: v for k, v in (("tol", args.tol), ("max_nfev", args.max_nfev)) if v is not None}
    ds = fit_disk(times, observed, free, model=args.model, setup=setup, initial=InitialState(**init_kw),
                  sigma=args.sigma, **options)
    results.save(ds, output)
    line = f"{show(output)}: fit of {args.model} {ds.attrs['status']}: {ds.attrs['message']}"
    if args.json:
        values = {str(k): {"value": float(v), "stderr": float(e)}
                  for k, v, e in zip(ds.parameter.values, ds.estimate.values, ds.stderr.values)}
        print(json.dumps(values))
        print(line, file=sys.stderr)
    else:
        print(line)
        for k, v, e in zip(ds.parameter.values, ds.estimate.values, ds.stderr.values):
            print(f"  {k} = {v:.6g} +- {e:.2g}")
    return 1 if ds.attrs["status"] == "not_converged" else 0

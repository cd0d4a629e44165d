"""The result of :func:`.fitting.fit`: uncertainty, identifiability, status, and the dataset of kind ``fit``.

At the optimum theta (p free values, m observed samples, residuals r, Jacobian J = dr/dtheta):
s^2 = |r|^2 / (m - p) without sigma, 1 with it; D = diag(1 / |J_k|) (column norms); J D = U S V^T;
cov = s^2 D V S^-2 V^T D over the singular values S_k >= ``identifiability_tol`` (a pseudo-inverse: the
combinations below it are undetermined, named in the message and flagged per value). AIC and BIC compare models
on the same data: m ln(|r|^2 / m) + 2p (+ p ln m) without sigma, |r|^2 + 2p (+ p ln m) with it.

Dimensions: ``time`` (the samples), ``parameter`` (the free values, with ``parameter_units``; ``parameter_column``
repeats it for matrices), ``combination`` (singular values, descending). Per observed series ``y``: the fitted run
``y``, the data ``y_data``, the residual ``y_residual`` = data - fit, and ``y_used`` (0 at missing samples, where
data and residual hold 0) if samples are missing; every state's fitted run too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..errors import ParameterError
from ..results import index_coordinate, make_attrs
from .datasets import flag_attrs, label_coordinates, mixed_units

STATUSES = ("completed", "not_converged", "bound_hit", "misfit", "not_identifiable")  # after completed: by priority
SYSTEMATIC = 0.5  # lag-1 autocorrelation of a series' residuals above which they are systematic (white noise: ~0)
KINDS = {"initial_state": 0, "parameter": 1}
AT_BOUND = {"inside": 0, "lower": 1, "upper": 2}
MIXED = "the units differ along parameter: see the coordinate parameter_units"


@dataclass
class Stage:
    """One least-squares solve over the first ``n_samples`` samples."""

    n_samples: int
    theta: np.ndarray
    status: int  # scipy's: > 0 converged, 0 max_nfev, -1 failed
    nfev: int
    njev: int
    active: np.ndarray  # -1 lower bound, 1 upper bound, 0 inside
    message: str


def _combination(names, direction, values) -> str:
    """A right singular vector (in the free values' own units) as relative changes, e.g. 'da/a : db/b = +0.71 :
    -0.71' (absolute 'dx' for values at zero); components below 5 % are left out."""
    rel = np.array([d / abs(v) if v != 0 else d for d, v in zip(direction, values)])
    rel /= np.linalg.norm(rel)
    keep = [i for i in range(len(rel)) if abs(rel[i]) >= 0.05]
    if keep and rel[keep[0]] < 0:
        rel = -rel
    terms = [f"d{names[i]}/{names[i]}" if values[i] != 0 else f"d{names[i]}" for i in keep]
    return f"{' : '.join(terms)} = {' : '.join(f'{rel[i]:+.3g}' for i in keep)}"


def summary(problem, theta, identifiability_tol: float) -> dict:
    """Residuals, covariance, correlations and the singular values of the column-scaled Jacobian of a
    :class:`.fitting.FitProblem` at ``theta``."""
    r, J = problem.residuals(theta), problem.jacobian(theta)
    m, p = J.shape
    rss = float(r @ r)
    s2 = 1.0 if problem.sigma_given else rss / (m - p)
    norms = np.linalg.norm(J, axis=0)
    scale = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 0.0)
    _U, S, Vt = np.linalg.svd(J * scale, full_matrices=False)
    kept = S >= identifiability_tol
    V = Vt.T
    cov = s2 * (scale[:, None] * (V[:, kept] / S[kept] ** 2) @ V[:, kept].T * scale[None, :])
    stderr = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    corr = np.where(np.outer(stderr, stderr) > 0, corr, 0.0)
    np.fill_diagonal(corr, np.where(stderr > 0, 1.0, 0.0))
    null = V[:, ~kept]
    determined = (norms > 0) & (np.max(np.abs(null), axis=1, initial=0.0) < 0.1)
    ic = (m * np.log(rss / m) if not problem.sigma_given and rss > 0 else rss)
    return {"r": r, "rss": rss, "s2": s2, "m": m, "p": p, "norms": norms, "S": S, "V": V, "kept": kept, "cov": cov,
            "stderr": stderr, "corr": corr, "determined": determined, "aic": ic + 2 * p, "bic": ic + p * np.log(m)}


def autocorrelations(problem, misfit) -> dict[str, float]:
    """Lag-1 autocorrelation of each observed series' residuals over its measured samples, in time order."""
    out = {}
    for j, k in enumerate(problem.names):
        r = misfit[problem.used[:, j], j] * problem.scale[problem.used[:, j], j]
        r = r - r.mean()
        out[k] = float(r[1:] @ r[:-1] / (r @ r)) if r.size > 2 and r @ r > 0 else 0.0
    return out


def status_of(problem, stage: Stage, stats: dict, theta, tol: float) -> tuple[str, str]:
    """(status, one-line message naming what to change): every finding in the message, the status of the first in
    the order not_converged, bound_hit (a bound can cause the others), misfit, not_identifiable."""
    names = problem.free
    misfit = problem.run(theta)[1] - problem.data
    rms = ", ".join(f"{k} {np.sqrt(np.mean(misfit[problem.used[:, j], j] ** 2)):.3g}"
                    for j, k in enumerate(problem.names))
    found = []  # (status, text)
    if stage.status <= 0:
        found.append(("not_converged", f"the trust region stopped after {stage.nfev} runs ({stage.message}); raise "
                      "max_nfev, give a start closer to the data or more horizons"))
    hit = [f"{names[i]} at its {'lower' if a < 0 else 'upper'} bound" for i, a in enumerate(stage.active) if a]
    if hit:
        found.append(("bound_hit", f"{', '.join(hit)}; widen the bound if it is not physical"))
    systematic = {k: a for k, a in autocorrelations(problem, misfit).items() if a > SYSTEMATIC}
    if systematic:
        what = ", ".join(f"{k} {a:.2f}" for k, a in systematic.items())
        found.append(("misfit", f"the residuals are systematic (lag-1 autocorrelation {what} > {SYSTEMATIC}): a "
                      "local minimum or a model that does not describe the record; give a closer start or shorter "
                      "first horizons (or expect this if the record's own noise is correlated)"))
    S, kept = stats["S"], stats["kept"]
    if not kept.all():
        flat = [names[i] for i in range(len(names)) if stats["norms"][i] == 0]
        if flat:
            what = f"the data do not depend on {', '.join(flat)}"
        else:
            k = int(np.flatnonzero(~kept)[-1])
            direction = stats["V"][:, k] / stats["norms"]  # in the free values' own units
            involved = [names[i] for i in range(len(names)) if abs(stats["V"][i, k]) >= 0.05]
            what = (f"only a combination of {', '.join(involved)} is determined "
                    f"({_combination(names, direction, theta)} leaves the fit unchanged: scaled singular value "
                    f"{S[k]:.2g} < {tol:.2g})")
        found.append(("not_identifiable", f"{what}; fix all but one of them or add data that separates them"))
    corr = np.abs(stats["corr"] - np.eye(len(names)))
    if len(names) > 1 and corr.max() > 0.99 and kept.all():
        i, j = np.unravel_index(np.argmax(corr), corr.shape)
        found.append(("completed", f"{names[i]} and {names[j]} are correlated ({stats['corr'][i, j]:+.4f}): a "
                      "longer or richer record separates them"))
    order = (*STATUSES[1:], "completed")  # the first finding in this order names the status
    status = min((s for s, _ in found), key=order.index, default="completed")
    head = f"converged ({problem.runs} model runs)" if status == "completed" else f"{problem.runs} model runs"
    return status, "; ".join([head, *(text for _, text in found), f"rms residual {rms}"])


def fit_dataset(problem, stages: list[Stage], config: dict, identifiability_tol: float) -> xr.Dataset:
    """The dataset of kind ``fit`` (module docstring)."""
    system, last = problem.system, stages[-1]
    theta = last.theta
    stats = summary(problem, theta, identifiability_tol)
    status, message = status_of(problem, last, stats, theta, identifiability_tol)
    X, Y, _dY = problem.run(theta)
    lag1 = autocorrelations(problem, Y - problem.data)
    x0, pars = problem.unpack(theta)
    names, p = problem.free, len(problem.free)
    units = [system.units_of(k) for k in names]
    coords = {**label_coordinates("parameter", names, units, "free value (initial state or parameter)"),
              "parameter_column": ("parameter_column", np.array(names, dtype=str),
                                   {"long_name": "free value (the columns of the matrices)"}),
              "combination": index_coordinate("combination", p, "index of the singular value, descending"),
              "time": ("time", problem.times, {"units": system.time_units, "long_name": "time of the sample"})}
    per = ("parameter",)
    data = {
        "estimate": (per, theta, {**mixed_units("fitted value"), "comment": MIXED}),
        "start": (per, problem.start, {**mixed_units("value at the start of the fit"), "comment": MIXED}),
        "stderr": (per, stats["stderr"], {**mixed_units("standard error of the estimate (over the determined "
                                                        "combinations)"), "comment": MIXED}),
        "free_kind": (per, np.array([KINDS["initial_state" if k in system.state_names else "parameter"]
                                     for k in names], np.int8), flag_attrs("what the free value is", KINDS)),
        "determined": (per, stats["determined"].astype(np.int8),
                       flag_attrs("whether the data determine the value (no: it lies along a combination "
                                  "with a singular value below identifiability_tol)", {"no": 0, "yes": 1})),
        "at_bound": (per, np.array([AT_BOUND["lower" if a < 0 else "upper" if a > 0 else "inside"]
                                    for a in last.active], np.int8), flag_attrs("bound active at the estimate",
                                                                                AT_BOUND)),
        "jacobian_column_norm": (per, stats["norms"], {"long_name": "norm of the Jacobian's column d r / d value "
                                                       "(the column scaling D^-1)", "comment": MIXED}),
        "covariance": (("parameter", "parameter_column"), stats["cov"],
                       {"long_name": "covariance of the estimates", "comment": "units: the product of the row's and "
                        "the column's parameter_units"}),
        "correlation": (("parameter", "parameter_column"), stats["corr"],
                        {"units": "1", "long_name": "correlation of the estimates (0 for an undetermined value)"}),
        "singular_value": ("combination", stats["S"], {"units": "1", "long_name": "singular value of the "
                                                       "column-scaled Jacobian J D (columns of unit norm)"}),
        "singular_vector": (("parameter", "combination"), stats["V"],
                            {"units": "1", "long_name": "right singular vector of J D: the combination of the "
                             "column-scaled free values each singular value belongs to"}),
    }
    for j, k in enumerate(problem.names):
        u = system.units_of(k)
        used = problem.used[:, j]
        data[f"{k}_data"] = ("time", np.where(used, problem.data[:, j], 0.0),
                             {"units": u, "long_name": f"measured {k}" + ("" if used.all() else " (0 where missing)")})
        data[f"{k}_residual"] = ("time", np.where(used, problem.data[:, j] - Y[:, j], 0.0),
                                 {"units": u, "long_name": f"residual of {k}: data - fit"
                                  + ("" if used.all() else " (0 where missing)"),
                                  "lag1_autocorrelation": lag1[k]})
        if not used.all():
            data[f"{k}_used"] = ("time", used.astype(np.int8), flag_attrs(f"whether the sample of {k} was measured",
                                                                          {"missing": 0, "used": 1}))
        if k in system.observables:
            data[k] = ("time", Y[:, j], {"units": u, "long_name": f"fitted run: {k}"})
    for i, k in enumerate(system.state_names):
        data[k] = ("time", X[:, i], {"units": system.units_of(k), "long_name": f"fitted run: state {k}"})
    attrs = make_attrs("fit", config, status, message, title=f"Fit of {system.name} to a record",
                       **system.attrs(pars), initial_state="; ".join(f"{k} = {v!r}" for k, v in
                                                                     zip(system.state_names, map(float, x0))),
                       n_samples=int(stats["m"]), n_free=int(p), degrees_of_freedom=int(stats["m"] - p),
                       residual_sum_of_squares=stats["rss"], residual_variance=stats["s2"],
                       sigma_given=int(problem.sigma_given), aic=float(stats["aic"]), bic=float(stats["bic"]),
                       identifiability_tol=float(identifiability_tol), model_runs=int(problem.runs),
                       horizon_samples=" ".join(str(s.n_samples) for s in stages),
                       least_squares_status=int(last.status))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def compare_fits(fits, names=None) -> xr.Dataset:
    """Models fitted to the same record side by side: along ``model`` (``names``, default each fit's ``model`` or
    ``system`` attribute) the residual sum of squares, AIC, BIC, their differences to the lowest, the Akaike
    weights exp(-dAIC/2) / sum, the number of free values and each fit's status. Lower AIC/BIC: the better
    model; a difference above 10 is decisive. Fits of different records (times, data, missing samples) or with and
    without sigma are refused: their criteria are not comparable."""
    fits = list(fits)
    if len(fits) < 2 or any(ds.attrs.get("kind") != "fit" for ds in fits):
        raise ParameterError("compare_fits needs two or more datasets of kind fit (dy.fit, td.fit, tippedisk fit)")
    names = [str(ds.attrs.get("model", ds.attrs.get("system", f"fit {i}"))) for i, ds in enumerate(fits)] \
        if names is None else [str(n) for n in names]
    if len(set(names)) != len(fits):
        raise ParameterError(f"compare_fits: the names {names} are not {len(fits)} distinct names; give names=[...]")
    first = fits[0]
    series = sorted(str(k) for k in first.data_vars if str(k).endswith(("_data", "_used")))
    for name, ds in zip(names[1:], fits[1:]):
        same = (ds.sizes["time"] == first.sizes["time"] and np.array_equal(ds.time.values, first.time.values)
                and sorted(str(k) for k in ds.data_vars if str(k).endswith(("_data", "_used"))) == series
                and all(np.array_equal(ds[k].values, first[k].values) for k in series))
        if not same:
            raise ParameterError(f"compare_fits: {name!r} was fitted to another record than {names[0]!r} (times, "
                                 "observed series or missing samples differ); fit every model to the same data")
        if ds.attrs["sigma_given"] != first.attrs["sigma_given"]:
            raise ParameterError(f"compare_fits: {name!r} and {names[0]!r} differ in whether sigma was given; give "
                                 "the same sigma (or none) to every fit")
    aic = np.array([float(ds.attrs["aic"]) for ds in fits])
    bic = np.array([float(ds.attrs["bic"]) for ds in fits])
    weight = np.exp(-(aic - aic.min()) / 2)
    per = ("model",)
    data = {
        "residual_sum_of_squares": (per, [float(ds.attrs["residual_sum_of_squares"]) for ds in fits],
                                    {"units": "1", "long_name": "sum of the squared weighted residuals"}),
        "aic": (per, aic, {"units": "1", "long_name": "Akaike information criterion (lower is better)"}),
        "bic": (per, bic, {"units": "1", "long_name": "Bayesian information criterion (lower is better)"}),
        "delta_aic": (per, aic - aic.min(), {"units": "1", "long_name": "AIC minus the lowest AIC"}),
        "delta_bic": (per, bic - bic.min(), {"units": "1", "long_name": "BIC minus the lowest BIC"}),
        "akaike_weight": (per, weight / weight.sum(), {"units": "1", "long_name": "Akaike weight exp(-dAIC/2) / sum"}),
        "n_free": (per, np.array([int(ds.attrs["n_free"]) for ds in fits], np.int32),
                   {"units": "1", "long_name": "number of free values"}),
        "free": (per, np.array([" ".join(map(str, ds.parameter.values)) for ds in fits], dtype=str),
                 {"long_name": "the free values"}),
        "fit_status": (per, np.array([str(ds.attrs["status"]) for ds in fits], dtype=str),
                       {"long_name": "status of each fit"}),
    }
    coords = {"model": ("model", np.array(names, dtype=str), {"long_name": "fitted model"})}
    best = names[int(np.argmin(aic))]
    message = f"lowest AIC: {best} (the next is {np.sort(aic - aic.min())[1]:.3g} higher)"
    unfinished = [n for n, ds in zip(names, fits) if ds.attrs["status"] != "completed"]
    if unfinished:
        message += f"; fits not completed: {', '.join(unfinished)} (see fit_status; their criteria may mislead)"
    return xr.Dataset(data, coords=coords, attrs=make_attrs(
        "fit_comparison", {"models": names}, "completed", message, title="Models fitted to the same record",
        n_samples=int(first.attrs["n_samples"]), sigma_given=int(first.attrs["sigma_given"]), best_model=best))

"""The set-valued tippedisk after the inversion (docs/rolling.md): the event-driven model against Moreau Models
1/2, the rolling motion as an invariant torus about an elliptic periodic orbit, and the orbit family in the
energy and the spin with the boundary where rolling stops being consistent with Coulomb's cone.

    tippedisk study rolling [--output-dir DIR] [--quick]

Writes rolling_convergence.nc (Moreau Model 1 against the hybrid model for three time steps),
rolling_inversion_runs.nc (gamma and E_tot of the runs drawn: h1, Moreau Models 1 and 2 at 1e-5 s), rolling_orbit.nc
(the torus of the Table 3 run: its returns to gamma = pi/2, the central orbit), rolling_family_energy.nc and
rolling_family_spin.nc (the family with the smallest cone margin per orbit), and the figures
rolling_inversion.png, rolling_section.png, rolling_family.png (:func:`redraw` draws them again from data/rolling).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import xarray as xr
from tippedisk_studies._common import prepare, save

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import rolling as ar
from tippedisk_analysis.dynamics.orbits import monodromy_fd
from tippedisk_analysis.plotting import style
from tippedisk_analysis.plotting.simulation import draw_convergence, shade_sliding
from tippedisk_analysis.results import make_attrs

T_RUN = 8.0  # [s] the Table 3 run through the inversion
T_COMPARE = 1.0  # [s] the window of the Moreau error
MOREAU_DTS = (1e-4, 1e-5, 1e-6)
SMALL_TORI = (1e-2, 3e-3, 1e-3)  # displacements from the central orbit along its elliptic eigenvector


def convergence(runs: dict, hybrid: xr.Dataset) -> xr.Dataset:
    """max |gamma_M1 - gamma_h1| on [0, T_COMPARE] and E_tot at the end, per Moreau time step."""
    t = hybrid.time.values
    window = t <= T_COMPARE + 1e-9
    err, energy = [], []
    for dt in MOREAU_DTS:
        m1 = runs[dt].interp(time=t[window])
        err.append(float(np.max(np.abs(m1.gamma.values - hybrid.gamma.values[window]))))
        energy.append(float(runs[dt].E_tot[-1]))
    config = {"t_compare": T_COMPARE, "t_run": T_RUN, "hybrid_config": hybrid.attrs.get("config", "")}
    return xr.Dataset(
        {"gamma_error": ("dt", np.array(err), {"units": "rad", "long_name": "max |gamma_M1 - gamma_h1| on [0, 1] s"}),
         "E_tot_end": ("dt", np.array(energy), {"units": "J", "long_name": f"E_tot of Model 1 at t = {T_RUN:g} s"}),
         "E_tot_end_hybrid": ((), float(hybrid.E_tot[-1]), {"units": "J", "long_name": "E_tot of h1 at the end"})},
        coords={"dt": ("dt", np.array(MOREAU_DTS), {"units": "s", "long_name": "Moreau time step"})},
        attrs=make_attrs("rolling_convergence", config, "completed",
                         "Moreau Model 1 against the event-driven model (hybrid-euler)"))


def inversion_runs(hybrid, m1, m2) -> xr.Dataset:
    """gamma and E_tot of the three runs drawn in rolling_inversion.png, with h1's switches (kind
    rolling_inversion_runs): h1 along ``hybrid_time``, Moreau Models 1 and 2 (dt 1e-5 s) along ``time``."""
    def column(ds, name, dim):
        units = {"gamma": "rad", "E_tot": "J"}[name]
        return (dim, ds[name].values.astype("float32"), {"units": units, "long_name": ds[name].attrs.get(
            "long_name", name)})

    data = {"gamma_h1": column(hybrid, "gamma", "hybrid_time"), "E_tot_h1": column(hybrid, "E_tot", "hybrid_time"),
            "gamma_m1": column(m1, "gamma", "time"), "E_tot_m1": column(m1, "E_tot", "time"),
            "gamma_m2": column(m2, "gamma", "time"), "E_tot_m2": column(m2, "E_tot", "time"),
            "switch_time": ("switch", hybrid.switch_time.values, {"units": "s", "long_name": "time of h1's switch"}),
            "switch_mode": ("switch", hybrid.switch_mode.values, {"units": "1", "long_name": "h1's mode after it"})}
    coords = {"hybrid_time": ("hybrid_time", hybrid.time.values, {"units": "s", "long_name": "time of h1"}),
              "time": ("time", m1.time.values, {"units": "s", "long_name": "time of the Moreau runs"})}
    message = "; ".join(f"{name}: {ds.attrs['message']}" for name, ds in (("h1", hybrid), ("m1", m1), ("m2", m2)))
    ds = xr.Dataset(data, coords=coords)
    ds.attrs = make_attrs("rolling_inversion_runs", {"t_run": float(hybrid.time[-1]), "moreau_dt": 1e-5},
                          "completed", message, model="h1, m1, m2",
                          title="Table 3's inversion by the event-driven model and Moreau Models 1 and 2")
    return ds


def runs_of(stored: xr.Dataset) -> tuple:
    """(h1, Moreau Model 1, Moreau Model 2) as datasets with ``time``, ``gamma``, ``E_tot`` from
    :func:`inversion_runs`' dataset (h1's with its switches)."""
    hybrid = xr.Dataset({"gamma": stored.gamma_h1, "E_tot": stored.E_tot_h1, "switch_time": stored.switch_time,
                         "switch_mode": stored.switch_mode}).rename(hybrid_time="time")
    return (hybrid, *(xr.Dataset({"gamma": stored[f"gamma_{m}"], "E_tot": stored[f"E_tot_{m}"]}) for m in ("m1", "m2")))


@style.styled
def inversion_figure(hybrid, m1, m2, conv):
    """Stacked: gamma through the inversion, the Moreau error over its time step, the energy."""
    fig, ax = style.stacked(3, panel_height=3.4)
    for ds, label, line in ((hybrid, "hybrid-euler (h1)", "-"), (m1, r"Moreau Model 1, $\Delta t$ = 1e-5 s", "--"),
                            (m2, r"Moreau Model 2, $\Delta t$ = 1e-5 s", ":")):
        ax[0].plot(ds.time, ds.gamma, line, label=label)
        ax[2].plot(ds.time, ds.E_tot, line, label=label)
    shade_sliding([ax[0], ax[2]], hybrid)
    for a in (ax[0], ax[2]):
        a.set_xlabel(r"$t$ [s]")
    style.legend_below(ax[0], ncol=2)
    ax[2].legend(loc="upper right")
    ax[0].set_xlim(0, 2)
    ax[0].set_ylabel(r"$\gamma$ [rad]")
    ax[0].set_title("through the inversion (shaded: h1 slides)")
    draw_convergence(ax[1], conv)
    ax[1].lines[0].set_label(r"Moreau Model 1 against h1 on [0, 1] s")
    ax[1].legend()
    ax[1].set(xlabel=r"Moreau time step $\Delta t$ [s]", ylabel=r"$\max\,|\gamma_{M1} - \gamma_{h1}|$ [rad]")
    ax[2].set_ylabel(r"$E_\mathrm{tot}$ [J]")
    ax[2].set_ylim(float(hybrid.E_tot[-1]) - 0.01, float(hybrid.E_tot[0]) + 0.005)
    return fig


def small_tori(orbit, t_end: float) -> list:
    """Sections of the motions started at the central orbit displaced along its elliptic eigenvector."""
    system = ar.reduced_system()
    x0 = orbit.states[0]
    ev, V = np.linalg.eig(monodromy_fd(system, x0, orbit.period, orbit.pars))
    v = V[:, int(np.argmax(ev.imag))].real
    v /= np.linalg.norm(v / np.asarray(system.state_scale))
    return [(a, ar.section(x0 + a * v, t_end=t_end)) for a in SMALL_TORI]


@style.styled
def section_figure(orbit_ds, tori, orbit):
    fig, (ax,) = style.stacked(1, panel_height=5.5)
    names = list(orbit_ds.state.values)
    X = orbit_ds.return_state.values
    ib, iy = names.index("beta"), names.index("omega_y")
    rho = float(orbit_ds.rotation_number)
    ax.plot(X[:, ib], X[:, iy], ".", ms=2, label=f"Table 3 run after the inversion (rotation number {rho:.6f})")
    for a, sec in tori:
        m = ar.identify(sec)
        ax.plot(sec.beta, sec.omega_y, ".", ms=1.5, label=f"displaced {a:g} from the orbit ({m.kind}, "
                                                          f"{m.rotation_number:.6f})")
    x0 = orbit.states[0]
    ax.plot(x0[0], x0[3], "k*", ms=10, label=f"elliptic orbit, $T$ = {orbit.period:.5f} s, Floquet angle "
                                            f"{ar.floquet_angle(orbit):.6f}")
    ax.set_xlabel(r"$\beta$ [rad]")
    ax.set_ylabel(r"$\omega_y$ [rad s$^{-1}$]")
    ax.set_title(r"returns of the rolling motion to $\gamma = \pi/2$ (upwards)")
    style.legend_below(ax, 0.15, markerscale=4)
    return fig


@style.styled
def family_figure(families):
    """Stacked, for the family in the energy then in the spin: the smallest cone margin and normal force on each
    orbit, and its period."""
    fig, ax = style.stacked(4, panel_height=3.6)
    labels = {"E_tot": (r"$E_\mathrm{tot}$ [J] ($\omega_x$ at $x_0$ held)", "the family in the energy"),
              "omega_x": (r"$\omega_x$ at the orbit's first point ($\gamma \approx \pi/2$) [rad s$^{-1}$] "
                          r"($E_\mathrm{tot}$ held)", "the family in the spin")}
    for j, ds in enumerate(families):
        p = ds.attrs["parameter"]
        x = ds[p].values
        xlabel, title = labels[p]
        margin, period = ax[2 * j], ax[2 * j + 1]
        margin.plot(x, ds.min_cone_margin, ".-", label=r"smallest $\mu\lambda_N - |\lambda_T|$")
        margin.plot(x, ds.min_lambda_N, ".-", label=r"smallest $\lambda_N$")
        margin.axhline(0, color="k", lw=0.8)
        boundary = ar.consistency_boundary(ds)
        for k, b in enumerate(boundary):
            margin.axvline(b, color="tab:red", ls=":", label=None if k else
                           "the cone margin crosses 0 at " + ", ".join(f"{v:.5g}" for v in boundary))
        start = float(x[np.argmin(np.abs(ds.arclength.values))])
        margin.axvline(start, color="0.5", ls="--", label="the orbit at the torus's centre")
        margin.set(ylabel="force on the orbit [N]", title=title, ylim=(None, 2.0 * float(ds.min_lambda_N.max())))
        margin.legend(loc="upper left")
        margin.sharex(period)
        margin.tick_params(labelbottom=False)
        period.plot(x, ds.period, ".-")
        period.set(ylabel="period [s]", xlabel=xlabel)
    return fig


def redraw(data_dir: str = "data/rolling", figure_dir: str = "docs/figures") -> list[Path]:
    """rolling_inversion.png, rolling_section.png and rolling_family.png again from the stored datasets in
    ``data_dir`` (the central orbit and the three small tori around it are recomputed: seconds)."""
    data, figures = Path(data_dir), Path(figure_dir)
    inversion = inversion_figure(*runs_of(td.load(data / "rolling_inversion_runs.nc")),
                                 td.load(data / "rolling_convergence.nc"))
    save(inversion, figures / "rolling_inversion.png")
    orbit_ds = td.load(data / "rolling_orbit.nc")
    orbit = central_orbit(orbit_ds)
    save(section_figure(orbit_ds, small_tori(orbit, 300.0), orbit), figures / "rolling_section.png")
    families = [td.load(data / f"rolling_family_{name}.nc") for name in ("energy", "spin")]
    save(family_figure(families), figures / "rolling_family.png")
    return [figures / name for name in ("rolling_inversion.png", "rolling_section.png", "rolling_family.png")]


def central_orbit(orbit_ds):
    """The elliptic periodic orbit at the torus's centre, found again from its stored start and period."""
    return dy.find_orbit(ar.reduced_system(), orbit_ds.initial_state.values[0], float(orbit_ds.period[0]),
                         orbit_ds.runtime_parameters.values[0], pinned=("omega_x",))


def main(output_dir: str = "output", quick: bool = False):
    out = prepare(output_dir)
    t_run = 2.0 if quick else T_RUN
    hybrid = td.simulate("h1", t_run)
    print(f"h1: {hybrid.attrs['message']}")
    runs = {dt: td.simulate("m1", t_run, dt=dt) for dt in MOREAU_DTS}
    m2 = td.simulate("m2", t_run, dt=1e-5)
    conv = convergence(runs, hybrid)
    td.save(conv, out / "rolling_convergence.nc")
    for dt, e in zip(MOREAU_DTS, conv.gamma_error.values):
        print(f"dt = {dt:g} s: max |gamma_M1 - gamma_h1| on [0, 1] s = {e:.4g} rad, E_tot(end) M1 "
              f"{float(runs[dt].E_tot[-1]):.9f} J")
    stored = td.save(inversion_runs(hybrid, runs[1e-5], m2), out / "rolling_inversion_runs.nc")
    save(inversion_figure(*runs_of(td.load(stored)), conv), out / "rolling_inversion.png")

    orbit_ds = ar.orbits_from_run(hybrid, returns_time=200.0 if quick else ar.RETURNS_TIME)
    td.save(orbit_ds, out / "rolling_orbit.nc")
    print(f"rolling_orbit: {orbit_ds.attrs['message']}")
    orbit = central_orbit(orbit_ds)
    tori = small_tori(orbit, 200.0 if quick else 300.0)
    for a, sec in tori:
        print(f"displaced by {a:g}: {ar.identify(sec).message}")
    save(section_figure(orbit_ds, tori, orbit), out / "rolling_section.png")

    families = []
    for parameter, bounds in (("E_tot", (0.30, 0.50)), ("omega_x", (30.0, 50.0))):
        ds = ar.family(orbit, parameter, bounds, max_points=4 if quick else 40)
        td.save(ds, out / f"rolling_family_{'energy' if parameter == 'E_tot' else 'spin'}.nc")
        boundary = ", ".join(f"{b:.6g}" for b in ar.consistency_boundary(ds)) or "none"
        print(f"family in {parameter}: {ds.attrs['message']}; the cone margin crosses zero at {boundary}")
        families.append(ds)
    save(family_figure(families), out / "rolling_family.png")
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])

"""Stability maps, critical spin speeds, netCDF round trip, CLI and figure."""

import json

import numpy as np
import pytest
from xarray.testing import assert_identical

from tippedisk_analysis import Friction, ParameterError, Setup, results
from tippedisk_analysis.analysis import maps
from tippedisk_analysis.analysis import reduced
from tippedisk_analysis.analysis import stability as sb
from tippedisk_analysis.analysis import stationary as st
from tippedisk_analysis.cli import main

OMEGA = np.linspace(20.0, 45.0, 26)
EPS = np.array([0.1, 0.2, 0.25])


@pytest.fixture(scope="module")
def small_map():
    return maps.stability_map(OMEGA, EPS)


def test_map_layout(small_map):
    ds = small_map
    assert ds.attrs["kind"] == "stability_map"
    assert list(ds["branch"].values) == ["noninverted", "inverted"]
    assert ds["max_real_eig"].dims == ("branch", "omega", "eps")
    assert ds["eig_real"].dims == ("branch", "omega", "eps", "eig")
    assert not any(np.iscomplexobj(v) for v in ds.data_vars.values())
    assert np.all(ds["eig_real"].diff("eig") <= 0)  # sorted by real part, descending
    np.testing.assert_array_equal(ds["max_real_eig"], ds["eig_real"].isel(eig=0))
    assert ds["stability"].dtype == np.int8
    assert ds["stability"].attrs["flag_meanings"].split() == list(sb.STABILITY_FLAGS)
    for name in ds.variables:
        if name not in ("branch", "eig", "crossing", "stability", "critical_direction"):
            assert "units" in ds[name].attrs, name
        assert "long_name" in ds[name].attrs, name
    assert json.loads(ds.attrs["config"])["omega"] == {"start": 20.0, "stop": 45.0, "n": 26}
    # the stored eigenvalues are the ones of the API at a grid point
    ev = sb.spectrum("inverted", [OMEGA[3]], maps._parameter_grid(
        Setup(), {"eps": [EPS[1]]}, 1e-12, (1, 1))).eigenvalues[0]
    np.testing.assert_allclose(ds["eig_real"].sel(branch="inverted").isel(omega=3, eps=1), ev.real)
    assert float(ds["residual"].max()) < 1e-10


def test_critical_speeds_are_sign_changes_refined_to_1e_6(small_map):
    ds = small_map
    n = ds["n_critical"]
    assert int(n.sel(branch="inverted", eps=0.25)) >= 2  # the stable window of the inverted branch
    assert int(n.sel(branch="inverted", eps=0.1)) == 0  # no stable window for mu/eps = 3
    pad = ds["omega_critical"].attrs["padding_value"]
    for b in ds["branch"].values:
        for j, eps in enumerate(EPS):
            k = int(n.sel(branch=b, eps=eps))
            oc = ds["omega_critical"].sel(branch=b, eps=eps).values
            assert np.all(oc[k:] == pad) and np.all(np.diff(oc[:k]) > 0)
            pars = maps._parameter_grid(Setup(), {"eps": [eps]}, 1e-12, (1, 1))[:, 0]
            for om, d in zip(oc[:k], ds["critical_direction"].sel(branch=b, eps=eps).values[:k]):
                below = sb.max_real_eig(str(b), om * (1 - 1e-6), pars)
                above = sb.max_real_eig(str(b), om * (1 + 1e-6), pars)
                assert below * above < 0  # a sign change within 1e-6 relative
                assert d == (1 if above < 0 else -1)
    direct = maps.find_critical_speeds("inverted", OMEGA, setup=Setup(friction=Friction(eps=0.25)))
    k = int(n.sel(branch="inverted", eps=0.25))
    np.testing.assert_allclose([c[0] for c in direct], ds["omega_critical"].sel(branch="inverted", eps=0.25)[:k],
                               rtol=1e-12)
    curves = maps.critical_speed_curves(ds)
    assert set(curves) == {"noninverted", "inverted"}
    assert int(np.isfinite(curves["inverted"]).sum()) == int(n.sel(branch="inverted").sum())


def test_critical_frequency_is_the_crossing_eigenvalue(small_map):
    """critical_frequency = |Im s| of the eigenvalue on the imaginary axis at Omega_c: the Hopf pair's
    frequency, and 0 where a real eigenvalue crosses. Checked with numpy's eigenvalues of the full 7x7
    Jacobian at the stored Omega_c (structural zero included, no deflation or sorting shared with maps)."""
    ds = small_map
    kinds = []
    for b in ds["branch"].values:
        for eps in EPS:
            k = int(ds["n_critical"].sel(branch=b, eps=eps))
            pars = maps._parameter_grid(Setup(), {"eps": [eps]}, 1e-12, (1, 1))[:, 0]
            for om, freq in zip(ds["omega_critical"].sel(branch=b, eps=eps).values[:k],
                                ds["critical_frequency"].sel(branch=b, eps=eps).values[:k]):
                J = reduced.jacobian(st.stationary_state(str(b), [om]), pars)[0]
                ev = np.linalg.eigvals(J)
                on_axis = ev[np.abs(ev.real) < 1e-9 * np.abs(J).max()]
                others = ev[np.abs(ev.real) >= 1e-9 * np.abs(J).max()]
                assert np.all(np.abs(others.real) > 1e-3)  # the crossing is isolated
                if len(on_axis) == 3:  # structural zero and a Hopf pair +-i w
                    w = np.sort(on_axis.imag)
                    assert w[1] == pytest.approx(0.0, abs=1e-9) and w[0] == pytest.approx(-w[2], rel=1e-9)
                    assert freq == pytest.approx(w[2], rel=1e-8) and freq > 1.0
                    kinds.append("hopf")
                else:  # structural zero and the real eigenvalue crossing zero
                    assert len(on_axis) == 2 and np.all(on_axis.imag == 0.0)
                    assert freq == 0.0
                    kinds.append("real")
    assert {"hopf", "real"} <= set(kinds)  # both kinds occur in this map (eps = 0.25, inverted branch)
    pad = ds["crossing"] >= ds["n_critical"]
    assert np.all(ds["critical_frequency"].where(pad, 0.0) == 0.0)  # 0 for padding


def test_netcdf_round_trip(small_map, tmp_path):
    path = results.save(small_map, tmp_path / "map.nc")
    assert_identical(results.load(path), small_map)


def test_extra_sweeps_become_dimensions():
    ds = maps.stability_map([30.0, 31.0], [0.25], mu=[0.2, 0.3], e=[1e-3, 2.5e-3], critical=True)
    assert ds["max_real_eig"].dims == ("branch", "omega", "eps", "mu", "e")
    assert ds["n_critical"].dims == ("branch", "eps", "mu", "e")
    # the linearisation at zero slip depends on mu/eps only
    a = maps.stability_map([30.0], [0.25], mu=[0.3], critical=False)["eig_real"]
    b = maps.stability_map([30.0], [0.5], mu=[0.6], critical=False)["eig_real"]
    np.testing.assert_allclose(a.values, b.values, rtol=1e-10)
    with pytest.raises(ParameterError, match="eccentricity"):
        maps.stability_map([30.0], [0.25], e=[0.05])
    with pytest.raises(ParameterError, match="eps"):
        maps.stability_map([30.0], [-0.1])


def test_cli_writes_map_and_plot(tmp_path, capsys):
    out = tmp_path / "map.nc"
    assert main(["stability-map", "--omega", "25:40:16", "--eps", "0.2:0.3:3", "--output", str(out)]) == 0
    ds = results.load(out)
    assert ds.sizes["omega"] == 16 and ds.sizes["eps"] == 3
    png = tmp_path / "map.png"
    assert main(["plot", str(out), "--output", str(png)]) == 0
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("args", [["--omega", "0:10", "--eps", "0.1:0.2:2"],
                                  ["--omega", "0:10:5", "--eps", "0.1:x:2"],
                                  ["--omega", "0:10:5", "--eps=-1:0.2:2"],
                                  ["--omega", "10:0:5", "--eps", "0.1:0.2:2"]])
def test_cli_bad_input_exits_2_without_file(tmp_path, capsys, args):
    out = tmp_path / "map.nc"
    assert main(["stability-map", *args, "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("tippedisk stability-map: error:") and err.count("\n") == 1
    assert not out.exists()
    assert not list(tmp_path.iterdir())

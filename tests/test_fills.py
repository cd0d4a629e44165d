"""No value that means success is stored where a computation failed (issue 30): a failed flow, an orbit off the
unit circle, a horizontal disk's Euler rates and a chunk of unknown origin are flagged or refused."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import orbits, rolling
from tippedisk_analysis.dynamics import sweeps
from tippedisk_analysis.errors import TippediskWarning


def test_a_failed_flow_has_no_energy_change_of_a_periodic_orbit():
    """A trial orbit whose flow fails over its period had energy_change 0.0, the value of a periodic orbit."""
    failed = dy.find_orbit(dy.textbook_system("vanderpol"), [2.0, 0.0], 6.66)
    failed.status = "nonfinite"
    columns = orbits._energy_columns([failed])
    np.testing.assert_array_equal(columns["energy_change_computed"][1], [0])
    assert "a fill where energy_change_computed = 0" in columns["energy_change"][2]["long_name"]


def test_an_orbit_off_the_unit_circle_has_no_floquet_angle():
    """An unstable (or contracting) orbit had the angle 0, a real resonance value; it is NO_ANGLE, outside
    (0, 1/2]."""
    vdp = dy.textbook_system("vanderpol")
    orbit = dy.find_orbit(vdp, [2.0, 0.0], 6.66)
    assert rolling.floquet_angle(orbit) == rolling.NO_ANGLE and not 0 < rolling.NO_ANGLE <= 0.5


def test_quaternion_moreau_runs_flag_where_euler_rates_exist():
    ds = td.simulate("m2", 0.002)
    flag = ds["euler_rates_defined"]
    assert flag.dtype == np.int8 and set(np.unique(flag.values)) <= {0, 1} and flag.attrs["flag_meanings"] == "no yes"
    assert np.all(flag.values == 1)  # upright at the start: the rates exist


def test_a_chunk_without_a_configuration_fingerprint_is_recomputed(tmp_path):
    path = tmp_path / "chunk_00000.nc"
    xr.Dataset({"v": ("v_0", np.zeros(4))}, attrs={"start": 0, "stop": 4}).to_netcdf(path)
    with pytest.warns(TippediskWarning, match="no configuration fingerprint"):
        assert sweeps._read_chunk(path, 0, 4, ["v"], "abc") is None
    xr.Dataset({"v": ("v_0", np.ones(4))}, attrs={"start": 0, "stop": 4, "config_hash": "abc"}).to_netcdf(
        tmp_path / "ok.nc")
    np.testing.assert_array_equal(sweeps._read_chunk(tmp_path / "ok.nc", 0, 4, ["v"], "abc")["v"], 1.0)

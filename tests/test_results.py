import json

import numpy as np
import pytest
import xarray as xr

import tippedisk_analysis as td
from tippedisk_analysis.defaults import TAYLOR_TOL
from tippedisk_analysis import results
from tippedisk_analysis.solvers import taylor


@pytest.fixture(scope="module")
def short_run():
    return td.simulate("ode-quaternion", 0.2, dt_output=0.01)


def test_netcdf_round_trip_is_identical(short_run, tmp_path):
    path = td.save(short_run, tmp_path / "run.nc")
    xr.testing.assert_identical(td.load(path), short_run)


def test_every_variable_has_units_and_long_name(short_run):
    for name, var in short_run.variables.items():
        assert var.attrs.get("units"), name
        assert var.attrs.get("long_name"), name


def test_attributes_are_netcdf_safe_and_hold_the_configuration(short_run):
    for key, value in short_run.attrs.items():
        assert isinstance(value, str | int | float | np.integer | np.floating), key
    config = results.config_of(short_run)
    assert config["model"] == "ode-quaternion"
    assert config["setup"]["friction"]["eps"] == 0.1
    assert config["initial"]["alpha_dot"] == 40.0
    assert config["integrator"]["tol"] == TAYLOR_TOL
    assert short_run.attrs["producer_version"] == td.__version__
    assert short_run.attrs["status"] == "completed"
    json.dumps(config)


def test_save_refuses_nan_and_writes_nothing(short_run, tmp_path):
    broken = short_run.copy(deep=True)
    broken["gamma"][3] = np.nan
    target = tmp_path / "broken.nc"
    with pytest.raises(td.DatasetError, match="gamma"):
        td.save(broken, target)
    assert list(tmp_path.iterdir()) == []


def test_load_rejects_foreign_files(tmp_path):
    text = tmp_path / "notes.nc"
    text.write_text("not a dataset")
    with pytest.raises(td.DatasetError, match="not a netCDF"):
        td.load(text)
    foreign = tmp_path / "foreign.nc"
    xr.Dataset({"a": ("x", [1.0, 2.0])}).to_netcdf(foreign)
    with pytest.raises(td.DatasetError, match="not written by tippedisk"):
        td.load(foreign)
    with pytest.raises(td.DatasetError, match="does not exist"):
        td.load(tmp_path / "missing.nc")

import json
import os

import numpy as np
import pytest
import xarray as xr

import tippedisk_analysis as td
from tippedisk_analysis.defaults import TAYLOR_TOL
from tippedisk_analysis import results


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


def test_temporary_names_are_unique_per_process_and_call(tmp_path):
    from tippedisk_analysis.files import temporary_name

    a, b = temporary_name(tmp_path / "run.nc"), temporary_name(tmp_path / "run.nc")
    assert a != b and a.parent == tmp_path and a.name.startswith(f".run.nc.{os.getpid()}.") and a.suffix == ".part"


@pytest.mark.parametrize("target, fragment", [("adir", "is a directory"), ("/dev/null", "not a regular file"),
                                              ("missing/run.nc", "does not exist"),
                                              ("/sys/run.nc", "cannot create files")])
def test_save_refuses_paths_it_cannot_write(short_run, tmp_path, target, fragment):
    (tmp_path / "adir").mkdir()
    path = target if target.startswith("/") else tmp_path / target
    with pytest.raises(td.TippediskError, match=fragment) as info:
        td.save(short_run, path)
    assert "--" not in str(info.value)  # API wording; the CLI's is in cli_message()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir"]


def test_save_replaces_unless_told_not_to(short_run, tmp_path):
    path = tmp_path / "run.nc"
    path.write_text("old")
    with pytest.raises(td.TippediskError, match="exists; pass overwrite=True") as info:
        td.save(short_run, path, overwrite=False)
    assert "give --overwrite" in info.value.cli_message()
    assert path.read_text() == "old"
    td.save(short_run, path)  # the Python default replaces, as xarray's to_netcdf does
    xr.testing.assert_identical(td.load(path), short_run)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]


def test_failed_write_leaves_nothing(tmp_path):
    from tippedisk_analysis.files import atomic_write

    def write(tmp):
        tmp.write_text("half")
        raise OSError(28, "No space left on device")

    with pytest.raises(td.TippediskError, match="No space left on device"):
        atomic_write(tmp_path / "x.nc", write)
    assert list(tmp_path.iterdir()) == []


def test_stale_temporary_files_of_dead_processes_are_removed(tmp_path):
    from tippedisk_analysis.files import check_output

    dead = tmp_path / ".run.nc.999999999.deadbeef.part"  # no such pid
    mine = tmp_path / f".run.nc.{os.getpid()}.cafe0123.part"
    dead.write_text("x")
    mine.write_text("x")
    check_output(tmp_path / "run.nc")
    assert not dead.exists() and mine.exists()


def test_load_refuses_directories_and_non_utf8_names(tmp_path):
    with pytest.raises(td.DatasetError, match="is a directory"):
        td.load(tmp_path)
    bad = tmp_path / os.fsdecode(b"\xff.nc")
    bad.write_bytes(b"x")
    with pytest.raises(td.DatasetError, match=r"'.*\\xff.nc' is not a valid UTF-8 file name"):
        td.load(bad)
    with pytest.raises(td.DatasetError, match="give a file name"):
        td.load(3)


def test_datasets_carry_cf_title_history_and_references(tmp_path):
    """CF's title, history (the command that made the file) and references (the paper for the disk's datasets,
    the package for any System's)."""
    import subprocess
    import sys
    from pathlib import Path

    from tippedisk_analysis import dynamics as dy

    exe = Path(sys.executable).with_name("tippedisk")
    subprocess.run([str(exe), "simulate", "--t-end", "0.05", "-o", str(tmp_path / "run.nc")], check=True,
                   capture_output=True)
    ds = td.load(tmp_path / "run.nc")
    assert ds.attrs["title"] == "Simulation of ode-euler (ODE Model 1)"
    assert ds.attrs["history"].startswith("tippedisk simulate --t-end 0.05 -o ")
    assert "doi:10.1134/S1560354720060052" in ds.attrs["references"]
    vdp = dy.textbook_system("vanderpol")
    section = dy.poincare_section(vdp, [2.0, 0.0], vdp.state_names[0], 0.0, t_end=20.0)
    assert section.attrs["title"] == f"Poincare section of {vdp.name}"
    assert section.attrs["references"] == f"tippedisk_analysis {td.__version__}"

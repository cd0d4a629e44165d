"""A full disk while a dataset is written: one line, exit 2, nothing half-written (issue 30). The disk is
made full by the writer: netCDF-C reports it as ``RuntimeError: NetCDF: HDF error``, the OS as ENOSPC."""

from __future__ import annotations

import errno

import pytest
import xarray as xr

from tippedisk_analysis.cli import main

FAILURES = {"hdf": RuntimeError("NetCDF: HDF error"), "enospc": OSError(errno.ENOSPC, "No space left on device")}


@pytest.fixture(params=sorted(FAILURES))
def full_disk(request, monkeypatch):
    def fail(self, path, *args, **kwargs):
        open(path, "wb").write(b"\0" * 64)  # a partial file, as a write that ran out of space leaves
        raise FAILURES[request.param]

    monkeypatch.setattr(xr.Dataset, "to_netcdf", fail)
    return request.param


@pytest.mark.parametrize("argv", [
    ["simulate", "--model", "ode1", "--t-end", "0.01"],
    ["simulate", "--model", "h1", "--t-end", "0.01"],
    ["simulate", "--model", "m1", "--t-end", "0.001"],
    ["stability-map", "--omega", "30:40:2", "--eps", "0.1"],
    ["bifurcation", "--omega", "20:30:4", "--t-end", "1", "--t-transient", "0.5"],  # chunks of a sweep
])
def test_a_full_disk_is_one_line_and_exit_2(tmp_path, capsys, full_disk, argv):
    out = tmp_path / "out.nc"
    assert main([*argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write" in err[0] and ("full" in err[0])
    assert list(tmp_path.iterdir()) == []  # no output, no temporary


def test_a_study_on_a_full_disk_leaves_no_output_folder(tmp_path, capsys, full_disk):
    out = tmp_path / "study"
    assert main(["study", "rolling", "--quick", "--output-dir", str(out)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not out.exists()

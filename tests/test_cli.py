import pytest

import tippedisk_analysis as td
from tippedisk_analysis.cli import main


def test_simulate_then_plot(tmp_path, capsys):
    out = tmp_path / "run.nc"
    assert main(["simulate", "--model", "ode1", "--t-end", "0.3", "--dt-output", "0.01", "--alpha-dot", "45",
                 "--gamma0", "-1.4", "--mu", "0.25", "--eps", "0.05", "--output", str(out)]) == 0
    ds = td.load(out)
    assert ds.attrs["model"] == "ode-euler"
    assert float(ds.alpha_dot[0]) == pytest.approx(45.0)
    assert float(ds.gamma[0]) == pytest.approx(-1.4)
    config = td.results.config_of(ds)
    assert (config["setup"]["friction"]["mu"], config["setup"]["friction"]["eps"]) == (0.25, 0.05)
    assert "completed" in capsys.readouterr().out
    png = tmp_path / "run.png"
    assert main(["plot", str(out), "--output", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--radius", "-0.045"], "radius"),
        (["--e", "0.05"], "not smaller than the radius"),
        (["--eps", "0"], "eps"),
        (["--model", "ode7"], "unknown model"),
        (["--t-end", "-1"], "t_end"),
        (["--dt-output", "0"], "dt_output"),
        (["--alpha-dot", "fast"], "not a number"),
    ],
)
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, args, fragment):
    out = tmp_path / "run.nc"
    assert _exit_code(["simulate", "--t-end", "0.1", "--output", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_plot_rejects_foreign_file(tmp_path, capsys):
    bogus = tmp_path / "bogus.nc"
    bogus.write_text("hello")
    assert main(["plot", str(bogus)]) == 2
    assert "not a netCDF" in capsys.readouterr().err
    assert not (tmp_path / "bogus.png").exists()


def _exit_code(argv):
    """main's return value, or the status of argparse's SystemExit."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def test_plot_rejects_damaged_dataset_and_unknown_format(tmp_path, capsys):
    import xarray as xr

    fake = tmp_path / "fake.nc"
    xr.Dataset({"a": ("x", [1.0])}, attrs={"producer": "tippedisk_analysis", "kind": "simulation"}).to_netcdf(fake)
    assert main(["plot", str(fake)]) == 2
    assert "damaged or not one of ours" in capsys.readouterr().err
    run = tmp_path / "run.nc"
    assert main(["simulate", "--t-end", "0.05", "--output", str(run)]) == 0
    assert main(["plot", str(run), "--output", str(tmp_path / "run.txt")]) == 2
    assert "cannot draw to '.txt'" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fake.nc", "run.nc"]


@pytest.mark.parametrize("args, fragment", [(["--fall-angle", "0"], "fall_angle"), (["--tol", "1"], "tol")])
def test_numerical_options_are_validated(tmp_path, capsys, args, fragment):
    out = tmp_path / "run.nc"
    assert main(["simulate", "--t-end", "0.1", "--output", str(out), *args]) == 2
    assert fragment in capsys.readouterr().err
    assert not out.exists()


def test_range_errors_name_the_option(tmp_path, capsys):
    out = tmp_path / "map.nc"
    assert _exit_code(["outcome-map", "--omega", "10:80", "--eps", "0.1:0.2:2", "--output", str(out)]) == 2
    assert "--omega '10:80' is not START:STOP:N" in capsys.readouterr().err
    assert not out.exists()

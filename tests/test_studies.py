import pytest

import tippedisk_analysis as td
from tippedisk_analysis import studies
from tippedisk_analysis.cli import main


def test_study_list_names_the_scripts(capsys):
    assert main(["study", "--list"]) == 0
    listed = capsys.readouterr().out.split()
    assert listed == studies.names()
    assert {"fig13_ode_inversion", "fig17_stroboscope"} <= set(listed)


def test_fig17_study_writes_dataset_and_figure(tmp_path):
    path = studies.run("fig17_stroboscope", str(tmp_path))
    ds = td.load(path)
    disk = td.Disk()
    assert float(ds.alpha_dot[0]) == pytest.approx(-50.0)
    assert float(ds.z_S[-1]) > disk.r + 0.9 * disk.e  # inverted: S well above G
    assert path.with_suffix(".png").stat().st_size > 10_000


def test_unknown_study_is_a_clear_error(capsys):
    assert main(["study", "fig99"]) == 2
    assert "unknown study 'fig99'" in capsys.readouterr().err

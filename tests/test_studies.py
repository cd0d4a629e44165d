import pytest

import tippedisk_analysis as td
from tippedisk_analysis.cli import main, study

STUDIES = study.names()
SLOW_STUDIES = {"basins", "continuation", "critical_spin", "fig09_10_coulomb_contensou", "held_spin", "highest_point",
                "lyapunov_map",
                "free_nutation", "lower_spin_homoclinic", "nutation_cycles", "periodic_orbits", "rolling"}  # > 1 s


def test_study_list_names_every_study_with_its_summary(capsys):
    assert main(["study", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == STUDIES
    assert {"fig13_ode_inversion", "fig17_stroboscope", "stability_map"} <= set(STUDIES)
    assert all(len(line.split()) > 1 for line in lines)  # every study has a docstring summary


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow) if name in SLOW_STUDIES else name
                                  for name in STUDIES])
def test_every_study_runs_at_reduced_size(name, tmp_path):
    """Each study (``--quick``) writes datasets of ours and figures."""
    assert main(["study", name, "--quick", "--output-dir", str(tmp_path)]) == 0
    datasets, figures = sorted(tmp_path.glob("*.nc")), sorted(tmp_path.glob("*.png"))
    assert datasets and figures
    for path in datasets:
        td.load(path)  # raises unless it is a complete dataset of ours
    assert all(f.stat().st_size > 10_000 for f in figures)


def test_fig17_study_inverts_the_disk(tmp_path):
    path = study.run("fig17_stroboscope", str(tmp_path))
    ds = td.load(path)
    disk = td.Disk()
    assert float(ds.alpha_dot[0]) == pytest.approx(-50.0)
    assert float(ds.z_S[-1]) > disk.r + 0.9 * disk.e  # inverted: S well above G


def test_unknown_study_is_a_clear_error(capsys):
    assert main(["study", "fig99"]) == 2
    assert "unknown study 'fig99'" in capsys.readouterr().err


@pytest.mark.slow
def test_the_highest_point_study_resumes_from_the_curves_it_finished(tmp_path, capsys):
    """A second run reads each finished curve (same configuration) instead of rerunning it; a curve whose file is
    gone is computed again."""
    assert main(["study", "highest_point", "--quick", "--output-dir", str(tmp_path)]) == 0
    first = capsys.readouterr().out
    kept = tmp_path / "highest_point_eps0.1.nc"
    stamp = kept.stat().st_mtime_ns
    (tmp_path / "highest_point_drilled_e1.5mm.nc").unlink()
    assert main(["study", "highest_point", "--quick", "--output-dir", str(tmp_path)]) == 0
    second = capsys.readouterr().out
    assert "read (same configuration)" not in first
    assert "highest_point_eps0.1.nc: read (same configuration)" in second and kept.stat().st_mtime_ns == stamp
    assert "highest_point_drilled_e1.5mm.nc: read" not in second
    assert (tmp_path / "highest_point_drilled_e1.5mm.nc").exists()
    assert td.load(kept).height.size == 9

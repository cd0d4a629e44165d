"""The Sect. 6 table of studies/README.md and docs/paper.md is true: recomputed here from the stored study datasets.

data/sect6/ holds the compact copies of the runs of ``tippedisk study sect6_table`` (the full-length runs take
about 10 s; regenerate them with that study and copy sect6_*.nc to data/sect6/). This test

* recomputes every row of the table from those datasets (and data/fig13_ode_inversion.nc,
  data/fig17_stroboscope.nc) and requires the tables in studies/README.md and docs/paper.md to equal the result,
* recomputes the key numbers a second time with plain numpy, not through the study's measures,
* re-simulates the first 0.3 s of every stored run with the current code and requires the stored samples to
  match, so the stored datasets cannot silently describe an older version of the models,
* (slow) re-simulates every run over its whole window (1 to 25 s, about 20 s in all) and requires the table
  computed from the fresh runs to equal the stored one, row by row, with h1's switches to round-off.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from tippedisk_studies import sect6_table

import tippedisk_analysis as td
from tippedisk_analysis.results import config_of

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "data"


@pytest.fixture(scope="module")
def runs():
    return sect6_table.load_runs(DATA / "sect6")


def _rows(runs):
    return sect6_table.table_rows(runs, td.load(DATA / "fig13_ode_inversion.nc"), td.load(DATA / "fig17_stroboscope.nc"),
                                  td.load(DATA / "rolling" / "rolling_orbit.nc"))


@pytest.fixture(scope="module")
def rows(runs):
    return _rows(runs)


def _block(path: Path, name: str) -> str:
    text = path.read_text()
    match = re.search(rf"<!-- {name}:begin -->\n(.*?)\n<!-- {name}:end -->", text, re.S)
    assert match, f"{path.name} has no <!-- {name}:begin/end --> block"
    return match.group(1).strip()


def test_studies_readme_table_equals_the_recomputed_table(rows):
    expected = sect6_table.markdown(rows) + "\n\n" + sect6_table.summary(rows)
    assert _block(ROOT / "studies" / "README.md", "sect6-table") == expected


def test_site_summary_equals_the_recomputed_table(rows):
    expected = sect6_table.summary(rows) + "\n\n" + sect6_table.markdown_short(rows)
    assert _block(ROOT / "docs" / "paper.md", "sect6-summary") == expected
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert sect6_table.summary(rows) in readme  # the landing page's one-line summary


def test_every_row_has_a_verdict_and_each_verdict_occurs(rows):
    assert len(rows) >= 40
    assert {r.verdict for r in rows} <= set(sect6_table.VERDICTS)
    assert {"reproduced", "partly", "not reproduced"} <= {r.verdict for r in rows}


def _amp(ds, t0, t1):
    t = ds.time.values
    g = ds.gamma.values[(t >= t0 - 1e-9) & (t <= t1 + 1e-9)]
    return 0.5 * (g.max() - g.min())


def test_key_numbers_recomputed_with_plain_numpy(runs):
    """The table's central numbers once more, straight from the arrays."""
    t = runs["m1"].time.values
    z = runs["m1"].z_S.values[(t >= 1) & (t <= 5)]
    assert 0.043 <= z.mean() <= 0.045  # Sect. 6.1: about 0.044 m
    law, variant = runs["m3_law"], runs["m3_variant"]
    assert _amp(law, 4, 5) > 0.9 * _amp(law, 1, 2)  # the law as stated: no damping (ratio 0.99)
    assert _amp(variant, 4, 5) < 0.5 * _amp(variant, 1, 2)  # the variant: Fig. 9's damping (0.19)
    m6, ode2 = runs["m6"], runs["ode2"]
    first = m6.time.values <= 1.0 + 1e-9
    np.testing.assert_allclose(m6.time.values[first], ode2.time.values[first], atol=1e-9)
    assert np.max(np.abs(m6.gamma.values[first] - ode2.gamma.values[first])) <= 1.2e-3  # 1.03e-3 rad
    g = runs["m4_variant"].g_N1.sel(time=5.0, method="nearest")
    assert -1.6e-5 < float(g) < -1.0e-5  # Fig. 10: -1.36e-5 m; the variant -1.18e-5 m


@pytest.mark.parametrize("key", list(sect6_table.RUNS))
def test_stored_runs_match_the_current_code(runs, key):
    """The first 0.3 s of each stored run, re-simulated now, equal the stored samples (float32), and the stored
    configuration is the one the study asks for."""
    model, _t_end, options = sect6_table.RUNS[key]
    fresh = sect6_table.compact(td.simulate(model, 0.3, **options))
    stored = runs[key].sel(time=slice(0.0, 0.3 + 1e-9))
    assert fresh.sizes["time"] == stored.sizes["time"] == 301 + (key == "h1")  # h1: + the slip onset's instant
    assert config_of(stored)["setup"] == config_of(fresh)["setup"]
    assert {k: v for k, v in config_of(stored)["integrator"].items() if k != "t_end"} == \
        {k: v for k, v in config_of(fresh)["integrator"].items() if k != "t_end"}
    for name in fresh.data_vars:  # quantities at round-off (g_N1 of the ODE models: zero by construction) meet 1e-15
        scale = max(float(np.max(np.abs(stored[name].values))), 1e-9)
        np.testing.assert_allclose(stored[name].values, fresh[name].values, rtol=1e-5, atol=1e-6 * scale, err_msg=name)


def test_fig17_dataset_covers_the_whole_inversion():
    ds = td.load(DATA / "fig17_stroboscope.nc")
    assert float(ds.alpha_dot[0]) == pytest.approx(-50.0)
    reached = ds.time.values[ds.gamma.values >= math.pi / 2]
    assert reached.size and 1.2 < reached[0] < 1.4 < float(ds.time[-1])  # gamma reaches pi/2 at 1.29 s


H1_SWITCHES = (0.28891781720413595, 0.42827936187968546)  # slip onset, stick (docs/rolling.md)


@pytest.mark.slow
def test_every_verdict_holds_on_fresh_runs(tmp_path, rows):
    """The whole table from runs made now (the study's own simulate_runs, full length), not from data/."""
    fresh = sect6_table.simulate_runs(tmp_path)
    assert _rows(fresh) == rows
    h1 = td.simulate("h1", 1.0)
    np.testing.assert_allclose(h1["switch_time"].values[1:], H1_SWITCHES, rtol=0, atol=1e-9)


def test_a_number_that_is_not_finite_is_an_error_not_a_verdict(runs):
    """A NaN used to fail its comparison and become 'not reproduced' (warnings suppressed)."""
    short = dict(runs, m10=runs["m10"].sel(time=slice(0.0, 3.0)))  # no [4, 5] s window: amplitudes are NaN
    with pytest.raises(ValueError, match="not finite"):
        _rows(short)

"""Poincaré sections and the brute-force bifurcation diagram (analysis/poincare.py, bifurcation.py)."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import xarray as xr

from tippedisk_analysis import ParameterError, load, save
from tippedisk_analysis.analysis import poincare
from tippedisk_analysis.analysis.bifurcation import bifurcation_diagram
from tippedisk_analysis.cli import main
from tippedisk_analysis.parameters import InitialState, Setup
from tippedisk_analysis.models import ode
from tippedisk_analysis.solvers import taylor

TOL = 1e-12  # one tolerance for the whole file: each compiled integrator is built once


@pytest.fixture(scope="module")
def beta_section():
    return poincare.poincare_section("beta_dot=0", t_end=3.0, tol=TOL)


def test_crossings_lie_on_the_section(beta_section):
    ds = beta_section
    assert ds.sizes["crossing"] >= 5 and int(ds["n_crossings"]) == ds.sizes["crossing"]
    scale = float(np.max(np.abs(ds["gamma_dot"])))  # the rates are of order |Omega|
    assert np.max(np.abs(ds["beta_dot"])) < 1e-10 * max(scale, 1.0)
    assert np.all(np.diff(ds["time"]) > 0)


def test_crossing_states_match_a_second_integration(beta_section):
    """Integrate again with the plain solver up to each crossing time: same state."""
    cm = taylor.compiled("ode-euler", TOL)
    setup, initial = Setup(), InitialState()
    names = cm.model.state_names
    for k in (0, beta_section.sizes["crossing"] // 2, -1):
        t_k = float(beta_section["time"][k])
        ta = copy.copy(cm.integrator)
        ta.pars[:] = ode.parameter_vector(setup)
        ta.time = 0.0
        ta.state[:] = ode.initial_state_vector(cm.model, setup, initial)
        ta.reset_cooldowns()
        ta.propagate_until(t_k)
        expected = np.asarray(ta.state)
        got = np.array([float(beta_section[n][k]) for n in names])
        np.testing.assert_allclose(got, expected, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("direction", ["positive", "negative"])
def test_direction_transient_and_count(direction):
    ds = poincare.poincare_section("gamma=pi/2", direction=direction, t_transient=0.5, t_end=4.0,
                                   max_crossings=2, tol=TOL)
    assert ds.sizes["crossing"] == 2 and ds.attrs["status"] == "completed"
    assert np.all(ds["time"] >= 0.5)
    np.testing.assert_allclose(ds["gamma"], math.pi / 2, atol=1e-10)
    sign = 1 if direction == "positive" else -1
    assert np.all(sign * ds["gamma_dot"] > 0)


def test_alpha_modulo_section():
    ds = poincare.poincare_section("alpha mod 2pi=1", t_end=0.6, tol=TOL)
    assert ds.sizes["crossing"] >= 2
    np.testing.assert_allclose(np.sin(ds["alpha"] - 1.0), 0.0, atol=1e-10)
    assert np.all(np.cos(ds["alpha"] - 1.0) > 0)  # alpha = 1 + 2 pi k, not 1 + pi
    assert np.all(ds["alpha_dot"] > 0)  # Omega > 0: alpha increases through the section


def test_netcdf_round_trip(beta_section, tmp_path):
    save(beta_section, tmp_path / "p.nc")
    xr.testing.assert_identical(load(tmp_path / "p.nc"), beta_section)


def test_empty_section_round_trip(tmp_path):
    ds = poincare.poincare_section("gamma=pi/2", t_end=0.05, tol=TOL)  # no inversion yet
    assert ds.sizes["crossing"] == 0 and int(ds["n_crossings"]) == 0
    save(ds, tmp_path / "e.nc")
    assert load(tmp_path / "e.nc").sizes["crossing"] == 0


@pytest.mark.parametrize("spec", ["beta_dot", "nonsense=0", "gamma=pi/", "gamma=1=2", "gamma=inf"])
def test_bad_section_raises(spec):
    with pytest.raises(ParameterError):
        poincare.parse_section(spec)


def test_cli_bad_section_exits_2_without_file(tmp_path, capsys):
    out = tmp_path / "p.nc"
    assert main(["poincare", "--section", "nonsense=0", "-o", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "choose one of" in err


def test_bifurcation_diagram(tmp_path):
    ds = bifurcation_diagram((40.0, 60.0, 3), t_transient=1.0, t_end=2.5, max_crossings=4, tol=TOL, progress=False)
    assert ds.sizes["omega"] == 3
    assert int(ds["n_crossings"].sum()) == ds.sizes["point"]
    assert set(np.unique(ds["omega_of_point"])) <= set(ds["omega"].values)
    assert np.all(ds["time"] >= 1.0)
    assert np.all(np.abs(ds["value"]) <= math.pi)
    # spun as in Table 3 the disk has inverted by t = 1 s (Fig. 13): S above G, gamma in (0, pi)
    assert np.all(np.sin(ds["value"]) > 0.5)
    save(ds, tmp_path / "b.nc")
    xr.testing.assert_identical(load(tmp_path / "b.nc"), ds)


def test_quaternion_model_finds_the_same_crossings():
    """ODE Model 2 (quaternions, wrapped gamma: a mod-2pi section) against ODE Model 1 (unwrapped gamma)."""
    quat = poincare.poincare_section("gamma mod 2pi=pi/2", model="ode-quaternion", t_end=2.0, tol=TOL)
    euler = poincare.poincare_section("gamma=pi/2", model="ode-euler", t_end=2.0, tol=TOL)
    assert quat.sizes["crossing"] == euler.sizes["crossing"] >= 1
    np.testing.assert_allclose(quat["time"], euler["time"], rtol=1e-7)
    np.testing.assert_allclose(quat["beta"], euler["beta"], atol=1e-7)


def test_sections_and_diagrams_flag_runs_whose_normal_force_turns_negative():
    """A fast spin (300 rad/s) makes lambda_N negative: the section says so, the diagram counts it as partial."""
    fast = poincare.poincare_section("beta_dot=0", initial=InitialState(alpha_dot=300.0), t_end=0.5, tol=TOL)
    assert fast.attrs["valid"] == 0 and 0 < fast.attrs["lift_off_time"] < 0.5
    assert "lambda_N < 0 from t =" in fast.attrs["message"]
    calm = poincare.poincare_section("beta_dot=0", t_end=0.5, tol=TOL)
    assert calm.attrs["valid"] == 1 and "lift_off_time" not in calm.attrs
    ds = bifurcation_diagram([40.0, 300.0], t_transient=0.1, t_end=0.5, max_crossings=2, tol=TOL, progress=False)
    assert list(ds["valid"].values) == [1, 0] and ds.attrs["status"] == "partial"
    assert "1 with lambda_N < 0" in ds.attrs["message"]

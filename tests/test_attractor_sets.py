"""Attractors compared as sets (:mod:`tippedisk_analysis.dynamics.attractors.sets`), and conservative flows, which
have no attractors: concentric cycles and the two responses of a forced Duffing oscillator share a centre but are
two attractors each with its own basin (references: the exact radii, scipy's DOP853 at 1e-10); Henon-Heiles and a
Lotka-Volterra centre preserve phase-space volume and get the status ``conservative``, dissipative systems keep
their attractors."""

from __future__ import annotations

import math

import heyoka as hy
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics import attractors as at
from tippedisk_analysis.dynamics.attractors import conservative, system_problem

x, y, u, w, px, py = hy.make_vars("x", "y", "u", "w", "px", "py")
PERIODIC = 1


def rings() -> dy.System:
    """r' = r g(r^2), g = -(r^2 - 1)(r^2 - 4)(r^2 - 9), theta' = 1: stable cycles r = 1 and r = 3, unstable r = 2."""
    r2 = x * x + y * y
    g = -(r2 - 1) * (r2 - 4) * (r2 - 9)
    return dy.System("rings", [x, y], [x * g - y, y * g + x])


def forced_duffing(force: float = 0.3, omega: float = 1.34) -> dy.System:
    """x'' + 0.2 x' + x + x^3 = F u with (u, w) a stable phase oscillator: u = cos(omega t) from (u, w) = (1, 0)."""
    return dy.System("forced_duffing", [x, y, u, w],
                     [y, -0.2 * y - x - x**3 + hy.par[0] * u, u + hy.par[1] * w - u * (u * u + w * w),
                      w - hy.par[1] * u - w * (u * u + w * w)], parameters={"F": force, "omega": omega})


DUFFING_GRID = dy.Grid(("x", "y", "u", "w"), (-4, -5, -1.5, -1.5), (4, 5, 1.5, 1.5), (80, 100, 30, 30))


def duffing_reference(force: float, omega: float, starts: np.ndarray, periods: int = 60) -> np.ndarray:
    """max |x| over the last two forcing periods of scipy's runs of x'' + 0.2 x' + x + x^3 = F cos(omega t) from
    ``starts`` (2, N), all in one vectorised DOP853 run at 1e-10."""
    n = starts.shape[1]

    def rhs(t, s):
        return np.concatenate([s[n:], -0.2 * s[n:] - s[:n] - s[:n] ** 3 + force * np.cos(omega * t)])

    period = 2 * math.pi / omega
    run = solve_ivp(rhs, (0.0, periods * period), starts.ravel(), method="DOP853", rtol=1e-10, atol=1e-10,
                    t_eval=np.linspace((periods - 2) * period, periods * period, 801))
    return np.abs(run.y[:n]).max(axis=1)


def test_concentric_cycles_are_two_attractors_with_the_radius_as_their_basin_boundary():
    """Both cycles have period 2 pi and centre 0: before, one attractor held every start. Now r < 2 goes to the
    cycle r = 1 and r > 2 to r = 3, each cycle's points on its circle."""
    axes = {"x": (-3.5, 3.5, 14), "y": (-3.5, 3.5, 14)}
    ds = dy.basins(rings(), dy.Grid(("x", "y"), (-4, -4), (4, 4), (80, 80)), axes, horizon=200.0, progress=False)
    assert ds.attrs["status"] == "completed" and ds.sizes["attractor"] == 2
    assert np.all(ds.attractor_kind.values == PERIODIC)
    np.testing.assert_allclose(ds.attractor_period.values, 2 * math.pi, rtol=1e-9)
    radius = np.hypot(ds.attractor_set.values[..., 0], ds.attractor_set.values[..., 1])  # (attractor, point)
    inner = int(np.argmin(radius.mean(axis=1)))
    np.testing.assert_allclose(radius[inner], 1.0, atol=1e-8)
    np.testing.assert_allclose(radius[1 - inner], 3.0, atol=1e-8)
    X, Y = np.meshgrid(np.linspace(*axes["x"]), np.linspace(*axes["y"]), indexing="ij")
    expected = np.where(np.hypot(X, Y) < 2.0, inner, 1 - inner)
    np.testing.assert_array_equal(ds.outcome.values, expected)


@pytest.mark.parametrize("cells", [(80, 100, 30, 30), (40, 50, 15, 15)])
def test_forced_duffing_small_and_large_responses_have_their_own_basins(cells):
    """F = 0.3, omega = 1.34: two stable responses of the forcing period (max |x| 1.09184 and 0.42056), 61 % / 39 %
    of 21 x 21 starts in (x, x') in [-3, 3]^2; every start's attractor is the one scipy's run from it ends on."""
    axes = {"x": (-3.0, 3.0, 21), "y": (-3.0, 3.0, 21)}
    grid = dy.Grid(DUFFING_GRID.names, DUFFING_GRID.lower, DUFFING_GRID.upper, cells)
    ds = dy.basins(forced_duffing(), grid, axes, state=[0, 0, 1, 0], horizon=300.0, progress=False)
    assert ds.attrs["status"] == "completed" and ds.sizes["attractor"] == 2
    assert np.all(ds.attractor_kind.values == PERIODIC)
    np.testing.assert_allclose(ds.attractor_period.values, 2 * math.pi / 1.34, rtol=1e-9)
    large = int(np.argmax(ds.attractor_amplitude.values))
    np.testing.assert_allclose(ds.attractor_amplitude.values[[large, 1 - large]], [1.09184, 0.42056], atol=2e-4)
    X, V = np.meshgrid(np.linspace(*axes["x"]), np.linspace(*axes["y"]), indexing="ij")
    reference = duffing_reference(0.3, 1.34, np.array([X.ravel(), V.ravel()])).reshape(X.shape)
    np.testing.assert_array_equal(ds.outcome.values == large, reference > 0.75)
    assert float(ds.basin_fraction[large]) == pytest.approx(0.61, abs=0.005)


def test_sets_distinguish_closed_curves_of_one_centre_and_join_two_samplings_of_one():
    """Two samplings of the unit circle (shifted phases) are one attractor; circles of radius 1 and 1.2 on a grid
    of 0.05-wide cells are two, at Hausdorff distance 0.2 / 0.05 = 4 cells; so are periods 2 pi and 4 pi."""
    grid = at.Grid(("x", "y"), (-2, -2), (2, 2), (80, 80))
    phase = np.linspace(0, 2 * math.pi, 64, endpoint=False)

    def cycle(r, shift=0.0, period=2 * math.pi):
        points = r * np.array([np.cos(phase + shift), np.sin(phase + shift)])
        return at.Description("periodic", points[:, 0], np.zeros(2), np.full(2, r), r, period, points=points)

    assert at.sets.same_set(grid, cycle(1.0), cycle(1.0, 0.05), 1.5)
    assert not at.sets.same_set(grid, cycle(1.0), cycle(1.2), 1.5)
    assert at.sets.set_distance(grid, cycle(1.0), cycle(1.2)) == pytest.approx(4.0, rel=1e-3)
    assert not at.sets.same_set(grid, cycle(1.0), cycle(1.0, period=4 * math.pi), 1.5)


def henon_heiles(integral: bool = True) -> dy.System:
    """H = (px^2 + py^2 + x^2 + y^2) / 2 + x^2 y - y^3 / 3: bounded motion below the escape energy 1/6."""
    energy = (px * px + py * py + x * x + y * y) / 2 + x * x * y - y * y * y / 3
    return dy.System("henon_heiles", [x, y, px, py], [px, py, -x - 2 * x * y, -y - x * x + y * y],
                     integrals={"H": energy} if integral else None)


HH_GRID = dy.Grid(("x", "y", "px", "py"), (-1, -1, -1, -1), (1, 1.5, 1, 1), (20, 25, 20, 20))
HH_AXES = {"x": (-0.3, 0.3, 11), "y": (-0.3, 0.3, 11)}


@pytest.mark.parametrize("integral", [True, False])
def test_henon_heiles_is_conservative_with_no_attractors_and_the_energy_of_each_start(integral):
    """Before: three irregular 'attractors' (0.752 / 0.198 / 0.050) holding starts of different energies, the
    resting start on the centre among them. Now the status says conservative, the table is empty, every start is
    bounded (H < 1/6), and the stored level is H at the start (exact formula), conserved along the run."""
    ds = dy.basins(henon_heiles(integral), HH_GRID, HH_AXES, horizon=200.0, progress=False)
    assert ds.attrs["status"] == "conservative" and "no attractors" in ds.attrs["message"]
    assert "\n" not in ds.attrs["message"] and ds.sizes["attractor"] == 0
    flags = dict(zip(ds.outcome.attrs["flag_meanings"].split(), ds.outcome.attrs["flag_values"]))
    assert np.all(ds.outcome.values == flags["bounded"])
    np.testing.assert_allclose(ds.assignment_time.values, 200.0)
    assert np.all(ds.divergence_mean.values == 0.0)
    if integral:
        X, Y = np.meshgrid(np.linspace(*HH_AXES["x"]), np.linspace(*HH_AXES["y"]), indexing="ij")
        energy = (X**2 + Y**2) / 2 + X**2 * Y - Y**3 / 3
        np.testing.assert_allclose(ds.integral_level.sel(integral="H").values, energy, rtol=1e-14, atol=1e-16)
        assert float(ds.integral_drift.max()) < 1e-9
    else:
        assert "integral_level" not in ds


def test_henon_heiles_starts_above_the_escape_energy_diverge_and_their_batch_mates_stay_bounded():
    """Starts with px = py = 0.1 over (x, y) in [-0.4, 0.4]^2: four corners lie above the escape energy 1/6 and blow
    up in finite time (scipy: |x| + |y| passes 10 within 30 time units); every other start stays bounded to t = 300.
    A run that escapes ends the batch's integration for the runs beside it: those are run again, never `failed`."""
    axes = {"x": (-0.4, 0.4, 11), "y": (-0.4, 0.4, 11)}
    ds = dy.basins(henon_heiles(), dy.Grid(("x", "y", "px", "py"), (-1, -1, -1, -1), (1, 1, 1, 1), (40, 40, 40, 40)),
                   axes, state=[0, 0, 0.1, 0.1], horizon=300.0, progress=False)
    flags = dict(zip(ds.outcome.attrs["flag_meanings"].split(), ds.outcome.attrs["flag_values"]))

    def escape(t, s):
        return abs(s[0]) + abs(s[1]) - 10.0
    escape.terminal = True
    expected = np.full((11, 11), flags["bounded"])
    for i, x0 in enumerate(np.linspace(*axes["x"])):
        for j, y0 in enumerate(np.linspace(*axes["y"])):
            run = solve_ivp(lambda t, s: [s[2], s[3], -s[0] - 2 * s[0] * s[1], -s[1] - s[0] ** 2 + s[1] ** 2],
                            (0.0, 30.0), [x0, y0, 0.1, 0.1], method="DOP853", rtol=1e-10, atol=1e-12, events=escape)
            if run.status == 1:
                expected[i, j] = flags["diverged"]
    assert (expected == flags["diverged"]).sum() == 4
    np.testing.assert_array_equal(ds.outcome.values, expected)


def test_lotka_volterra_centre_is_conservative_though_its_divergence_is_not_zero_pointwise():
    """x' = x (1 - y), y' = y (x - 1): div f = x - y, zero only on average over an orbit (d/dt log(x y)); the levels
    of V = x - log x + y - log y are those of the starts."""
    v = x - hy.log(x) + y - hy.log(y)
    s = dy.System("lotka_volterra", [x, y], [x * (1 - y), y * (x - 1)], integrals={"V": v})
    axes = {"x": (0.3, 2.5, 8), "y": (0.3, 2.5, 8)}
    ds = dy.basins(s, dy.Grid(("x", "y"), (0, 0), (8, 8), (80, 80)), axes, horizon=300.0, progress=False)
    assert ds.attrs["status"] == "conservative" and ds.sizes["attractor"] == 0
    X, Y = np.meshgrid(np.linspace(*axes["x"]), np.linspace(*axes["y"]), indexing="ij")
    np.testing.assert_allclose(ds.integral_level.sel(integral="V").values, X - np.log(X) + Y - np.log(Y),
                               rtol=1e-14)


@pytest.mark.parametrize("delta", [1e-3, 0.02])
def test_a_weakly_damped_oscillator_keeps_its_attractor(delta):
    """x'' + delta x' + x = 0: the divergence is -delta everywhere, with no scatter: never conservative, however
    small delta; the origin is the one attractor."""
    s = dy.System("damped", [x, y], [y, -hy.par[0] * y - x], parameters={"delta": delta})
    volume = conservative.volume_test(system_problem.SystemProblem(s, dy.Grid(("x", "y"), (-3, -3), (3, 3),
                                                                                      (60, 60))),
                                         at.RecurrenceSettings(horizon=100.0), {"x": (-2.0, 2.0, 9)}, [0.0, 0.0],
                                         s.pars, 4)
    assert not volume.conservative
    np.testing.assert_allclose(volume.divergence, -delta, rtol=1e-9)


def test_a_volume_test_too_short_for_its_runs_does_not_decide():
    """Runs shorter than the blocks' two correlation times tell nothing: the test is undecided (not conservative),
    and says so."""
    s = dy.System("lotka_volterra", [x, y], [x * (1 - y), y * (x - 1)])
    volume = conservative.volume_test(system_problem.SystemProblem(s, dy.Grid(("x", "y"), (0, 0), (8, 8),
                                                                                      (80, 80))),
                                         at.RecurrenceSettings(horizon=10.0), {"x": (0.3, 2.5, 8)}, [0.0, 1.0],
                                         s.pars, 4)
    assert not volume.conservative and "could not decide" in volume.message


PROJECTIONS = {"x, y": dy.Grid(("x", "y"), (-4, -5), (4, 5), (80, 100)),
               "x, y, u": dy.Grid(("x", "y", "u"), (-4, -5, -1.5), (4, 5, 1.5), (80, 100, 30)),
               "x, u": dy.Grid(("x", "u"), (-4, -1.5), (4, 1.5), (80, 30)),
               # coarse: a window that the periodic check does not close has one neutral exponent, not two (it
               # was taken for a third, irregular attractor holding 90 starts)
               "x, y coarse": dy.Grid(("x", "y"), (-4, -5), (4, 5), (40, 50))}


@pytest.mark.parametrize("name", list(PROJECTIONS))
def test_forced_duffing_on_a_grid_that_misses_states_assigns_every_start_as_scipy(name):
    """Grids over (x, y), (x, y, u), (x, u): the two responses cross in the projection. Before: (x, y) gave 0.90 /
    0.10 (130 of 441 starts wrong), (x, u) one attractor, both `completed`. Now an assignment by cells holds only
    where the run's full state is near the attractor's (Description.state_points): every start as scipy's run."""
    axes = {"x": (-3.0, 3.0, 21), "y": (-3.0, 3.0, 21)}
    ds = dy.basins(forced_duffing(), PROJECTIONS[name], axes, state=[0, 0, 1, 0], horizon=300.0, progress=False)
    assert ds.attrs["status"] == "completed" and ds.sizes["attractor"] == 2 and ds.attrs["undecided"] == 0
    large = int(np.argmax(ds.attractor_amplitude.values))
    np.testing.assert_allclose(ds.attractor_amplitude.values[[large, 1 - large]], [1.09184, 0.42056], atol=3e-4)
    X, V = np.meshgrid(np.linspace(*axes["x"]), np.linspace(*axes["y"]), indexing="ij")
    reference = duffing_reference(0.3, 1.34, np.array([X.ravel(), V.ravel()])).reshape(X.shape)
    np.testing.assert_array_equal(ds.outcome.values == large, reference > 0.75)


def test_an_assignment_needs_the_full_state_near_the_attractor_in_each_state_scaled_by_its_width():
    """The orbit (x, y, u) = (cos s, sin s, cos s) on a grid over (x, y) of 0.1-wide cells: it spans 20 cells, u
    spans 2, so a cell of u is 2 / 20 = 0.1 wide; at (1, 0, 1) a state with u 0.1 higher passes (gap 1 <= 1.5 plus half
    a step), 0.3 off fails (gap 3). An equilibrium has no extent: u's width is the finest observed cell (0.1)."""
    from tippedisk_analysis.dynamics.attractors import confirm

    class Projection(at.Problem):
        state_names = ("x", "y", "u")
        grid = at.Grid(("x", "y"), (-2, -2), (2, 2), (40, 40))

    s = np.linspace(0, 2 * math.pi, 128, endpoint=False)
    orbit = at.Description("periodic", np.zeros(3), np.zeros(2), np.ones(2), 1.0, 2 * math.pi,
                           points=np.array([np.cos(s), np.sin(s)]),
                           state_points=np.array([np.cos(s), np.sin(s), np.cos(s)]))
    widths, _period = confirm.state_widths(Projection(), orbit)
    np.testing.assert_allclose(widths, [0.1, 0.1, 0.1])
    on = orbit.state_points[:, 0]  # x = 1, y = 0, u = 1: moving u up moves it away from every point
    assert confirm.gap(Projection(), orbit, on) == 0.0
    assert confirm.confirms(Projection(), orbit, on + [0, 0, 0.1])
    assert not confirm.confirms(Projection(), orbit, on + [0, 0, 0.3])
    rest = at.Description("equilibrium", np.zeros(3), np.zeros(2), np.zeros(2), state_points=np.zeros((3, 1)))
    np.testing.assert_allclose(confirm.state_widths(Projection(), rest)[0], [0.1, 0.1, 0.1])
    assert confirm.confirms(Projection(), rest, [0.05, -0.1, 0.15])
    assert not confirm.confirms(Projection(), rest, [0.05, -0.1, 0.2])
    assert confirm.confirms(Projection(), at.Description("equilibrium", np.zeros(3), np.zeros(2), np.zeros(2)),
                            [0.0, 0.0, 9.0])  # no state_points (a grid over every state): not checked


def test_a_torqued_pendulum_on_a_grid_over_its_angle_alone_tells_the_rest_point_from_the_running_orbit():
    """theta'' + 0.25 theta' + sin theta = 0.5: a rest point (theta = pi / 6) and a running orbit that passes its
    angle. Before: on a grid over theta alone 0.11 / 0.89 (178 of 441 starts wrong); now every start as scipy's run
    (running: mean |omega| > 0.5 over t in [180, 200]), as on a grid over (theta, omega)."""
    theta, omega = hy.make_vars("theta", "omega")
    pendulum = dy.System("torqued_pendulum", [theta, omega], [omega, 0.5 - 0.25 * omega - hy.sin(theta)])
    axes = {"theta": (-math.pi, math.pi, 21), "omega": (-3.0, 3.0, 21)}
    grid = dy.Grid(("theta",), (-math.pi,), (math.pi,), (100,), (True,))
    ds = dy.basins(pendulum, grid, axes, horizon=200.0, progress=False)
    assert ds.attrs["status"] == "completed" and ds.sizes["attractor"] == 2 and ds.attrs["undecided"] == 0
    rest = int(np.flatnonzero(ds.attractor_kind.values == 0)[0])
    angle, speed = ds.attractor_state.values[rest]
    np.testing.assert_allclose([math.cos(angle), math.sin(angle), speed], [math.sqrt(3) / 2, 0.5, 0.0], atol=1e-10)
    T, W = np.meshgrid(np.linspace(*axes["theta"]), np.linspace(*axes["omega"]), indexing="ij")
    n = T.size
    run = solve_ivp(lambda t, z: np.concatenate([z[n:], 0.5 - 0.25 * z[n:] - np.sin(z[:n])]), (0.0, 200.0),
                    np.concatenate([T.ravel(), W.ravel()]), method="DOP853", rtol=1e-10, atol=1e-10,
                    t_eval=np.linspace(180.0, 200.0, 201))
    running = np.abs(run.y[n:]).mean(axis=1).reshape(T.shape) > 0.5
    np.testing.assert_array_equal(ds.outcome.values != rest, running)
    # the running orbit is a closed orbit on the cylinder: its least period is the time of one turn
    turn = 1 - rest
    assert int(ds.attractor_kind[turn]) == PERIODIC
    k = int(np.flatnonzero(running.ravel())[0])
    one = solve_ivp(lambda t, z: [z[1], 0.5 - 0.25 * z[1] - math.sin(z[0])], (0.0, 400.0), [T.ravel()[k], W.ravel()[k]],
                    method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    up = [t for t in np.linspace(300.0, 400.0, 20001)][:-1]
    angle = one.sol(np.array(up))[0]
    marks = np.floor(angle / (2 * math.pi))
    crossings = np.flatnonzero(np.diff(marks) != 0)
    assert float(ds.attractor_period[turn]) == pytest.approx(np.mean(np.diff(np.array(up)[crossings])), rel=1e-3)

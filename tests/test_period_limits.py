"""The end of an orbit branch at the period bound named right (tippedisk_analysis.dynamics.period_limits): a
saddle-node on the invariant cycle (power law), a saddle's homoclinic orbit and a heteroclinic cycle (log law),
each limit within its stated uncertainty of an exact or independently computed value."""

import math

import heyoka as hy
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics import continuation as co


def _snic() -> dy.System:
    """x' = x (1 - r^2) - y (mu - y), y' = y (1 - r^2) + x (mu - y): on r = 1 theta' = mu - sin(theta), so for
    mu > 1 the cycle has T = 2 pi / sqrt(mu^2 - 1) exactly and a saddle-node appears on it at mu = 1."""
    x, y = hy.make_vars("x", "y")
    mu, r2 = hy.par[0], x * x + y * y
    return dy.System("snic_circle", (x, y), (x * (1 - r2) - y * (mu - y), y * (1 - r2) + x * (mu - y)), {"mu": 2.0})


def _snic_branch(period_max, method="collocation"):
    system = _snic()
    orbit = dy.find_orbit(system, [1.0, 0.0], 2 * math.pi / math.sqrt(3.0), [2.0], method=method)
    orbit.parameter, orbit.value = "mu", 2.0
    assert orbit.period == pytest.approx(2 * math.pi / math.sqrt(3.0), rel=1e-8)
    return dy.continue_orbits(orbit, "mu", bounds={"mu": (0.5, 3.0)}, direction=-1, period_max=period_max)


def _end(br):
    assert br.status == "completed" and br.special_points, br.message
    return br.special_points[-1]


@pytest.mark.parametrize("method", ["collocation", "shooting"])
def test_a_saddle_node_on_the_cycle_is_named_with_its_limit_mu_1(method):
    """The old end called it a homoclinic orbit at mu ~ 1.0038797 (period_max 50); the limit is mu = 1."""
    br, prob = _snic_branch(50.0, method)
    sp = _end(br)
    assert sp.kind == "snic" and sp.label == "SNIC1"
    assert abs(sp.data["limit"] - 1.0) <= sp.data["error"] < 1e-4
    assert sp.data["fold"] == pytest.approx(1.0, abs=1e-10)  # the fold of equilibria the orbit passes
    assert sp.data["rate"] == pytest.approx(math.pi * math.sqrt(2.0), rel=1e-3)  # T ~ 2 pi / sqrt(2 (mu - 1))
    assert "saddle-node on the invariant cycle (SNIC) at mu ~ " in br.message and "homoclinic" not in br.message
    ds = dy.branch_dataset(prob, br)
    assert ds.attrs["labels"] == "SNIC1" and ds.attrs["period_limit"] == "snic"
    assert ds.attrs["period_limit_value"] == sp.data["limit"] and ds.attrs["period_limit_error"] == sp.data["error"]
    k = list(ds.special_label.values).index("SNIC1")
    assert float(ds.special_limit[k]) == sp.data["limit"] and float(ds.special_limit_error[k]) == sp.data["error"]


def test_the_snic_limit_does_not_follow_period_max():
    """The old estimate followed period_max (1.00388, 1.00024 for 50, 200): now both contain mu = 1 and each other."""
    ends = [_end(_snic_branch(period_max)[0]).data for period_max in (50.0, 200.0)]
    for end in ends:
        assert abs(end["limit"] - 1.0) <= end["error"]
    assert abs(ends[0]["limit"] - ends[1]["limit"]) <= ends[0]["error"] + ends[1]["error"]
    assert ends[1]["error"] < ends[0]["error"] < 1e-4  # a longer period pins it closer


def _bogdanov_takens() -> dy.System:
    """x' = y, y' = x - x^2 + mu y + x y: the saddle (0, 0), a Hopf point at mu = -1 of (1, 0)."""
    x, y = hy.make_vars("x", "y")
    return dy.System("bt_unfolding", (x, y), (y, x - x * x + hy.par[0] * y + x * y), {"mu": -0.9})


def _side(mu: float) -> int:
    """+1 if the saddle's unstable manifold (right branch) passes beyond the saddle (x < 0), -1 if it turns back
    (y = 0 at x > 0) after its loop: scipy's DOP853 at rtol 1e-12, independent of heyoka."""
    def f(t, z):
        return [z[1], z[0] - z[0] ** 2 + mu * z[1] + z[0] * z[1]]

    J = np.array([[0.0, 1.0], [1.0, mu]])
    vals, vecs = np.linalg.eig(J)
    v = vecs[:, np.argmax(vals)] * np.sign(vecs[0, np.argmax(vals)])
    past = lambda t, z: z[0]  # noqa: E731 (x falls through 0)
    back = lambda t, z: z[1]  # noqa: E731 (y rises through 0: only after the loop, it starts with y > 0)
    past.terminal = back.terminal = True
    past.direction, back.direction = -1.0, 1.0
    sol = solve_ivp(f, (0.0, 200.0), 1e-9 * v, method="DOP853", rtol=1e-12, atol=1e-15, events=(past, back))
    return 1 if sol.t_events[0].size else -1


def _bt_homoclinic() -> float:
    low, high = -0.87, -0.86
    assert _side(low) != _side(high)
    while high - low > 1e-11:
        mid = 0.5 * (low + high)
        low, high = (mid, high) if _side(mid) == _side(low) else (low, mid)
    return 0.5 * (low + high)


def test_a_saddles_homoclinic_orbit_is_named_with_its_limit():
    """Orbits from the Hopf point at mu = -1 of the Bogdanov-Takens unfolding end in the saddle's homoclinic orbit;
    its parameter by bisection on the unstable manifold's side (scipy): mu = -0.86454524742."""
    system = _bogdanov_takens()
    orbit, _g = dy.orbit_from_hopf(system, "mu", -1.0, [1.0, 0.0], radius=0.1)
    br, _prob = dy.continue_orbits(orbit, "mu", bounds={"mu": (-1.5, 0.5)}, period_max=50.0, segments=4,
                                   options=co.Options(ds=0.02, ds_max=0.2, max_points=200))
    sp = _end(br)
    reference = _bt_homoclinic()
    assert sp.kind == "homoclinic" and sp.label == "HC1"
    assert abs(sp.data["limit"] - reference) <= sp.data["error"] + 2e-11 and sp.data["error"] < 1e-8
    lam_u = (reference + math.sqrt(reference ** 2 + 4)) / 2  # the saddle's unstable eigenvalue at the limit
    assert sp.data["rate"] == pytest.approx(lam_u, rel=0.02)
    assert f"approach to a homoclinic orbit at mu ~ {sp.data['limit']:.8g} +- " in br.message


def _heteroclinic() -> dy.System:
    """x' = y, y' = -x + x^3 - y (H - c), H = y^2/2 + x^2/2 - x^4/4: dH/dt = -y^2 (H - c), so H = c is a cycle
    for 0 < c < 1/4 and at c = 1/4 the cycle through the saddles (+-1, 0) (eigenvalues +-sqrt(2))."""
    x, y = hy.make_vars("x", "y")
    H = y * y / 2 + x * x / 2 - x * x * x * x / 4
    return dy.System("heteroclinic_cycle", (x, y), (y, -x + x * x * x - y * (H - hy.par[0])), {"c": 0.1})


def test_a_heteroclinic_cycle_is_named_with_its_limit_one_quarter():
    system = _heteroclinic()
    orbit, _g = dy.orbit_from_hopf(system, "c", 0.0, [0.0, 0.0], radius=0.1)
    br, prob = dy.continue_orbits(orbit, "c", bounds={"c": (-0.1, 0.3)}, period_max=50.0, method="collocation",
                                  options=co.Options(ds=0.02, ds_max=0.2, max_points=200))
    sp = _end(br)
    assert sp.kind == "heteroclinic" and sp.label == "HET1"
    assert abs(sp.data["limit"] - 0.25) <= sp.data["error"] < 1e-8
    assert sp.data["rate"] == pytest.approx(math.sqrt(2.0) / 2, rel=0.02)  # two passages at rate sqrt(2)
    assert sorted(round(e[0], 9) for e in sp.data["equilibria"]) == [-1.0, 1.0]
    assert "heteroclinic cycle through 2 saddles at c ~ 0.25" in br.message
    assert dy.branch_dataset(prob, br).attrs["period_limit"] == "heteroclinic"


def test_a_branch_stopped_before_a_limit_says_so_without_a_number():
    """AUTO's 'ab' stopped at T = 10 (D = 0.1066, above the fold D = 0.10573898 where its saddle is born): no
    saddle and no fold at the orbit's slowest point, so no limit is given (the orbits end at D = 0.10550707)."""
    ab = dy.textbook_system("ab")
    value, state = dy.TEXTBOOK["ab"].start["hopf"]
    ds = dy.hopf_branch(ab, state, ab.with_pars(D=value), "D", bounds=(0.1, 0.2), period_max=10.0,
                        method="collocation")
    assert ds.attrs["status"] == "completed" and ds.attrs["labels"] == "PB1"
    assert ds.attrs["period_limit"] == "period_bound" and "period_limit_value" not in ds.attrs
    assert "no infinite-period limit named: no equilibrium and no fold" in ds.attrs["message"]
    assert float(ds.special_limit.values[-1]) == 0.0 and float(ds.special_limit_error.values[-1]) == 0.0

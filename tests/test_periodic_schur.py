"""The eigenvalues of a product of pencils (dynamics/periodic_schur.py) against products built with known
eigenvalues, and the collocation multipliers they give (dynamics/collocation.py) against closed forms."""

import math

import numpy as np
import pytest

from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.dynamics.periodic_schur import product_eigenvalues


def known_product(values, N=80, n_extra_rows=0, seed=1, triangular=True):
    """Pencils (A_j, B_j) with A_j x_j + B_j x_j+1 = 0 and M = prod_j (-B_j^-1 A_j) = Q_0 (prod_j D_j) Q_0^T:
    M_j = Q_j+1 D_j Q_j^T (Q_N = Q_0, D_j upper triangular with the N-th roots of ``values`` on the diagonal, the
    signs on D_0), B_j random, A_j = -B_j M_j. The eigenvalues of M are exactly ``values``."""
    rng = np.random.default_rng(seed)
    values = np.asarray(values, dtype=float)
    n = len(values)
    roots = np.abs(values) ** (1.0 / N)
    Q = [np.linalg.qr(rng.normal(size=(n, n)))[0] for _ in range(N)] + [None]
    Q[N] = Q[0]
    A, B = np.empty((N, n, n)), np.empty((N, n, n))
    for j in range(N):
        D = np.triu(rng.normal(size=(n, n))) if triangular else np.zeros((n, n))
        np.fill_diagonal(D, roots * (np.sign(values) if j == 0 else 1.0))
        B[j] = rng.normal(size=(n, n))
        A[j] = -B[j] @ (Q[j + 1] @ D @ Q[j].T)
    return A, B


def dense_eigenvalues(A, B):
    M = np.eye(A.shape[1])
    for A_j, B_j in zip(A, B):
        M = -np.linalg.solve(B_j, A_j @ M)
    return np.linalg.eigvals(M)


def by_modulus(values):
    values = np.asarray(values)
    return values[np.argsort(-np.abs(values))]


def test_multipliers_from_1e90_to_1e_10_keep_their_relative_accuracy_where_the_dense_product_loses_them():
    exact = np.array([1e90, -3e40, 1.0, 0.5, 1e-4, -1e-10])
    A, B = known_product(exact)
    spectrum = product_eigenvalues(A, B)
    assert spectrum.completed, spectrum.message
    found = by_modulus(spectrum.values)
    assert np.max(np.abs(found / exact - 1.0)) < 1e-10
    assert np.allclose(spectrum.log_moduli[np.argsort(-spectrum.log_moduli)], np.log(np.abs(exact)), rtol=0,
                       atol=1e-10)
    dense = by_modulus(dense_eigenvalues(A, B))  # the product formed: everything below ~1e90 eps is lost
    assert np.abs(dense[-1] / exact[-1] - 1.0) > 1.0 and np.abs(dense[2] / exact[2] - 1.0) > 1.0


def test_a_complex_pair_and_close_moduli_stay_together_and_are_exact():
    """Moduli that do not separate under the sweeps (a complex pair, 1 next to 0.999) form blocks whose
    eigenvalues are still exact; every factor turns the pair by 0.7 / N and scales it by 1e6^(1/N)."""
    rng = np.random.default_rng(3)
    N, n, theta = 60, 5, 0.7
    c, s = math.cos(theta / N), math.sin(theta / N)
    D = np.zeros((n, n))
    D[:2, :2] = 1e6 ** (1 / N) * np.array([[c, -s], [s, c]])
    D[2, 2], D[3, 3], D[4, 4] = 1.0, 0.999 ** (1 / N), 1e-8 ** (1 / N)
    Q = [np.linalg.qr(rng.normal(size=(n, n)))[0] for _ in range(N)]
    A, B = np.empty((N, n, n)), np.empty((N, n, n))
    for j in range(N):
        B[j] = rng.normal(size=(n, n))
        A[j] = -B[j] @ (Q[(j + 1) % N] @ (D + np.triu(0.3 * rng.normal(size=(n, n)), 2)) @ Q[j].T)
    spectrum = product_eigenvalues(A, B)
    exact = np.array([1e6 * np.exp(0.7j), 1e6 * np.exp(-0.7j), 1.0, 0.999, 1e-8])
    for value in exact:
        assert np.min(np.abs(spectrum.values - value)) < 1e-10 * abs(value), (value, spectrum.values)
    assert (0, 2) in spectrum.blocks  # the pair


def test_a_singular_block_is_a_status_not_an_exception():
    A, B = known_product([1e3, 1.0, 1e-3], N=20)
    B[7] = np.outer(B[7][:, 0], [1.0, 2.0, 3.0])  # rank one: x_8 is not determined by x_7
    spectrum = product_eigenvalues(A, B)
    assert spectrum.status == "singular" and "mesh interval 7" in spectrum.message
    assert len(spectrum.message.splitlines()) == 1
    A[3, 0, 0] = math.nan
    assert product_eigenvalues(A, B).status == "nonfinite"


def test_the_hopf_normal_form_cycle_has_the_multipliers_exp_minus_2_beta_T_and_exp_minus_T():
    """z' = (beta + i omega) z + (l1 + i c) z |z|^2 with the slave w' = -w + u v, rotated in R^3 (l1 = -1): the
    cycle r^2 = beta, T = 2 pi / (omega + c beta), multipliers 1, exp(-2 beta T) (radial), exp(-T) (the slave)."""
    from tippedisk_analysis.dynamics.systems import HOPF_ROTATION

    system = dy.textbook_system("hopf")
    beta, omega, c = 0.2, 1.0, 0.5
    pars = system.with_pars(beta=beta, omega=omega, l1=-1.0, c=c)
    T = 2 * math.pi / (omega + c * beta)
    orbit = dy.find_orbit(system, HOPF_ROTATION @ [math.sqrt(beta), 0.0, 0.0], T, pars, method="collocation",
                          ntst=20)
    assert orbit.converged, orbit.message
    assert orbit.period == pytest.approx(T, rel=1e-10)
    nontrivial = np.sort(orbit.multipliers[~orbit.trivial].real)
    assert np.allclose(nontrivial, np.sort([math.exp(-2 * beta * T), math.exp(-T)]), rtol=1e-8, atol=0)
    assert abs(orbit.multipliers[orbit.trivial][0] - 1.0) < 1e-9


def test_van_der_pol_has_the_floquet_exponent_of_the_literature():
    """mu = 1: the nontrivial Floquet exponent is -1.059377 per unit time (T = 6.663287)."""
    system = dy.textbook_system("vanderpol")
    pars = system.with_pars(mu=1.0)
    orbit = dy.find_orbit(system, [2.0, 0.0], 6.66, pars, method="collocation", ntst=40)
    assert orbit.converged, orbit.message
    assert orbit.period == pytest.approx(6.663286859, rel=1e-8)
    exponent = math.log(abs(orbit.multipliers[~orbit.trivial][0])) / orbit.period
    assert exponent == pytest.approx(-1.059377, abs=2e-6)


def test_a_singular_block_on_an_orbit_gives_nan_multipliers_and_the_reason_not_an_exception():
    """The collocation problem's multipliers where a condensed block is singular (forced here): NaN, a message
    naming the interval, the stability undecided; the monodromy formed densely is NaN too."""
    from tippedisk_analysis.dynamics.collocation import CollocationProblem

    system = dy.textbook_system("vanderpol")
    orbit = dy.find_orbit(system, [2.0, 0.0], 6.66, system.with_pars(mu=1.0), method="collocation", ntst=20)
    prob = CollocationProblem(system, orbit.pars, ntst=20)
    u = prob.pack(orbit.states, orbit.period)
    ev = prob._evaluate(u)
    A, B = (np.array(block) for block in ev["condensed"])
    B[5] = 0.0
    ev["condensed"] = (A, B)
    assert np.all(np.isnan(prob.state_eigenvalues(u)))
    assert np.all(np.isnan(ev["M"]))
    record = prob.orbit(u)
    assert "mesh interval 5" in record.message and len(record.message.splitlines()) == 1
    assert record.multiplier_source == "none" and not record.multipliers_reliable


def test_a_singular_system_during_a_branch_ends_it_with_a_status_and_keeps_its_orbits(monkeypatch):
    """numpy's LinAlgError anywhere in a step (forced here at the 8th orbit's multipliers) ends the branch with the
    status singular, a one-line message and the orbits computed so far in the dataset."""
    from tippedisk_analysis.dynamics.collocation import CollocationProblem

    original, calls = CollocationProblem.state_eigenvalues, []

    def failing(self, u):
        calls.append(1)
        if len(calls) == 8:
            raise np.linalg.LinAlgError("Singular matrix")
        return original(self, u)

    monkeypatch.setattr(CollocationProblem, "state_eigenvalues", failing)
    system = dy.textbook_system("hopf")
    po = dy.hopf_branch(system, (0.0, 0.0, 0.0), system.with_pars(beta=0.0), "beta", bounds=(-0.1, 1.0))
    assert po.attrs["status"] == "singular" and "Singular matrix" in po.attrs["message"]
    assert len(po.attrs["message"].splitlines()) == 1
    assert po.sizes["point"] == 7 and np.all(po.orbit_status.values == 0)

"""The scalar test functions of cycle bifurcations on the collocation discretisation (:mod:`.collocation`), for the
curves of :mod:`.cycle_curves`: minimally augmented systems, as MatCont's and BifurcationKit's.

Each test is the last component g of a bordered solve

    [[A, b], [c^T, 0]] [v; g] = [0; 1],

zero exactly where A is singular; b, c are A's left and right null vectors at the last reference point
(:meth:`BorderedTest.set_borders`, conjugated for complex A) and dg = -w^T (dA) v with [w; h] from the
transposed solve. A is

* ``fold`` (LPC): the Jacobian of (collocation, phase condition) in (T, nodes): singular at a fold of cycles;
* ``period_doubling`` (PD): the variational collocation equations dv/dtau - T f_x(x) v = 0 with v(1) = -v(0)
  (the last interval's right node is -v_0): singular where -1 is a multiplier;
* ``neimark_sacker`` (NS): the same with v(1) = e^(i theta) v(0), complex: singular where e^(i theta) is a
  multiplier; g is complex (two real equations) and theta is an unknown of the curve.

The second derivatives of f in dA v are central differences of the compiled linearisation along v at the Gauss
points (they shape Newton's steps only: the residual, and so the curve, is exact to the collocation's accuracy).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse
from scipy.sparse import linalg as sparse_linalg

from .collocation_solver import sparse_jacobian

FD_STEP = 1e-6  # the central difference of f_x along v: this share of the state scale
CRITICAL = ("fold", "period_doubling", "neimark_sacker")


class BorderedTest:
    """The test function of ``critical`` (one of CRITICAL) for the curve problem ``curve`` (it evaluates f, f_x and
    f_(p, q) at the Gauss points: ``curve._at_gauss``), on its mesh."""

    def __init__(self, curve, critical: str):
        self.curve, self.critical = curve, critical
        self.borders = None  # (b, c), set from the null vectors of the first matrix, then by set_borders

    # -- the matrix
    def multiplier(self, theta: float) -> complex:
        """The critical multiplier the boundary condition v(1) = mu v(0) imposes."""
        return -1.0 if self.critical == "period_doubling" else complex(math.cos(theta), math.sin(theta))

    def matrix(self, ev: dict, theta: float):
        """A (module docstring) as a sparse CSC matrix."""
        curve, mesh, n = self.curve, self.curve.mesh, self.curve.n
        if self.critical == "fold":
            phase = np.concatenate([[0.0], curve.base._phase])[None, :]
            return sparse_jacobian(ev["blocks"], ev["extras"][:, :, :1], phase, mesh, n, 1)
        ntst, m = mesh.ntst, mesh.m
        j, k, a, i, b = np.ix_(range(ntst), range(m), range(n), range(m + 1), range(n))
        shape = (ntst, m, n, m + 1, n)
        rows = np.broadcast_to((j * m + k) * n + a, shape).ravel()
        cols = np.broadcast_to(mesh.intervals[j, i] * n + b, shape).ravel()
        factor = np.ones((ntst, m + 1), dtype=complex)
        factor[-1, -1] = self.multiplier(theta)  # x_ntst = mu x_0
        values = (ev["blocks"].reshape(shape) * factor[:, None, None, :, None]).ravel()
        if self.critical == "period_doubling":
            values = values.real
        size = mesh.n_nodes * n
        return sparse.coo_matrix((values, (rows, cols)), shape=(size, size)).tocsc()

    # -- g and its gradient
    def evaluate(self, ev: dict, theta: float) -> dict:
        """{"g": complex, "g_row": d g / d u (complex, the layout of u), "v", "w"}; g NaN where the bordered matrix
        is singular (the borders miss the null space)."""
        A = self.matrix(ev, theta)
        size = A.shape[0]
        if self.borders is None:
            self.borders = null_vectors(A)
        b, c = self.borders
        M = sparse.bmat([[A, sparse.csc_matrix(b[:, None])], [sparse.csc_matrix(c[None, :]), None]], format="csc")
        rhs = np.zeros(size + 1, dtype=M.dtype)
        rhs[-1] = 1.0
        try:
            lu = sparse_linalg.splu(M)
        except RuntimeError:
            return {"g": complex(math.nan), "g_row": np.full(len(self.curve.scale), complex(math.nan))}
        vg, wh = lu.solve(rhs), lu.solve(rhs, trans="T")
        v, w = vg[:-1], wh[:-1]
        return {"g": complex(vg[-1]), "g_row": self._gradient(ev, v, w, theta), "v": v, "w": w}

    def set_borders(self, ev: dict) -> None:
        """The borders from the null vectors v, w of the evaluation ``ev`` (the last reference point)."""
        if "v" in ev:
            self.borders = (np.conj(ev["w"]) / np.linalg.norm(ev["w"]), np.conj(ev["v"]) / np.linalg.norm(ev["v"]))

    def _variation(self, v: np.ndarray, theta: float) -> tuple[np.ndarray, float]:
        """(the variation at the Gauss points (ntst, m, n), its T component) of the null vector v."""
        mesh, n = self.curve.mesh, self.curve.n
        if self.critical == "fold":
            return mesh.at_gauss(v[1:].reshape(-1, n))[0], v[0]
        V = v.reshape(-1, n)
        closed = np.concatenate([V, self.multiplier(theta) * V[:1]])
        pieces = closed[np.arange(mesh.ntst)[:, None] * mesh.m + np.arange(mesh.m + 1)[None, :]]
        return mesh.basis.at_gauss @ pieces, 0.0

    def _directional(self, ev: dict, vz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(f_xx[vz, .], f_xp vz) at the Gauss points by central differences of f_x, f_p along real vz."""
        scale = np.asarray(self.curve.system.state_scale)
        step = FD_STEP / max(float(np.max(np.abs(vz / scale))), 1e-300)
        _f1, J_plus, fp_plus = self.curve._at_gauss(ev["xz"] + step * vz, ev["pars"])
        _f2, J_minus, fp_minus = self.curve._at_gauss(ev["xz"] - step * vz, ev["pars"])
        return (J_plus - J_minus) / (2 * step), (fp_plus - fp_minus) / (2 * step)

    def _gradient(self, ev: dict, v: np.ndarray, w: np.ndarray, theta: float) -> np.ndarray:
        """dg/du = -w^T (dA/du) v; the collocation rows of A v at Gauss point k are
        (slope terms) - T f_x(x_k) v(z_k) [- f(x_k) v_T for the fold]; the phase row is constant."""
        curve, mesh, n, T = self.curve, self.curve.mesh, self.curve.n, ev["T"]
        vz, v_T = self._variation(v, theta)
        wz = w[: mesh.n_nodes * n].reshape(mesh.ntst, mesh.m, n)  # the collocation rows' weights
        if np.iscomplexobj(vz):
            (dJ_r, dfp_r), (dJ_i, dfp_i) = self._directional(ev, vz.real), self._directional(ev, vz.imag)
            dJ, dfp = dJ_r + 1j * dJ_i, dfp_r + 1j * dfp_i
        else:
            dJ, dfp = self._directional(ev, vz)
        Jv = np.einsum("jkab,jkb->jka", ev["J"], vz)
        fp = curve._at_gauss(ev["xz"], ev["pars"])[2]
        row = np.zeros(len(curve.scale), dtype=complex)
        row[0] = np.sum(wz * Jv)  # -w . d(A v)/dT, d(A v)/dT = -f_x v_x
        row[1:3] = np.einsum("jka,jkap->p", wz, T * dfp + v_T * fp)
        if self.critical == "neimark_sacker":  # dA/dtheta: the last interval's right-node columns times i mu
            last = ev["blocks"][-1][:, mesh.m * n:]
            row[3] = -w[(mesh.n_nodes - mesh.m) * n: mesh.n_nodes * n] @ (last @ (1j * self.multiplier(theta)
                                                                               * v[:n]))
        at_x = T * np.einsum("jka,jkab->jkb", wz, dJ) + v_T * np.einsum("jka,jkab->jkb", wz, ev["J"])
        nodal = np.einsum("ki,jkb->jib", mesh.basis.at_gauss, at_x)  # Gauss points to the interval's nodes
        grad = np.zeros((mesh.n_nodes, n), dtype=complex)
        np.add.at(grad, mesh.intervals, nodal)
        row[curve.x_start:] = grad.ravel()
        return row


def null_vectors(A) -> tuple[np.ndarray, np.ndarray]:
    """(b, c): the conjugated (left, right) unit null vectors of a nearly singular sparse A by two steps of inverse
    iteration, the borders of the first bordered solve."""
    lu = sparse_linalg.splu(A.tocsc())
    rng = np.random.default_rng(1)
    pair = []
    for trans in ("T", "N"):
        x = rng.normal(size=A.shape[0]) + (1j * rng.normal(size=A.shape[0]) if np.iscomplexobj(A.data) else 0.0)
        for _ in range(2):
            x = lu.solve(x / np.linalg.norm(x), trans=trans)
        pair.append(np.conj(x) / np.linalg.norm(x))
    return pair[0], pair[1]

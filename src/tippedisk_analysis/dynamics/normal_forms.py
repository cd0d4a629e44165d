"""Normal-form coefficients of equilibrium bifurcations from exact derivative tensors.

Generic (numpy only): J = f_x (n x n), B = f_xx (n, n, n), C = f_xxx (n, n, n, n) at the point,
as :meth:`.tensors.Field.tensor` returns them. Formulas follow Kuznetsov,
*Elements of Applied Bifurcation Theory* (3rd ed., Sect. 3.5 and 5.4), with <p, q> = conj(p) . q.

Isolated equilibria (an invertible J apart from the critical eigenvalues):

* fold: a = 1/2 <p, B(q, q)>, J q = 0, J^T p = 0, <p, q> = 1 (the z' = a z^2 coefficient);
* Hopf: the first Lyapunov coefficient
  l1 = 1/(2 omega) Re[<p, C(q, q, conj q)> - 2 <p, B(q, J^-1 B(q, conj q))>
                      + <p, B(conj q, (2 i omega - J)^-1 B(q, q))>],
  J q = i omega q, J^T p = -i omega p, <q, q> = <p, q> = 1; l1 < 0 supercritical, > 0 subcritical.

Lines of equilibria (a family x*(s) with J phi0 = 0 at every member, phi0 = dx*/ds), the
bifurcations "without parameters" of Fiedler, Liebscher & Alexander (J. Differential Equations 168,
2000; Liebscher, *Bifurcation without Parameters*, Springer 2015), here for a vector field that is
only C^1 on the line: f(x* + w) = J w + B(w, w)/2 + N(w) + O(|w|^3) with an odd term N of degree two
(for the tippedisk N(w) = (G_xs w)|Gamma w| from |gamma_T| in (2.29), see
:func:`tippedisk_analysis.analysis.reduced.nonsmooth_split`). In the center coordinates (s along the
line, z of the critical mode, r = |z|), to second order:

* Hopf (a pair i omega): s' = b r^2, r' = a s r + k r^2, with a + i a' = <p, B(phi0, q)> = d lambda/ds,
  b = psi0 . B(q, conj q) (psi0^T J = 0, psi0 . phi0 = 1; the odd N averages out of s'), and
  k = Re kappa, kappa = (1/2 pi) int <p, N(q e^{i theta} + c.c.)> e^{-i theta} d theta, the
  resonant (first Fourier) part of N: z' contains kappa |z| z. For a smooth field k = 0 and the
  cubic l1 decides, as in the classical case; here the C^1 term dominates it.
* real eigenvalue through 0: s' = b z^2 + k0 z|z|, z' = a s z + c z^2 + k z |z|, with a = p . B(phi0, q),
  b = psi0 . B(q, q) / 2, c = p . B(q, q) / 2, k = p . N(q), k0 = psi0 . N(q) (dual bases of the kernel
  {phi0, q}; the odd term does not average out of s' here as it does at a Hopf point).

Dividing by r (or |z|) leaves the linear system (r, s)' = M (r, s), M = [[k, a], [b, 0]] (for the real
case [[k + c, a], [b + k0, 0]] on the side z > 0 and [[k - c, a], [b - k0, 0]] on z < 0), which
classifies the point:

* a b > 0: **hyperbolic** (saddle): orbits near the line leave the neighbourhood;
* a b < 0, k^2 + 4 a b < 0: **elliptic** (focus): an orbit leaving the line at s0 on the unstable
  side returns to it at s1 = -s0 exp(pi k / (2 nu)) on the stable side, nu = sqrt(-a b - k^2/4);
  no periodic orbits;
* a b < 0, k^2 + 4 a b > 0: a node, **repelling** (k > 0: orbits leave the line and the
  neighbourhood) or **attracting** (k < 0).
"""

from __future__ import annotations

import numpy as np

from .tensors import bilinear, trilinear


def _critical_pair(J: np.ndarray):
    """(omega, q, p) of the eigenvalue pair nearest the imaginary axis: J q = i omega q,
    J^T p = -i omega p (so <p, J x> = i omega <p, x>), <q, q> = 1, <p, q> = 1."""
    vals, vecs = np.linalg.eig(J)
    complex_ = np.flatnonzero(vals.imag > 1e-12 * max(1.0, np.abs(vals).max()))
    k = complex_[np.argmin(np.abs(vals[complex_].real))]
    omega = vals[k].imag
    q = vecs[:, k] / np.linalg.norm(vecs[:, k])
    lvals, lvecs = np.linalg.eig(J.T)
    m = np.argmin(np.abs(lvals - (-1j * omega)))  # J^T p = -i omega p
    p = lvecs[:, m]
    p = p / np.conj(np.vdot(p, q))  # <p, q> = conj(p) . q = 1
    return float(omega), q, p, complex(vals[k])


def hopf_frequency(J: np.ndarray) -> float:
    """omega of the complex pair of J nearest the imaginary axis."""
    return _critical_pair(J)[0]


def _real_null(M: np.ndarray, transpose: bool = False) -> np.ndarray:
    """Unit vector spanning the (numerically) one-dimensional null space of M (or of M^T)."""
    return np.linalg.svd(M.T if transpose else M)[2][-1]


def fold_coefficient(J: np.ndarray, B: np.ndarray) -> dict:
    """Quadratic coefficient a = 1/2 <p, B(q, q)> of a fold of an isolated equilibrium."""
    q = _real_null(J)
    q = q * np.sign(q[np.argmax(np.abs(q))])  # orientation: the largest component positive (a's sign is q's)
    p = _real_null(J, transpose=True)
    p = p / (p @ q)
    return {"a": float(0.5 * p @ bilinear(B, q, q)), "q": q, "p": p}


L1_DEGENERATE = 1e-9  # |l1| below this share of the size of its terms: zero to round-off (a degenerate Hopf point)


def first_lyapunov_coefficient(J: np.ndarray, B: np.ndarray, C: np.ndarray) -> dict:
    """Hopf point of an isolated equilibrium: frequency omega and l1 (Kuznetsov (3.20), n-dim form); ``scale``:
    the size of its terms, (sum of their moduli) / (2 omega); ``degenerate``: |l1| <= L1_DEGENERATE max(scale,
    omega) (l1 vanishes to round-off: a generalised Hopf point, a centre where the system is conservative, or a
    linear one where every nonlinear term vanishes, as van der Pol's at mu = 0)."""
    omega, q, p, lam = _critical_pair(J)
    n = J.shape[0]
    qb = np.conj(q)
    h11 = np.linalg.solve(J, bilinear(B, q, qb))  # J^-1 B(q, conj q)
    h20 = np.linalg.solve(2j * omega * np.eye(n) - J, bilinear(B, q, q))
    terms = (np.vdot(p, trilinear(C, q, q, qb)), -2 * np.vdot(p, bilinear(B, q, h11)), np.vdot(p, bilinear(B, qb, h20)))
    l1, scale = float(sum(terms).real / (2 * omega)), float(sum(map(abs, terms)) / (2 * omega))
    degenerate = abs(l1) <= L1_DEGENERATE * max(scale, omega)  # terms that all vanish (a linear centre) too
    return {"l1": l1, "scale": scale, "degenerate": degenerate, "frequency": omega,
            "eigenvalue": lam, "q": q, "p": p}


def nonsmooth_hopf_coefficient(q: np.ndarray, p: np.ndarray, nonsmooth, n_theta: int = 512) -> complex:
    """kappa = (1/2 pi) int_0^{2 pi} <p, N(w(theta))> e^{-i theta} d theta, w = q e^{i theta} + c.c.

    N (``nonsmooth``: w -> vector) is odd and positively homogeneous of degree two; the trapezoidal
    rule converges spectrally where |Gamma w(theta)| does not vanish (the generic case).
    """
    theta = 2 * np.pi * np.arange(n_theta) / n_theta
    total = 0j
    for th in theta:
        w = 2 * (q * np.exp(1j * th)).real
        total += np.vdot(p, nonsmooth(w)) * np.exp(-1j * th)
    return complex(total / n_theta)


def classify_line(a: float, b: float, k: float) -> str:
    """Class of a bifurcation from a line of equilibria from M = [[k, a], [b, 0]] (module docstring)."""
    if a * b > 0:
        return "hyperbolic"
    if a * b == 0:
        return "degenerate"
    if k * k + 4 * a * b < 0:
        return "elliptic"
    return "repelling_node" if k > 0 else "attracting_node"


def elliptic_return(a: float, b: float, k: float) -> float:
    """s1 / s0 of an elliptic point: the spin-rate offset at which an orbit lands, per offset it left at."""
    nu = np.sqrt(-a * b - 0.25 * k * k)
    return float(-np.exp(np.pi * k / (2 * nu)))


def line_hopf(J: np.ndarray, B: np.ndarray, phi0: np.ndarray, nonsmooth=None) -> dict:
    """Hopf point on a line of equilibria with tangent phi0 = dx*/ds: a, b, k and the class."""
    omega, q, p, lam = _critical_pair(J)
    psi0 = _real_null(J, transpose=True)
    psi0 = psi0 / (psi0 @ phi0)
    dlam = np.vdot(p, bilinear(B, phi0, q))  # d lambda / ds
    b = float(psi0 @ bilinear(B, q, np.conj(q)).real)
    a = float(dlam.real)
    kappa = nonsmooth_hopf_coefficient(q, p, nonsmooth) if nonsmooth is not None else 0j
    k = float(kappa.real)
    return {"a": a, "a_imag": float(dlam.imag), "b": b, "k": k, "kappa": kappa, "class": classify_line(a, b, k),
            "frequency": omega, "eigenvalue": lam, "q": q, "p": p, "psi0": psi0}


def line_transcritical(J: np.ndarray, B: np.ndarray, phi0: np.ndarray, nonsmooth=None) -> dict:
    """A second real eigenvalue through 0 on a line of equilibria (tangent phi0): a, b, c, k and the class
    (of the side z > 0, ``class``, and z < 0, ``class_negative``)."""
    U, sv, Vt = np.linalg.svd(J)
    kernel = Vt[-2:].T  # span {phi0, q}
    left = U[:, -2:]  # left kernel
    q = kernel[:, 0] - (kernel[:, 0] @ phi0) / (phi0 @ phi0) * phi0
    if np.linalg.norm(q) < 1e-8:
        q = kernel[:, 1] - (kernel[:, 1] @ phi0) / (phi0 @ phi0) * phi0
    q /= np.linalg.norm(q)
    q *= np.sign(q[np.argmax(np.abs(q))])  # orientation: the largest component positive (defines the side z > 0)
    # dual basis (psi0, p) of the left kernel: psi0 . phi0 = 1, psi0 . q = 0, p . phi0 = 0, p . q = 1
    M = left.T @ np.column_stack([phi0, q])  # 2 x 2
    dual = left @ np.linalg.inv(M).T
    psi0, p = dual[:, 0], dual[:, 1]
    a = float(p @ bilinear(B, phi0, q))
    b = float(0.5 * psi0 @ bilinear(B, q, q))
    c = float(0.5 * p @ bilinear(B, q, q))
    N = nonsmooth(q) if nonsmooth is not None else np.zeros_like(q)
    k, k0 = float(p @ N), float(psi0 @ N)
    return {"a": a, "b": b, "c": c, "k": k, "k0": k0, "class": classify_line(a, b + k0, k + c),
            "class_negative": classify_line(a, b - k0, k - c), "q": q, "p": p, "psi0": psi0,
            "smallest_singular_values": sv[-3:]}

"""Exact derivative tensors of compiled outputs: f(x; p) and the symmetric tensors of its first to third
derivatives with respect to the state and chosen runtime parameters.

:meth:`.system.System.field` builds and caches one per (pinned observables, parameters) of a system.
Derivatives are symbolic (``hy.diff_tensors``) and compiled once (``hy.cfunc``; heyoka caches the
machine code on disk), never finite differences.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from ..compilation import compiling


@dataclass(frozen=True)
class _Tensor:
    cfunc: object  # compiled derivatives of one order
    shape: tuple  # (n_out, n_arg, ..., n_arg)
    positions: np.ndarray  # flat positions in the dense tensor (every permutation of the arguments) ...
    source: np.ndarray  # ... and the compiled entry that fills each


class Field:
    """Outputs (e.g. the right-hand side and constraint functions) of ``variables`` and ``parameters``.

    outputs: heyoka expressions; variables: heyoka variables (the state x); parameters: the
    hy.par[i] expressions to differentiate by, in the order the tensors' trailing arguments use
    (state first, then these). Every evaluation takes the full runtime parameter vector ``pars``.
    """

    def __init__(self, outputs, variables, parameters=()):
        self.outputs = list(outputs)
        self.variables = list(variables)
        self.parameters = list(parameters)
        self.n_out, self.n_state = len(self.outputs), len(self.variables)
        self.n_args = self.n_state + len(self.parameters)
        self._values = hy.cfunc(self.outputs, self.variables)
        self._tensors: dict[tuple[int, bool], _Tensor] = {}

    def _call(self, cf, x, pars) -> np.ndarray:
        x = np.ascontiguousarray(np.asarray(x, dtype=float).reshape(self.n_state, 1))
        if cf.nparams == 0:
            return cf(x)[:, 0]
        pars = np.ascontiguousarray(np.asarray(pars, dtype=float)[: cf.nparams].reshape(-1, 1))
        return cf(x, pars=pars)[:, 0]

    def values(self, x, pars) -> np.ndarray:
        """The outputs at one point, shape (n_out,)."""
        return self._call(self._values, x, pars)

    def _tensor(self, order: int, with_parameters: bool) -> _Tensor:
        key = (order, with_parameters)
        if key not in self._tensors:
            with compiling(f"the derivative tensors of order {order} ({self.n_out} outputs)"):
                self._tensors[key] = self._compile(order, with_parameters)
        return self._tensors[key]

    def _compile(self, order: int, with_parameters: bool) -> _Tensor:
        args = self.variables + (self.parameters if with_parameters else [])
        entries = hy.diff_tensors(self.outputs, diff_args=args, diff_order=order).get_derivatives(order)
        shape = (self.n_out, *([len(args)] * order))
        positions, source = [], []
        for i, (multi, _expr) in enumerate(entries):  # multi = [output, times each argument is differentiated]
            arguments = tuple(k for k, n in enumerate(multi[1:]) for _ in range(n))
            for perm in set(itertools.permutations(arguments)):
                positions.append(np.ravel_multi_index((multi[0], *perm), shape))
                source.append(i)
        function = hy.cfunc([expr for _m, expr in entries], self.variables)
        return _Tensor(function, shape, np.array(positions, dtype=np.int64), np.array(source, dtype=np.int64))

    def tensor(self, x, pars, order: int, with_parameters: bool = True) -> np.ndarray:
        """Derivative tensor of ``order`` (1, 2, 3) at one point, shape (n_out, n, ..., n), n = n_state
        (+ the differentiated parameters if ``with_parameters``); symmetric in the trailing axes.

        The state-only tensor is compiled only when needed: if the tensor with parameters is compiled
        already, it is a slice of that one (the second-order tensor with parameters has three times the
        entries and compiles for seconds on a cold cache)."""
        if not with_parameters and self.parameters and (order, True) in self._tensors:
            return self.tensor(x, pars, order)[(slice(None), *([slice(0, self.n_state)] * order))]
        t = self._tensor(order, with_parameters)
        values = self._call(t.cfunc, x, pars)
        out = np.zeros(t.shape)
        out.flat[t.positions] = values[t.source]
        return out


    def has_kink(self, x, pars, order: int, scale) -> bool:
        """Whether the derivative tensor of ``order`` (1: the Jacobian, 2: the second derivatives) has a kink at
        x along some state coordinate: a jump of the next derivative, as an ``abs(x) * x`` term (order 1) or a
        ``relu(x)**3`` term (order 2) gives, or a smoothing of one far below the steps. Per entry, the second
        difference over steps h = KINK_STEPS times ``scale`` (the states' typical sizes) falls as h where smooth,
        grows as 1/h where round-off dominates, and keeps its size at a kink; the smallest pair of steps whose
        differences stand above round-off (measured on the output's largest entry) and do not grow decides."""
        x = np.asarray(x, dtype=float)
        T0 = self.tensor(x, pars, order, with_parameters=False)
        for k, size in enumerate(np.asarray(scale, dtype=float)[: self.n_state]):
            step = np.zeros(self.n_state)
            step[k] = size
            seconds, floors = [], []
            for h in KINK_STEPS:
                plus = self.tensor(x + h * step, pars, order, with_parameters=False)
                minus = self.tensor(x - h * step, pars, order, with_parameters=False)
                seconds.append(np.abs(plus - 2 * T0 + minus) / (h * size))
                magnitude = np.max(np.maximum(np.maximum(np.abs(plus), np.abs(minus)), np.abs(T0)).reshape(
                    T0.shape[0], -1), axis=1).reshape(-1, *([1] * order))
                floors.append(np.broadcast_to(KINK_ROUND_OFF * magnitude / (h * size), T0.shape))
            decided = np.zeros(T0.shape, dtype=bool)
            for i in range(len(KINK_STEPS) - 1, 0, -1):  # smallest pair of steps first
                ratio = seconds[i] / np.maximum(seconds[i - 1], np.finfo(float).tiny)
                clear = ~decided & (seconds[i] > floors[i]) & (seconds[i - 1] > floors[i - 1]) & (ratio < 2.0)
                if np.any(clear & (ratio > KINK_RATIO)):
                    return True
                decided |= clear
        return False


KINK_STEPS = (1e-4, 1e-5, 1e-6, 1e-7)  # steps of Field.has_kink, times the state scale
KINK_RATIO = 0.5  # second differences over steps 10x apart: ratio 0.1 where smooth, 1 at a kink, 10 in round-off
KINK_ROUND_OFF = 1e4 * np.finfo(float).eps  # share of an output's largest entry its evaluation may be off by


def bilinear(B: np.ndarray, a, b) -> np.ndarray:
    """B(a, b) = sum_jk B[:, j, k] a_j b_k (complex vectors allowed)."""
    return np.einsum("ijk,j,k->i", B, a, b)


def trilinear(C: np.ndarray, a, b, c) -> np.ndarray:
    """C(a, b, c) = sum_jkl C[:, j, k, l] a_j b_k c_l."""
    return np.einsum("ijkl,j,k,l->i", C, a, b, c)

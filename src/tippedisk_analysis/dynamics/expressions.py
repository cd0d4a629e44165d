"""Rewrites of heyoka expressions that keep a declared system integrable everywhere it is defined.

heyoka (7.13) differentiates ``b**n`` by the recursion of a general power, which divides by ``b``: a Taylor
step at ``b = 0`` exactly gives NaN for ``x**3`` (``x**2`` has a recursion of its own and is safe), although
the polynomial is smooth there. :func:`expand_integer_powers` writes every integer power n >= 3 as products of
squares, so a run started at x = 0 integrates.
"""

from __future__ import annotations

import itertools
import re

import heyoka as hy

from ..errors import ParameterError

_INTEGER_POWER = re.compile(r"\*\*([3-9]|[1-9]\d+)\.0+(?![0-9]*[1-9])")  # b**3.000..., b**12.000...


def _power(base, n: int):
    """base**n (n >= 1) by squaring: (b**2)**2 * b for n = 5; heyoka's square is safe at b = 0."""
    if n == 1:
        return base
    half = _power(base, n // 2)
    square = half**2
    return square * base if n % 2 else square


def expand_integer_powers(expression):
    """``expression`` with every power b**n of integer n >= 3 replaced by products of squares (the same
    function; heyoka's Taylor recursion of b**n is singular at b = 0). Expressions without one are returned
    as they are."""
    if not _INTEGER_POWER.search(str(expression)):
        return expression
    import sympy

    names = (f"_integer_power_{k}" for k in itertools.count())
    replacements: dict = {}

    def expand(node):  # sympy replaces inner powers first: a base holds only symbols already in replacements
        symbol = sympy.Symbol(next(names))
        replacements[symbol] = _power(hy.from_sympy(node.base, replacements), int(node.exp))
        return symbol

    try:
        tree = hy.to_sympy(expression).replace(lambda e: e.is_Pow and e.exp.is_Integer and e.exp >= 3, expand)
        return hy.from_sympy(tree, replacements)
    except TypeError as exc:  # a function sympy cannot translate back (heyoka's relu, say)
        raise ParameterError(f"cannot rewrite the integer powers of {expression} ({exc}); write them as products, "
                             "e.g. x*x*x for x**3") from None

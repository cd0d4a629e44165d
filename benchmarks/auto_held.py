"""AUTO-07p (bifpy's transpiled path) on a :class:`~tippedisk_analysis.dynamics.System`, for the benchmarks: the
System's right-hand side, its exact state Jacobian and its derivative in the continuation parameter written as an
AUTO-07p equation file (Fortran), checked against the System at random states, and a periodic-orbit branch started
from a small orbit at a Hopf point (bifpy starts no branch at a Hopf point itself). Not a test.

The equation file comes from heyoka's decomposition of the System's compiled functions (``cfunc.dc``: one
elementary operation a line, every shared subexpression once; about 1,000 operations for the held-spin model's
right-hand side, 3,800 with its Jacobians). bifpy's own tracer prints each equation as one sympy tree without
common subexpressions: for the held-spin model 20 MB and 10 MB of text for its two nontrivial equations (146 s
to print), and ``sympy.cse`` of the Jacobians does not finish in 15 min; so bifpy's ``generate_equation_file`` is
replaced by this file for the run (AUTO-07p, its constants file, the compile and the output parsing are bifpy's,
unchanged). bifpy compiles the file with gfortran's defaults (no -O).

AUTO-07p: apt-get install gfortran; .venv/bin/pip install bifpy  (a benchmark extra, never a test dependency)
"""

from __future__ import annotations

import ast
import math
import re
import resource
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from unittest import mock

import numpy as np

PERIOD_SLOT = 11  # AUTO-07p's PAR(11): the period of a periodic orbit
PARAMETER_SLOTS = tuple(range(1, PERIOD_SLOT))  # PAR(1) the continuation parameter, PAR(2-10) the others
_FUNCTIONS = {"sin": "sin", "cos": "cos", "combined_sin": "sin", "combined_cos": "cos", "sqrt": "sqrt",
              "exp": "exp", "log": "log", "tan": "tan", "tanh": "tanh", "atan": "atan", "asin": "asin",
              "acos": "acos", "abs": "abs"}
_OPERATORS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", "sub": "-", "div": "/"}
_TEMPORARY = re.compile(r"u_(\d+)$")
_PARAMETER = re.compile(r"p(\d+)$")
_TOTAL_TIME = re.compile(r"Total Time\s+([0-9.E+-]+)", re.IGNORECASE)


def _number(value: float) -> str:
    """A double-precision Fortran literal that reads back as ``value`` exactly."""
    if not math.isfinite(value):
        raise ValueError(f"the decomposition holds the constant {value}; AUTO-07p's Fortran cannot take it")
    mantissa, _, exponent = repr(float(value)).partition("e")
    return f"{mantissa if '.' in mantissa else mantissa + '.0'}d{int(exponent or 0)}"


def _fortran(node, slots: dict) -> str:
    """Fortran for one node of an elementary operation of heyoka's decomposition (u_i -> w(i), hy.par[k] ->
    par(slots[k])), every operation in parentheses."""
    if isinstance(node, ast.Constant):  # a negative one in parentheses: Fortran takes no "* -2.0d0"
        return f"({_number(node.value)})" if math.copysign(1.0, node.value) < 0 else _number(node.value)
    if isinstance(node, ast.Name):
        if match := _TEMPORARY.match(node.id):
            return f"w({match[1]})"
        if (match := _PARAMETER.match(node.id)) and int(match[1]) in slots:
            return f"par({slots[int(match[1])]})"
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return f"(-{_fortran(node.operand, slots)})"
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
        power = node.right.value if isinstance(node.right, ast.Constant) else None
        exponent = f"({int(power)})" if power is not None and float(power).is_integer() else \
            f"({_fortran(node.right, slots)})"  # x**3.0 of a negative x is NaN in Fortran, x**3 is not
        return f"({_fortran(node.left, slots)}**{exponent})"
    if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
        return f"({_fortran(node.left, slots)} {_OPERATORS[type(node.op)]} {_fortran(node.right, slots)})"
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
        name, args = node.func.id, [_fortran(a, slots) for a in node.args]
        if name in _OPERATORS and len(args) == 2:
            return f"({args[0]} {_OPERATORS[name]} {args[1]})"
        if name in _FUNCTIONS and len(args) == 1:
            return f"{_FUNCTIONS[name]}({args[0]})"
    raise ValueError(f"cannot write {ast.unparse(node)!r} of heyoka's decomposition in Fortran; add its function "
                     "to auto_held._FUNCTIONS")


def _wrap(statement: str, width: int = 120) -> list[str]:
    """A free-form Fortran statement in lines of at most ``width`` characters (split at spaces, & continued)."""
    lines, line = [], "      "
    for word in statement.split(" "):
        if len(line) + len(word) > width:
            lines.append(line + "&")
            line = "     &"
        line += word + " "
    return [*lines, line.rstrip()]


def _subroutine(name: str, cf, slots: dict, outputs: list[str]) -> str:
    """A subroutine ``name``(U, PAR, OUT) evaluating the cfunc ``cf`` through its decomposition; ``outputs``: the
    Fortran targets of its outputs in order."""
    dc = [str(e) for e in cf.dc]
    body = [f"      w({i}) = u({i + 1})" for i in range(cf.nvars)]
    for i, text in enumerate(dc[cf.nvars:len(dc) - cf.nouts], start=cf.nvars):
        body += _wrap(f"w({i}) = {_fortran(ast.parse(text, mode='eval').body, slots)}")
    body += [f"      {target} = {_fortran(ast.parse(text, mode='eval').body, slots)}"
             for target, text in zip(outputs, dc[len(dc) - cf.nouts:])]
    return "\n".join([f"      SUBROUTINE {name}(U, PAR, OUT)", "      IMPLICIT NONE",
                      "      DOUBLE PRECISION, INTENT(IN) :: U(*), PAR(*)",
                      "      DOUBLE PRECISION, INTENT(OUT) :: OUT(*)",
                      f"      DOUBLE PRECISION :: w(0:{len(dc)})", *body, f"      END SUBROUTINE {name}", ""])


def parameter_slots(system, parameter: str) -> dict:
    """{System parameter index: AUTO-07p PAR slot}: ``parameter`` in PAR(1), the other parameters the right-hand
    side uses in PAR(2-10) in their order (PAR(11) is the period)."""
    from tippedisk_analysis.dynamics.system import parameter_indices

    first = system.parameter_index(parameter)
    used = [first, *sorted(parameter_indices(system.rhs) - {first})]
    if len(used) > len(PARAMETER_SLOTS):
        raise ValueError(f"{system.name}'s right-hand side uses {len(used)} parameters; AUTO-07p's PAR(1-10) hold 10")
    return dict(zip(used, PARAMETER_SLOTS))


def equation_file(system, parameter: str, start_pars, start_state, start_orbit, period: float) -> str:
    """An AUTO-07p equation file for ``system`` continued in ``parameter``: FUNC (f; with IJAC >= 1 the exact
    d f / d u, with IJAC = 2 d f / d ``parameter``), STPNT (u(t) = start_state + Re(start_orbit e^(2 pi i t)) at
    ``start_pars``, period ``period`` [time units]) and empty BCND, ICND, FOPT, PVLS."""
    n, slots = system.n, parameter_slots(system, parameter)
    rhs = _subroutine("EXPORTED_RHS", system.rhs_function(), slots, [f"out({i + 1})" for i in range(n)])
    linear = _subroutine("EXPORTED_LINEARISATION", system.linearisation_function((parameter,)), slots,
                         [f"out({i + 1})" for i in range(n * (n + 2))])
    unpack = [f"      F({i + 1}) = w({i + 1})" for i in range(n)]
    unpack += [f"      DFDU({i + 1},{j + 1}) = w({n + n * i + j + 1})" for i in range(n) for j in range(n)]
    parameter_column = [f"      DFDP({i + 1},1) = w({n + n * n + i + 1})" for i in range(n)]
    parameter_column += [f"      DFDP({i + 1},{PERIOD_SLOT}) = 0.0d0" for i in range(n)]
    start_values = [f"      PAR({slot}) = {_number(start_pars[k])}" for k, slot in slots.items()]
    start_values.append(f"      PAR({PERIOD_SLOT}) = {_number(period)}")
    for i in range(n):
        start_values += _wrap(f"U({i + 1}) = ({_number(start_state[i])}) + ({_number(start_orbit[i].real)})"
                              f" * cos(angle) + ({_number(-start_orbit[i].imag)}) * sin(angle)")
    return "\n".join([
        "      SUBROUTINE FUNC(NDIM,U,ICP,PAR,IJAC,F,DFDU,DFDP)", "      IMPLICIT NONE",
        "      INTEGER, INTENT(IN) :: NDIM, ICP(*), IJAC", "      DOUBLE PRECISION, INTENT(IN) :: U(NDIM), PAR(*)",
        "      DOUBLE PRECISION, INTENT(OUT) :: F(NDIM)",
        "      DOUBLE PRECISION, INTENT(INOUT) :: DFDU(NDIM,NDIM), DFDP(NDIM,*)",
        f"      DOUBLE PRECISION :: w({n * (n + 2)})", "      IF (IJAC .EQ. 0) THEN",
        "        CALL EXPORTED_RHS(U, PAR, F)", "        RETURN", "      END IF",
        "      CALL EXPORTED_LINEARISATION(U, PAR, w)", *unpack, "      IF (IJAC .EQ. 1) RETURN", *parameter_column,
        "      END SUBROUTINE FUNC", "", rhs, linear,
        "      SUBROUTINE STPNT(NDIM,U,PAR,T)", "      IMPLICIT NONE", "      INTEGER, INTENT(IN) :: NDIM",
        "      DOUBLE PRECISION, INTENT(INOUT) :: U(NDIM),PAR(*)", "      DOUBLE PRECISION, INTENT(IN) :: T",
        "      DOUBLE PRECISION :: angle", "      angle = 2.0d0 * acos(-1.0d0) * T", *start_values,
        "      END SUBROUTINE STPNT", "",
        *(f"      SUBROUTINE {name}\n      END SUBROUTINE {name}\n" for name in ("BCND", "ICND", "FOPT", "PVLS"))])


_DRIVER = """      PROGRAM CHECK_EXPORT
      IMPLICIT NONE
      INTEGER :: k, count, ICP(2)
      DOUBLE PRECISION :: U({n}), PAR(36), F({n}), DFDU({n},{n}), DFDP({n},36)
      READ(*,*) count
      DO k = 1, count
        READ(*,*) U, PAR(1:10)
        CALL FUNC({n}, U, ICP, PAR, 2, F, DFDU, DFDP)
        WRITE(*,'(*(ES26.17E3))') F, DFDU, DFDP(:,1)
      END DO
      END PROGRAM CHECK_EXPORT
"""


def check_export(system, parameter: str, source: str, pars, states, values) -> dict:
    """The equation file ``source`` compiled with a driver and evaluated at ``states`` (N, n) and the parameter's
    ``values`` (N,), other parameters ``pars``: {"rhs", "Jacobian", "parameter derivative": the largest difference
    from the System's f, its exact Jacobian and its exact d f / d parameter, relative to each one's max norm}."""
    n, slots, k = system.n, parameter_slots(system, parameter), system.parameter_index(parameter)
    with tempfile.TemporaryDirectory(prefix="auto-export-") as folder:
        folder = Path(folder)
        (folder / "model.f90").write_text(source)
        (folder / "driver.f90").write_text(_DRIVER.format(n=n))
        subprocess.run(["gfortran", "-o", "check", "driver.f90", "model.f90"], cwd=folder, check=True,
                       capture_output=True)
        lines = [str(len(states))]
        for state, value in zip(states, values):
            par = np.zeros(len(PARAMETER_SLOTS))
            for index, slot in slots.items():
                par[slot - 1] = value if index == k else pars[index]
            lines.append(" ".join(repr(float(v)) for v in (*state, *par)))
        out = subprocess.run(["./check"], cwd=folder, input="\n".join(lines), check=True, capture_output=True,
                             text=True).stdout
    rows = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    errors = {"rhs": 0.0, "Jacobian": 0.0, "parameter derivative": 0.0}
    linear = system.linearisation_function((parameter,))
    for row, state, value in zip(rows, states, values):
        p = np.array(pars, dtype=float)
        p[k] = value
        exact = system.evaluate(linear, state, p)
        pairs = {"rhs": (row[:n], system.f(state, p)),
                 "Jacobian": (row[n:n + n * n].reshape(n, n, order="F"), system.jacobian(state, p)),
                 "parameter derivative": (row[n + n * n:], exact[n + n * n:])}
        for name, (exported, reference) in pairs.items():
            scale = max(float(np.max(np.abs(reference))), np.finfo(float).tiny)
            errors[name] = max(errors[name], float(np.max(np.abs(exported - reference))) / scale)
    return errors


def unavailable() -> str | None:
    """Why AUTO-07p cannot run here (bifpy or gfortran missing), or None."""
    try:
        import bifpy  # noqa: F401
    except ImportError as exc:
        return f"bifpy is not importable ({exc})"
    return None if shutil.which("gfortran") else "gfortran is not on PATH"


def hopf_start(system, state, pars, amplitude: float) -> tuple:
    """(the small orbit's complex amplitudes 2 r q (n,), its period 2 pi / omega) at the Hopf point (``state``,
    ``pars``): q the unit eigenvector of the eigenvalue i omega (largest imaginary part), r = ``amplitude``."""
    values, vectors = np.linalg.eig(system.jacobian(state, pars))
    k = int(np.argmax(values.imag))
    return 2 * amplitude * vectors[:, k] / np.linalg.norm(vectors[:, k]), 2 * math.pi / float(values[k].imag)


def run(source: str, ndim: int, *, ntst: int, bounds, marks=(), ncol: int = 4, nmx: int = 1000, ds: float = 0.01,
        ds_max: float = 0.5) -> tuple:
    """AUTO-07p's periodic-orbit branch (IPS 2, exact Jacobian JAC 1, ``ntst`` x ``ncol``, its default tolerances
    EPSL = EPSU = 1e-7, EPSS = 1e-5) of the equation file ``source`` (:func:`equation_file`) in PAR(1) within
    ``bounds`` (RL0, RL1), user points at ``marks``, at most ``nmx`` points: (bifpy's result, wall time [s], CPU
    time [s] of this process and its children (gfortran, AUTO-07p), AUTO-07p's own total time [s] or nan)."""
    from bifpy import auto
    from bifpy.auto import _transpile

    settings = dict(ips=auto.IPS_PERIODIC_ORBIT, ndim=ndim, npar=len(PARAMETER_SLOTS), nmx=nmx, ntst=ntst, ncol=ncol,
                    iad=3, ilp=1, isp=2, itmx=9, itnw=5, nwtn=3, jac=1, ds=ds, dsmin=1e-5, dsmax=ds_max,
                    rl0=float(bounds[0]), rl1=float(bounds[1]), a0=-1e300, a1=1e300, epsl=1e-7, epsu=1e-7, epss=1e-5)
    wall, cpu = time.perf_counter(), cpu_time()
    with mock.patch.object(_transpile, "generate_equation_file", lambda *args, **keywords: source):
        result = auto.run(lambda u, p: None, lambda u, p, t: None, settings, icu=[1, auto.PERIOD_INDEX],
                          uzr={1: list(marks)} if marks else None, jac=auto.AUTO_JACOBIAN, transpile=True,
                          keep_output=True)
    wall, cpu = time.perf_counter() - wall, cpu_time() - cpu
    folder = Path(result.output_directory)
    found = _TOTAL_TIME.search((folder / "stdout.txt").read_text()) if (folder / "stdout.txt").exists() else None
    shutil.rmtree(folder)
    return result, wall, cpu, float(found[1]) if found else math.nan


_CODES = {"BRANCH_POINT": "BP", "FOLD": "LP", "HOPF_BIFURCATION": "HB", "PERIOD_DOUBLING": "PD", "TORUS": "TR",
          "USER_SPECIFIED_VALUE": "UZ", "END_POINT": "EP", "ABNORMAL_TERMINATION": "MX"}


def code(point) -> str:
    """AUTO-07p's two-letter type of a point of bifpy's result (BP, LP, PD, TR, UZ, EP, MX, ...)."""
    name = point.point_type.name
    return _CODES.get(name, name)


def cpu_time() -> float:
    """CPU time [s] of this process (all threads) and of its finished children."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def marked_orbits(result, marks, segments: int, tolerance: float = 1e-3) -> dict:
    """{mark: (AUTO-07p's parameter there, its period, its orbit at ``segments`` equal steps of time (segments, n),
    its Floquet multipliers)} at the labeled point nearest to each of ``marks`` (its user point, or the special point
    it labeled there instead) within ``tolerance`` of it, on the branch's first pass (before its first fold LP; the
    parameter also steps back where AUTO-07p locates a special point, so a step back is no turn)."""
    from scipy.interpolate import CubicSpline

    points = result.branches[0].points
    turn = next((k for k, p in enumerate(points) if code(p) == "LP"), len(points))
    labeled = [p for p in points[:turn] if p.is_labeled and p.periodic_orbit is not None]
    found = {}
    for mark in marks:
        point = min(labeled, key=lambda p: abs(float(p.parameters[0]) - mark), default=None)
        if point is None or abs(float(point.parameters[0]) - mark) > tolerance:
            continue
        orbit = point.periodic_orbit
        states = CubicSpline(orbit.normalized_time, np.array(orbit.state))(np.arange(segments) / segments)
        found[mark] = (float(point.parameters[0]), float(orbit.period), states, point.floquet_multipliers)
    return found

"""The package's structure: arrows point down, no import cycles, test helpers stay out of the library."""

from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "tippedisk_analysis"
# lower layers must not import higher ones (DESIGN.md: parameters -> models -> solvers -> results -> analysis -> fronts)
LAYERS = {
    # the generic dynamics layer knows nothing of the disk
    "dynamics": {"models", "solvers", "parameters", "kinematics", "analysis", "cli", "plotting", "testing"},
    "models": {"solvers", "analysis", "cli", "plotting", "testing"},
    "solvers": {"analysis", "cli", "plotting", "testing"},
    "analysis": {"cli", "plotting", "testing"},
    "plotting": {"cli", "testing"},
    "cli": {"testing"},
}


def _imports(path: Path) -> set[str]:
    """Absolute names of the tippedisk_analysis modules ``path`` imports (module- and function-level)."""
    module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = package
            for _ in range(max(node.level - 1, 0)):
                base = base.rpartition(".")[0]
            name = f"{base}.{node.module}" if node.level and node.module else (node.module or base)
            found.add(name)
            found.update(f"{name}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {n for n in found if n.startswith("tippedisk_analysis.")}


def _sources():
    return sorted(PACKAGE.rglob("*.py"))


@pytest.mark.parametrize("path", _sources(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_arrows_point_down(path):
    parts = path.relative_to(PACKAGE).parts
    layer = parts[0] if len(parts) > 1 else path.stem
    forbidden = LAYERS.get(layer, set()) | ({"testing"} if path.stem != "testing" else set())
    bad = [name for name in _imports(path) if name.split(".")[1] in forbidden and name.split(".")[1] != layer]
    assert not bad, f"{path.relative_to(PACKAGE)} imports {bad} (a higher layer or the test helpers)"


MAX_LINES = 500
OVERSIZED: set[str] = set()
"""Modules still to be split (issue 23 lands in steps); the list only shrinks."""


@pytest.mark.parametrize("path", _sources(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_above_500_lines(path):
    """One concern per module: a module that grows past MAX_LINES splits by concern, not by size."""
    name = str(path.relative_to(PACKAGE))
    lines = len(path.read_text().splitlines())
    if name in OVERSIZED:
        assert lines > MAX_LINES, f"{name} has {lines} lines now: take it off OVERSIZED"
    else:
        assert lines <= MAX_LINES, f"{name} has {lines} lines, more than {MAX_LINES}: split it by concern"


def test_no_import_cycles():
    graph = {}
    for path in _sources():
        name = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")
        graph[name] = {n for n in _imports(path) if n != name}
    modules = set(graph)
    graph = {k: {n for n in v if n in modules and not k.startswith(n + ".")} for k, v in graph.items()}
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in graph[node]:
            if state.get(nxt) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])


def test_every_subpackage_is_installed():
    """pyproject.toml lists the packages explicitly (studies are mapped in): none may be forgotten."""
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(PACKAGE.parent).parts) for p in PACKAGE.rglob("__init__.py")}
    assert found | {"tippedisk_studies"} == listed


def test_importing_the_package_compiles_nothing():
    code = ("import sys, tippedisk_analysis, tippedisk_analysis.cli; "
            "print(sorted(m for m in ('numba', 'heyoka', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


INTEGRATOR_BUILDERS = {"taylor_adaptive", "taylor_adaptive_batch", "var_ode_sys"}
"""heyoka's integrator constructors: only the generic layer calls them (System.taylor), so every model of the
disk is integrated, linearised and sectioned the one way."""


@pytest.mark.parametrize("path", [p for p in _sources() if p.relative_to(PACKAGE).parts[0] != "dynamics"],
                         ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_integrator_is_built_outside_dynamics(path):
    calls = [node.func.attr for node in ast.walk(ast.parse(path.read_text()))
             if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
             and node.func.attr in INTEGRATOR_BUILDERS]
    assert not calls, (f"{path.relative_to(PACKAGE)} builds a heyoka integrator ({', '.join(calls)}); declare the "
                       "model as a dynamics.System and take System.taylor")


def test_the_integrator_rule_sees_a_builder():
    """The rule above is not vacuous: the generic layer's System.taylor is found by it."""
    tree = ast.parse((PACKAGE / "dynamics" / "system.py").read_text())
    found = {node.func.attr for node in ast.walk(tree)
             if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)}
    assert {"taylor_adaptive", "taylor_adaptive_batch", "var_ode_sys"} <= found

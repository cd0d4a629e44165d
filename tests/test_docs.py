"""The code examples of the documentation pages run as printed (the tutorials run when the site is built:
`bash run.sh docs`, part of CI), and what they compute ended well."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import xarray as xr

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = ["getting_started.md", "python.md", "continuation.md", "periodic_orbits.md", "fitting.md"]  # dynamics*.md: their own test
BAD = ("failed", "nonfinite", "not_converged", "corrector_failed")


def code_blocks(page: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", (DOCS / page).read_text(), re.S | re.M)


def test_every_page_with_python_examples_is_tested():
    with_code = {p.name for p in DOCS.glob("*.md") if code_blocks(p.name)}
    assert with_code == set(PAGES) | {"dynamics.md", "dynamics_hybrid.md"}


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES)
def test_the_examples_of_a_page_run(page, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    exec("import tippedisk_analysis as td", ns)
    blocks = code_blocks(page)
    assert blocks
    for block in blocks:
        exec(compile(block, f"docs/{page}", "exec"), ns)
    datasets = {k: v for k, v in ns.items() if isinstance(v, xr.Dataset)}
    assert datasets or page == "periodic_orbits.md"
    for name, ds in datasets.items():
        assert ds.attrs.get("status") not in BAD, f"{page}: {name} ended {ds.attrs.get('status')}"


def _api_examples() -> dict:
    namespace: dict = {}
    exec((DOCS / "api_examples.py").read_text(), namespace)
    return namespace["EXAMPLES"]


def test_every_module_of_the_api_reference_has_an_example():
    source = (DOCS / "conf.py").read_text()
    modules = re.findall(r'^\s+\("(tippedisk_analysis[\w.]*)", "', source[source.index("API_MODULES"):], re.M)
    assert modules and set(modules) == set(_api_examples())


@pytest.mark.slow
@pytest.mark.parametrize("module", sorted(_api_examples()))
def test_the_api_examples_run(module, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(_api_examples()[module], f"docs/api_examples.py:{module}", "exec"), namespace)
    datasets = {k: v for k, v in namespace.items() if isinstance(v, xr.Dataset)}
    for name, ds in datasets.items():
        assert ds.attrs.get("status") not in BAD, f"{module}: {name} ended {ds.attrs.get('status')}"


def test_the_readme_links_resolve():
    root = DOCS.parent
    text = (root / "README.md").read_text()
    targets = [t.split("#")[0] for t in re.findall(r"\]\(([^)]+)\)", text) if "://" not in t]
    assert len(targets) > 10
    missing = [t for t in targets if not (root / t).exists()]
    assert not missing, f"README links to missing files: {missing}"

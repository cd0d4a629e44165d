"""Sphinx configuration of the documentation site (``bash run.sh docs`` -> docs/_build/html).

The command-line page and the API reference are generated here from the argparse definitions and the
public modules' ``__all__`` at every build, so they cannot drift from the code. Tutorials (docs/tutorials/)
are MyST notebooks executed during the build (cached in docs/_build/.jupyter_cache).
"""

from __future__ import annotations

import importlib
import logging
import os
import re
from pathlib import Path

import tippedisk_analysis
from tippedisk_analysis.plotting.style import STYLE

HERE = Path(__file__).resolve().parent
logging.getLogger("traitlets").setLevel(logging.WARNING)  # nbclient's "Executing notebook" lines: not the build's news
GENERATED = HERE / "_generated"

project = "tippedisk_analysis"
author = "the tippedisk_analysis developers"
copyright = "2026, the tippedisk_analysis developers"
release = version = tippedisk_analysis.__version__
extensions = ["myst_nb", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax",
              "sphinx-mathjax-offline"]  # MathJax served with the site: formulas render without a network
exclude_patterns = ["_build", "*.py", "**/.ipynb_checkpoints"]
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath", "amsmath"]  # $...$ and $$...$$ rendered by MathJax
nb_execution_mode = "cache"
nb_execution_cache_path = str(HERE / "_build" / ".jupyter_cache")
nb_execution_timeout = 300
nb_execution_raise_on_error = True
autodoc_member_order = "bysource"
autodoc_typehints = "none"
napoleon_numpy_docstring = True
html_theme = "furo"  # wraps code and tables to the window, fits a laptop screen
html_title = f"tippedisk_analysis {release}"
html_static_path = ["_static"]
html_css_files = ["site.css"]  # option names unbroken, long lines scroll in their box, the title fits 390 px
suppress_warnings = ["myst.header"]  # pages written for GitHub start at level-2 headings in places
smartquotes = False  # "--disk" stays two hyphens in option tables and prose (no en dash)

# the public modules of the API reference: (module, title); a module's public names are its __all__
API_MODULES = (
    ("tippedisk_analysis", "Top level: parameters, simulation, datasets"),
    ("tippedisk_analysis.dynamics", "The generic dynamics layer"),
    ("tippedisk_analysis.analysis.stationary", "Stationary spins"),
    ("tippedisk_analysis.analysis.stability", "Stability of the spins"),
    ("tippedisk_analysis.analysis.maps", "Stability maps and critical spin speeds"),
    ("tippedisk_analysis.analysis.spin_continuation", "Continuation of the spins"),
    ("tippedisk_analysis.analysis.reduced", "The symmetry-reduced tippedisk"),
    ("tippedisk_analysis.analysis.orbits", "Periodic orbits of the tippedisk"),
    ("tippedisk_analysis.analysis.lyapunov", "Lyapunov exponents of the tippedisk"),
    ("tippedisk_analysis.analysis.poincare", "Poincaré sections"),
    ("tippedisk_analysis.analysis.outcome_map", "Outcome maps"),
    ("tippedisk_analysis.analysis.basins", "Basins and basin fractions"),
    ("tippedisk_analysis.analysis.bifurcation", "Bifurcation diagrams"),
    ("tippedisk_analysis.analysis.rolling", "The rolling disk"),
    ("tippedisk_analysis.analysis.inversion", "Whether a start inverts: the threshold of the initial spin"),
    ("tippedisk_analysis.analysis.critical_spin", "The critical spin in closed form"),
    ("tippedisk_analysis.analysis.spin_passage", "After the inversion: the passage along the inverted spins"),
    ("tippedisk_analysis.analysis.nutation_cycles", "The held model's nutation cycles"),
    ("tippedisk_analysis.analysis.free_nutation", "The free disk's nutation, averaged"),
    ("tippedisk_analysis.plotting", "Figures and animations"),
    ("tippedisk_analysis.solvers.moreau", "Moreau time stepping"),
)


# names a module's reference page leads with (what a user calls first); the rest follow in __all__ order
LEAD = {
    "tippedisk_analysis.dynamics": (
        "System", "equilibrium_branch", "special_point_curve", "orbit_branch", "hopf_branch", "find_orbit",
        "continue_orbits", "lyapunov_spectrum", "basins", "Grid", "poincare_section", "homoclinic_point",
        "homoclinic_scan", "homoclinic_curve", "symmetric_family", "Shooting", "family_drift", "drift_at",
        "HybridSystem", "Guard", "Jump", "simulate_hybrid", "find_hybrid_orbit", "filippov_system",
        "textbook_system", "Event", "branch_dataset"),
}


def _cli_examples() -> dict:
    """The first example of each command printed in the docs or the README (``tippedisk NAME ...``)."""
    from tippedisk_analysis.cli.registry import COMMANDS

    text = "\n".join(p.read_text() for p in sorted(HERE.glob("*.md"))) + (HERE.parent / "README.md").read_text()
    found = {}
    for name in COMMANDS:
        lines = re.findall(r"^(?:\\$ )?(tippedisk " + re.escape(name) + r"\b[^\n]*)", text, re.M)
        if lines:
            found[name] = lines[0]
    return found


def _cli_pages() -> dict:
    """{path: text}: the overview of ``tippedisk`` and one page per command (usage, options table, example)."""
    import argparse

    from tippedisk_analysis.cli import build_parser
    from tippedisk_analysis.cli.registry import COMMANDS

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    summaries = {a.dest: a.help or "" for a in sub._choices_actions}
    examples = _cli_examples()
    overview = ["# Command line", "", "Generated from the argparse definitions of `tippedisk` at build time. "
                "Every command ends with a one-line result; bad input gives one line naming the problem and exit "
                "status 2.", "", "| command | what it does |", "|---|---|"]
    overview += [f"| [`tippedisk {name}`](cli/{name}.md) | {_cell(summaries.get(name, ''))} |" for name in COMMANDS]
    overview += ["", "```{toctree}", ":hidden:", "", *(f"cli/{name}" for name in COMMANDS), "```", ""]
    pages = {"cli.md": "\n".join(overview)}
    for name in COMMANDS:
        command = sub.choices[name]
        formatter = command._get_formatter()
        lines = [f"# tippedisk {name}", "", command.description or summaries.get(name, ""), "", "```text",
                 command.format_usage().strip(), "```", "", "| option | default | meaning |", "|---|---|---|"]
        for action in command._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            flags = ", ".join(f"`{flag}`" for flag in action.option_strings) or f"`{action.metavar or action.dest}`"
            text = " ".join(formatter._expand_help(action).split()) if action.help else ""
            stored = "" if action.default in (None, argparse.SUPPRESS, False, []) or not action.option_strings \
                else str(action.default)
            value = action.option_strings and action.nargs != 0  # a flag's help names no value of its own
            default = (_help_default(text, bare=False) or stored or value and _help_default(text)) if text else stored
            lines.append(f"| {flags} | {f'`{_cell(default)}`' if default else ''} | {_cell(text)} |")
        if name in examples:
            lines += ["", "Example:", "", "```bash", examples[name], "```"]
        pages[f"cli/{name}.md"] = "\n".join(lines) + "\n"
    return pages


def _clause(text: str) -> str:
    """``text`` up to its first ``;``, ``, ``, ``: `` or unbalanced ``)`` (the value a help gives, not its gloss)."""
    depth = 0
    for i, char in enumerate(text):
        depth += (char == "(") - (char == ")")
        if depth < 0 or (depth == 0 and (char == ";" or text.startswith((", ", ": "), i))):
            return text[:i].strip()
    return text.strip()


def _help_default(text: str, bare: bool = True) -> str:
    """The default an option's help gives: "(default X)", "(Table 2: X)", or (``bare``) a value in parentheses
    after the option's unit or ending the help, "[m] (0.045)", "(--disk geometry; 0.015)"; "" when it gives
    none. A default given for another option ("--to E_MAX [J] (default ...)") is not this option's."""
    for said in re.finditer(r"\bdefault\b:?\s+(?=\S)|\(([^()]*;\s*)?Table \d+:\s*", text):
        if not re.search(r"--[\w-]+ [A-Z][A-Z_]*(?: \[[^]]*\])? \($", text[:said.start()]):
            return _clause(text[said.end():])
    for group in re.finditer(r"(?:(?<=\] )|^)\(|\((?=[^()]*\)$)", text) if bare else ():
        rest = text[group.end():]
        while rest:
            value = _clause(rest)
            if re.fullmatch(r"(?!default)-?[\w.+/ ]{1,24}", value) and re.search(r"\d|pi|^-", value):
                return value
            rest = rest[len(value):].lstrip() if rest[len(value):].lstrip().startswith(";") else ""
            rest = rest[1:]
    return ""


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _api_examples() -> dict:
    namespace: dict = {}
    exec((HERE / "api_examples.py").read_text(), namespace)
    return namespace["EXAMPLES"]


def _api_pages() -> dict:
    """{path: text}: the overview of the public modules and one page per module (every name in its
    ``__all__`` with its docstring)."""
    overview = ["# API reference", "",
                "Every function and class that a public module lists in `__all__`, with its docstring, a page per "
                "module. Modules not listed here (the analysis modules' helpers, models, the CLI) are internal.", "",
                "| module | contents |", "|---|---|"]
    pages, documented = {}, set()  # an object a second module re-exports is described once (:no-index: after)
    examples = _api_examples()
    for module_name, title in API_MODULES:
        module = importlib.import_module(module_name)
        slug = module_name.replace("tippedisk_analysis", "td").replace(".", "_")
        overview.append(f"| [`{module_name}`](api/{slug}.md) | {title} |")
        summary = (module.__doc__ or "").strip().split("\n\n")[0]
        summary = re.sub(r":(?:class|func|mod|meth|attr):`~?\.?([^`]+)`", r"`\1`", summary)  # markdown, not RST roles
        lines = [f"# {title}", "", f"`{module_name}`: {summary}", ""]
        if module_name in examples:  # docs/api_examples.py (tests/test_docs.py runs each)
            lines += ["Example:", "", "```python", examples[module_name].strip(), "```", ""]
        lead = LEAD.get(module_name, ())
        names = [*lead, *(n for n in module.__all__ if n not in lead)]
        names = [n for n in names if not n.startswith("__") and callable(getattr(module, n))]
        lines += ["| name | what it does |", "|---|---|"]
        for name in names:
            obj = getattr(module, name)
            target = f"{obj.__module__}.{obj.__qualname__}"
            lines.append(f"| {{py:obj}}`{name} <{target}>` | {_cell(_first_sentence(obj))} |")
        lines.append("")
        for name in names:
            obj = getattr(module, name)
            kind = "autoclass" if isinstance(obj, type) else "autofunction"
            target = f"{obj.__module__}.{obj.__qualname__}"
            members = ["   :members:"] if kind == "autoclass" and not issubclass(obj, Exception) else []
            members += ["   :no-index:"] if target in documented else []
            documented.add(target)
            lines += ["```{eval-rst}", f".. {kind}:: {target}", *members, "```", ""]
        pages[f"api/{slug}.md"] = "\n".join(lines)
    overview += ["", "```{toctree}", ":hidden:", "", *(p.removesuffix(".md") for p in pages), "```", ""]
    return {"api.md": "\n".join(overview), **pages}


def _first_sentence(obj) -> str:
    """The first sentence of an object's docstring, RST roles as code: its one-line description."""
    import inspect

    text = " ".join((inspect.getdoc(obj) or "").split("\n\n")[0].split())
    text = re.sub(r":(?:class|func|mod|meth|attr|data):`~?\.?([^`]+)`", r"`\1`", text).replace("``", "`")
    end = re.search(r"(?<!e\.g)(?<!i\.e)(?<!\bFigs)(?<!\bFig)(?<!\bSect)(?<!\bEq)(?<!\bcf)\.(\s|$)", text)
    text = text[:end.start() + 1] if end else text
    if len(text) <= 160:
        return text
    clause = text.find(";", 40, 160)  # the first clause when the sentence runs on
    return text[:clause] + " ..." if clause > 0 else text[:text.rfind(" ", 0, 156)] + " ..."


def _schema_page() -> str:
    """Every dataset kind with the variables of its stored example (data/) that has the most, their dims, units
    and names."""
    from tippedisk_analysis import results

    examples: dict[str, tuple[str, object]] = {}
    for path in sorted((HERE.parent / "data").rglob("*.nc")):
        ds = results.load(path)
        kind = ds.attrs["kind"]
        if kind not in examples or len(ds.data_vars) > len(examples[kind][1].data_vars):
            examples[kind] = (str(path.relative_to(HERE.parent)), ds)
    lines = ["# Dataset kinds and their variables", "",
             "Generated at build time from the fullest stored example of each kind in `data/` (conventions: "
             "[the dataset schema](../datasets.md)). A run of other settings can add or omit variables "
             "(a model's own outputs, a system's states).", ""]
    for kind, (path, ds) in sorted(examples.items()):
        lines += [f"## {kind}", "", f"Example: `{path}`; dims {', '.join(f'{k} ({v})' for k, v in ds.sizes.items())}.",
                  "", "| variable | dims | units | long_name |", "|---|---|---|---|"]
        for name, var in ds.data_vars.items():
            long = str(var.attrs.get("long_name", "")).replace("|", "\\|")
            lines.append(f"| `{name}` | {', '.join(var.dims) or 'scalar'} | {var.attrs.get('units', '')} | {long} |")
        lines.append("")
    return "\n".join(lines)


def _generate(_app=None, _config=None) -> None:
    for folder in ("cli", "api"):
        (GENERATED / folder).mkdir(parents=True, exist_ok=True)
    for name, text in (*_cli_pages().items(), *_api_pages().items(), ("schema.md", _schema_page())):
        path = GENERATED / name
        if not path.exists() or path.read_text() != text:
            path.write_text(text)


KERNEL_CONFIG = """c.IPKernelApp.log_level = "ERROR"
c.InteractiveShellApp.exec_lines = [
    "import warnings; warnings.filterwarnings('ignore', message=r'compiling .* \\(first use on this machine')"]
c.InlineBackend.rc = """ + repr({**STYLE, "figure.dpi": 100}) + "\n"  # the tutorials' figures in the figure style


def _quiet_kernels() -> None:
    """The tutorials' kernels log at ERROR: ipykernel warns at every start that a local TCP kernel is not
    encrypted (the build runs on one machine; nothing leaves it), which buried the build's real messages. They
    ignore the package's CompileNotice (a build on a machine without heyoka's disk cache compiles everything
    once): a tutorial shows no compile notice, and with it no path of the build machine. Their figures draw in
    the site's figure style (12-pt text)."""
    profile = GENERATED / "ipython" / "profile_default"
    profile.mkdir(parents=True, exist_ok=True)
    (profile / "ipython_kernel_config.py").write_text(KERNEL_CONFIG)
    os.environ["IPYTHONDIR"] = str(profile.parent)


def _link_images(app, doctree, docname) -> None:
    """Every image links to its full-size file: Sphinx links only the images it scales (``:width:``), which left
    the tutorials' outputs and the images of markdown tables without one."""
    if app.builder.format != "html":
        return
    from docutils import nodes
    from sphinx.util.osutil import relative_uri

    images = relative_uri(app.builder.get_target_uri(docname), "_images")
    for node in list(doctree.findall(nodes.image)):
        stored = app.env.images.get(node["uri"])
        if isinstance(node.parent, nodes.reference) or stored is None or any(
                key in node for key in ("scale", "width", "height")):
            continue  # already a link, a remote image, or one Sphinx links itself
        link = nodes.reference("", "", internal=True, refuri=f"{images}/{stored[1]}")
        node.replace_self(link)
        link.append(node)


def setup(app):
    _quiet_kernels()
    app.connect("config-inited", _generate)
    app.connect("doctree-resolved", _link_images)

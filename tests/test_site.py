"""The built site as a researcher reads it: no working notes, formulas typeset, pages of a readable length, a
landing page with a quick start.

Reads docs/_build/html when it is newer than every source page; otherwise builds the site once per session
into a temporary folder (the tutorials' outputs come from the build's cache, docs/_build/.jupyter_cache). Every
check of the built site lives here, so that a test run builds it at most once; they are slow checks (a fresh build
executes the tutorials).
"""

from __future__ import annotations

import html
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

DOCS = Path(__file__).resolve().parents[1] / "docs"
MAX_WORDS = 4000

# Pages exempt from the checks of the published text (none: every page is cleaned)
PENDING: set[str] = set()
# Pages of results, each shown with at least one figure (built page names; the inversion's topic pages by prefix)
ANALYSIS_PAGES = re.compile(r"^(stability|continuation|periodic_orbits|periodic_orbits_tippedisk|dynamics|attractors"
                            r"|trajectories|rolling|inversion(_\w+)?)\.html$")
# Figure text beside 16-px body text: the smallest text of a figure shown in furo's text column (590 px at its
# narrowest desktop layout; 736 px at a 1366-px window, measured in Chromium) renders at least this large
COLUMN_PX = 590
MIN_FIGURE_TEXT_PX = 14
# On a phone (390 px wide, a ~350-px column) a figure keeps a minimum width (site.css) at which its text is this large
PHONE_TEXT_PX = 12
# Figures on analysis pages that are not drawn in the plotting package's style, and why
FIGURE_TEXT_EXEMPT: dict[str, str] = {}  # none: every study figure is drawn in the style, from data/ (REDRAWN)
# Reference generated from the code (docstrings, argparse) and the changelog are not prose pages for the length
LENGTH_EXEMPT = re.compile(r"^(_generated/|changelog\.html$|genindex\.html$|search\.html$|py-modindex\.html$)")

PROCESS_NOTES = re.compile(
    r"\bissues?\s+#?\d+|\bthe issue\b|\breview(?:er|ers|s)?\b|\bpy-spy\b|\bcommits?\s+[0-9a-f]{7,40}\b"
    r"|(?<![\w./-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}(?![\w./-])"  # a bare commit hash
    r"|\bnot done\b|\bshared (?:machine|with)\b|\bother sessions\b|\bone attempt\b|\btried by\b",
    re.I)
RAW_FORMULA = re.compile(r"sqrt\(|\^\s*[-+(0-9A-Za-z{]")
# Symbols written as plain text: "r + 0.8 e", z_S, P_N, E_tot, "Omega = 40 rad/s", "eps 0.1", "3 pi / 16"
PLAIN_NOTATION = re.compile(r"\br [+-] (?:\d*\.?\d+ )?e\b|\b(?:z_S|P_N|E_tot|g_N1|omega_c|alpha_dot|Omega|eps|gamma)\b"
                            r"|\d ?(?:π|pi) ?/ ?\d")
# Pages whose text comes from files outside docs/ (data/README.md, studies/README.md, the Sect. 6 table a study writes)
INCLUDED_TEXT = {"paper.html", "data_catalogue.html", "studies_analysis.html", "studies_catalogue.html"}


def _sources_mtime() -> float:
    sources = [*DOCS.glob("*.md"), *DOCS.glob("tutorials/*.md"), *DOCS.glob("_static/*"), DOCS / "conf.py",
               DOCS.parent / "README.md"]
    return max(p.stat().st_mtime for p in sources)


@pytest.fixture(scope="session")
def site(tmp_path_factory) -> Path:
    """The built site's folder: docs/_build/html when it is up to date, else a fresh build."""
    built = DOCS / "_build" / "html"
    index = built / "index.html"
    if index.exists() and index.stat().st_mtime >= _sources_mtime():
        return built
    out = tmp_path_factory.mktemp("site") / "html"
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS),
                           str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


def pages(site: Path) -> dict[str, str]:
    """{path relative to the site: the HTML of the page's article}."""
    found = {}
    for path in sorted(site.rglob("*.html")):
        name = path.relative_to(site).as_posix()
        if name.startswith(("_static/", "_sources/", "_images/")):
            continue
        text = path.read_text(encoding="utf-8")
        article = re.search(r"<article[^>]*>(.*?)</article>", text, re.S)
        found[name] = article.group(1) if article else text
    return found


def prose(article: str) -> str:
    """The text a reader sees outside code blocks, inline code and typeset math."""
    text = re.sub(r"<(script|style|pre)\b.*?</\1>", " ", article, flags=re.S)
    text = re.sub(r'<(span|div) class="math[^"]*">.*?</\1>', " ", text, flags=re.S)
    text = re.sub(r"<code\b.*?</code>", " ", text, flags=re.S)
    text = re.sub(r"<[^>]+>", " ", text)
    return html.unescape(text)


def headings(article: str) -> list[str]:
    return re.findall(r"<h[1-6][^>]*>(.*?)</h[1-6]>", article, re.S)


def test_no_working_notes_in_the_published_text(site):
    """Issue numbers, reviews, attempts, commit hashes, machine load and tool names are history, not results."""
    found = {name: sorted({m.group(0) for m in PROCESS_NOTES.finditer(prose(body) + " ".join(
                 re.findall(r"<code\b[^>]*>(.*?)</code>", body, re.S)))})
             for name, body in pages(site).items() if name not in PENDING and not name.startswith("changelog")}
    assert not {k: v for k, v in found.items() if v}


def test_formulas_are_typeset_in_prose_and_absent_from_headings(site):
    """`sqrt(` or a power `^2` in the reader's text is a formula left raw; a heading holds no formula."""
    raw, in_headings = {}, {}
    for name, body in pages(site).items():
        if name in PENDING or name.startswith(("_generated/", "changelog")):
            continue
        hits = [line.strip()[:80] for line in prose(body).splitlines() if RAW_FORMULA.search(line)]
        if hits:
            raw[name] = hits
        bad = [h for h in headings(body) if 'class="math' in h or RAW_FORMULA.search(prose(h))]
        if bad:
            in_headings[name] = bad
    assert not raw, raw
    assert not in_headings, in_headings


def test_symbols_in_prose_are_typeset(site):
    """A height r + 0.8 e, a force P_N or an angle 3 pi / 16 in the reader's text is math: $r + 0.8e$, $P_N$."""
    plain = {name: sorted({m.group(0) for m in PLAIN_NOTATION.finditer(prose(body))})
             for name, body in pages(site).items()
             if name not in INCLUDED_TEXT and not name.startswith(("_generated/", "changelog", "genindex"))}
    assert not {name: hits for name, hits in plain.items() if hits}


def test_pages_are_of_a_readable_length(site):
    words = {name: len(prose(body).split()) for name, body in pages(site).items()}
    long = {name: n for name, n in words.items()
            if n > MAX_WORDS and name not in PENDING and not LENGTH_EXEMPT.match(name)}
    assert not long, f"pages over {MAX_WORDS} words: {long}"


def test_the_landing_page_has_a_quick_start(site):
    """The first page says what the package does and how to run it from a fresh clone, tippedisk on PATH."""
    body = pages(site)["index.html"]
    assert re.search(r"<h2[^>]*>\s*Quick start", body)
    quick = body[re.search(r"<h2[^>]*>\s*Quick start", body).end():]
    block = html.unescape(re.sub(r"<[^>]+>", "", re.search(r"<pre>(.*?)</pre>", quick, re.S).group(1)))
    assert "bash run.sh demo" in block
    assert "source .venv/bin/activate" in block or ".venv/bin/tippedisk" in block
    assert len([line for line in block.splitlines() if line.strip()]) <= 6
    assert "<img" in body and "paper.html" in body and "tutorials/" in body and "_generated/api.html" in body


def test_the_site_renders_math_titles_and_tutorial_figures(site):
    """Formulas go to MathJax (not raw text), no page title carries an internal issue number, every tutorial shows
    at least one figure."""
    models = (site / "models.html").read_text()
    assert models.count('class="math notranslate nohighlight"') >= 5 and "mathjax" in models.lower()
    assert r"\tag{2.29}" in models or "(2.29)" in models
    titles = {p.name: re.search(r"<title>(.*?)</title>", p.read_text(), re.S).group(1) for p in site.rglob("*.html")}
    assert not [name for name, title in titles.items() if "(issue" in title]
    tutorials = sorted((site / "tutorials").glob("*.html"))
    assert len(tutorials) == len(list((DOCS / "tutorials").glob("*.md")))
    assert not [p.name for p in tutorials if "<img" not in p.read_text()]


def test_every_analysis_page_shows_a_figure(site):
    found = [name for name in pages(site) if ANALYSIS_PAGES.match(name)]
    assert not [name for name in found if "<img" not in pages(site)[name]]
    assert len(found) >= 14, found


def test_every_image_links_to_its_full_size_file(site):
    """A plain <a href> to the image's own file around each <img>: a reader enlarges a figure by a click."""
    unlinked = {}
    for name, body in pages(site).items():
        folder = (site / name).parent
        for match in re.finditer(r'<img\b[^>]*\bsrc="([^"]+)"', body):
            link = re.search(r'<a\b[^>]*\bhref="([^"#]+)"[^>]*>\s*$', body[:match.start()])
            if not link or link.group(1) != match.group(1) or not (folder / link.group(1)).is_file():
                unlinked.setdefault(name, []).append(match.group(1))
    assert not unlinked, unlinked



def shown_width(img_tag: str, natural_px: int) -> float:
    """Width [px] at which furo shows an <img> in a COLUMN_PX column: its style's width (px or %), else its own
    width, never wider than the column."""
    width = re.search(r"width:\s*([\d.]+)(px|%)", img_tag)
    if not width:
        return min(natural_px, COLUMN_PX)
    value, unit = float(width.group(1)), width.group(2)
    return min(value if unit == "px" else COLUMN_PX * value / 100.0, COLUMN_PX)


def test_figure_text_on_analysis_pages_is_as_large_as_the_body_text(site):
    """Each figure of an analysis page records its smallest text and width in its PNG (plotting.style); at the width
    the page shows it, that text is at least MIN_FIGURE_TEXT_PX (body text: 16 px). Figures not drawn in the
    plotting package's style are listed in FIGURE_TEXT_EXEMPT with the reason."""
    from PIL import Image

    from tippedisk_analysis.plotting.style import rendered_px

    sizes, small, shown = {}, {}, set()
    for name, body in pages(site).items():
        if not ANALYSIS_PAGES.match(name):
            continue
        for tag in re.findall(r"<img\b[^>]*>", body):
            source = re.search(r'\bsrc="([^"]+)"', tag).group(1)
            figure = Path(source).name
            shown.add(figure)
            if figure in FIGURE_TEXT_EXEMPT:
                continue
            with Image.open((site / name).parent / source) as image:
                description, natural = image.info.get("Description", ""), image.width
            if not description:
                small[f"{name}: {figure}"] = "no Description (not drawn by plotting.plot_dataset)"
                continue
            sizes[figure] = rendered_px(description, shown_width(tag, natural))
            if sizes[figure] < MIN_FIGURE_TEXT_PX:
                small[f"{name}: {figure}"] = f"{sizes[figure]:.1f} px"
    assert not small, small
    assert len(sizes) >= 8, sizes
    assert not set(FIGURE_TEXT_EXEMPT) - shown, "exempt figures no analysis page shows"


def test_figures_keep_a_readable_width_on_a_phone(site):
    """At 390 px the text column is about 350 px: site.css keeps every PNG of a <figure> at a minimum width (the
    figure scrolls sideways in its box), at which each analysis figure's smallest text renders >= PHONE_TEXT_PX;
    a table of names and what they do breaks long words to fit the column."""
    from PIL import Image

    from tippedisk_analysis.plotting.style import rendered_px

    css = (site / "_static" / "site.css").read_text()
    assert re.search(r"figure > a\.image-reference\s*\{[^}]*overflow-x: auto", css)
    assert re.search(r"@media \(max-width: 34em\)[^@]*table\.docutils[^{]*td\s*\{\s*overflow-wrap: anywhere", css)
    assert re.search(r"div\.cell_output img\s*\{[^}]*min-width", css)  # the tutorials' figures
    minimum = float(re.search(r'figure img\[src\$="\.png"\][^{]*\{[^}]*min-width: (\d+)px', css).group(1))
    small, outside = {}, []
    for name, body in pages(site).items():
        if not ANALYSIS_PAGES.match(name):
            continue
        linked = r'<figure\b[^>]*>\s*<a class="[^"]*image-reference[^"]*" href="[^"]+">\s*<img\b[^>]*src="'
        outside += [f"{name}: {src}" for src in re.findall(r'<img\b[^>]*\bsrc="([^"]+\.png)"', body)
                    if not re.search(linked + re.escape(src) + '"', body)]
        for source in re.findall(r'<figure\b[^>]*>\s*<a\b[^>]*>\s*<img\b[^>]*\bsrc="([^"]+\.png)"', body):
            with Image.open((site / name).parent / source) as image:
                description = image.info.get("Description", "")
            if description and rendered_px(description, minimum) < PHONE_TEXT_PX:
                small[f"{name}: {Path(source).name}"] = rendered_px(description, minimum)
    assert not outside, outside
    assert not small, small


@pytest.mark.parametrize("data, options", [("stability_map.nc", {}), ("attractors/basins_eps0.25.nc", {}),
                                           ("periodic/periodic_tippedisk_frictionless.nc", {}),
                                           ("fig13_ode_inversion.nc", {})])
def test_figures_record_text_readable_at_the_column_width(tmp_path, data, options):
    """plot_dataset's PNG records its smallest text and width; shown COLUMN_PX wide that text is >= 14 px, and the
    record holds: no tick label, axis label, title or legend text of the redrawn figure is smaller."""
    import matplotlib.pyplot as plt
    from matplotlib.legend import Legend
    from matplotlib.text import Text
    from PIL import Image

    import tippedisk_analysis as td
    from tippedisk_analysis.plotting import FIGURES, plot_dataset
    from tippedisk_analysis.plotting.style import DESCRIPTION, rendered_px

    ds = td.load(DOCS.parent / "data" / data)
    with Image.open(plot_dataset(ds, tmp_path / "figure.png", **options)) as image:
        description, width_px, dpi = image.info["Description"], image.width, image.info["dpi"][0]
    points, width_in = (float(v) for v in DESCRIPTION.search(description).groups())
    assert abs(width_px - width_in * dpi) <= 1
    assert rendered_px(description, COLUMN_PX) >= MIN_FIGURE_TEXT_PX
    fig = FIGURES[ds.attrs["kind"]](ds, **options)
    fig.canvas.draw()
    texts = [fig._suptitle, *fig.texts, *(lg for lg in fig.legends)]
    for ax in fig.axes:
        texts += [*ax.get_xticklabels(), *ax.get_yticklabels(), ax.xaxis.label, ax.yaxis.label, ax.title, *ax.texts,
                  ax.get_legend()]
    legends = [t for t in texts if isinstance(t, Legend)]
    texts = [t for t in texts if isinstance(t, Text)] + [t for lg in legends for t in lg.get_texts()]
    fonts = [t.get_fontsize() for t in texts if t.get_visible() and t.get_text().strip()]
    plt.close(fig)
    assert min(fonts) >= points and fig.get_figwidth() == width_in  # ticks, labels, titles, legends


# Study figures drawn again from data/ by their study's redraw(data_dir, figure_dir) (seconds each)
REDRAWN = {"spin_passage": ("data/inversion", ["spin_passage.png"]),
           "nutation_cycles": ("data/inversion", ["nutation_cycles.png"]),
           "continuation": ("data/continuation", ["continuation_window.png"]),
           "free_nutation": ("data/inversion", ["free_nutation.png"]),
           "held_cycle_ends": ("data/inversion", ["held_cycle_ends.png", "held_cycle_ends_link.png"]),
           "rolling": ("data/rolling", ["rolling_inversion.png", "rolling_section.png", "rolling_family.png"])}


@pytest.mark.parametrize("study", sorted(REDRAWN))
def test_study_figures_redraw_from_stored_data_in_the_figure_style(tmp_path, study):
    """A study figure shown on an analysis page is drawn again from its stored datasets alone, WIDTH wide with
    no text under FONT_PT (the PNG's Description, read back)."""
    import importlib

    from PIL import Image

    from tippedisk_analysis.plotting.style import DESCRIPTION, FONT_PT, WIDTH

    data_dir, names = REDRAWN[study]
    importlib.import_module(f"tippedisk_studies.{study}").redraw(str(DOCS.parent / data_dir), str(tmp_path))
    for name in names:
        with Image.open(tmp_path / name) as image:
            points, width = (float(v) for v in DESCRIPTION.search(image.info["Description"]).groups())
        assert points >= FONT_PT and width == WIDTH, (name, points, width)


def test_the_tutorials_kernels_show_no_compile_notice(tmp_path, monkeypatch):
    """A build on a machine without heyoka's disk cache compiles every model once: the tutorials' kernels
    (docs/conf.py's profile) print no CompileNotice, and with it no path of the build machine; their figures
    draw in the figure style (12-pt text)."""
    nbformat = pytest.importorskip("nbformat")
    from nbclient import NotebookClient

    namespace: dict = {"__file__": str(DOCS / "conf.py")}
    exec(compile((DOCS / "conf.py").read_text(), "docs/conf.py", "exec"), namespace)
    profile = tmp_path / "ipython" / "profile_default"
    profile.mkdir(parents=True)
    (profile / "ipython_kernel_config.py").write_text(namespace["KERNEL_CONFIG"])
    monkeypatch.setenv("IPYTHONDIR", str(profile.parent))
    cell = ("import time, tippedisk_analysis.compilation as c\nc.NOTICE_AFTER = 0.01\n"
            "with c.compiling('a model'):\n    time.sleep(0.3)\nprint('done')")
    style = ("import matplotlib.pyplot as plt\nplt.figure()\n"
             "print(plt.rcParams['font.size'], plt.rcParams['legend.fontsize'])")
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(cell), nbformat.v4.new_code_cell(style)])
    NotebookClient(notebook, timeout=120, kernel_name="python3").execute()
    assert [(o.get("name"), o.get("text")) for o in notebook.cells[0].outputs] == [("stdout", "done\n")]
    assert [o.get("text") for o in notebook.cells[1].outputs if o.get("name") == "stdout"] == ["12.0 12.0\n"]


def cli_rows(site: Path) -> dict[tuple[str, str], tuple[list[str], str, str]]:
    """{(command, first option): (the option cell's code spans, default cell, meaning)} of the command pages."""
    rows = {}
    for path in sorted((site / "_generated" / "cli").glob("*.html")):
        body = pages(site)[path.relative_to(site).as_posix()]
        for row in re.findall(r"<tr[^>]*>\s*<td>(.*?)</tr>", body, re.S):
            cells = re.split(r"</td>\s*<td>", row)
            codes = [html.unescape(re.sub(r"<[^>]+>", "", c)) for c in re.findall(r"<code\b.*?</code>", cells[0], re.S)]
            default, meaning = (" ".join(prose(c).split()) for c in cells[1:3])
            default = default or " ".join(html.unescape(re.sub(r"<[^>]+>", "", cells[1])).split())
            rows[(path.stem, codes[0])] = (codes, default, meaning)
    return rows


def test_command_pages_show_the_default_the_help_gives(site):
    """The default column holds the default an option's help states, argparse's or the text's ("(default 0.05)",
    "(Table 2: 0.435)", "[m] (0.045)"), and every option name is one code span that does not break."""
    rows = cli_rows(site)
    read_off_the_help = {("basins", "--dt"): "0.05", ("basins", "--omega"): "40", ("basins", "--mass"): "0.435",
                         ("basins", "--hole-radius"): "0.015", ("basins", "--radius"): "0.045",
                         ("basins", "--eps"): "0.1", ("basins", "--threads"): "cores", ("animate", "--size"): "960x540",
                         ("simulate", "--gamma-dot"): "-alpha_dot cos(beta)", ("simulate", "--model"): "ode-euler",
                         ("critical-spin", "--eps"): "0.1", ("continue", "--branch"): "inverted",
                         ("lyapunov", "--t-end"): "20", ("study", "--output-dir"): "output/"}
    assert {key: rows[key][1] for key in read_off_the_help} == read_off_the_help
    assert rows[("periodic-orbits", "--frictionless")][1] == ""  # its help's "(default E + 0.1 J)" is --to's
    said = {key: meaning for key, (_, default, meaning) in rows.items()
            if re.search(r"\((?:[^()]*; )?default:? [^)\s]|\((?:[^()]*; )?Table \d+: \S", meaning)
            and not re.search(r"--[\w-]+ [A-Z_]+ (?:\[[^]]*\] )?\(default", meaning) and not default}
    assert not said, said
    assert len(rows) > 150
    assert not [codes for codes, _, _ in rows.values() if any(" " in c or "," in c for c in codes)]
    css = (site / "_static" / "site.css").read_text()
    assert re.search(r"td:first-child code[^{]*\{\s*white-space: nowrap", css)
    assert 'href="../../_static/site.css' in (site / "_generated" / "cli" / "basins.html").read_text()


def test_api_descriptions_end_at_a_sentence_not_an_abbreviation(site):
    """A public name's one-line description is its docstring's first sentence whole: "(the paper's Figs. 13-15)"
    is not cut after "Figs."."""
    cut = {}
    for path in sorted((site / "_generated" / "api").glob("*.html")):
        for row in re.findall(r"<tr[^>]*>\s*<td>(.*?)</tr>", pages(site)[path.relative_to(site).as_posix()], re.S):
            text = " ".join(prose(re.split(r"</td>\s*<td>", row)[-1]).split())
            if re.search(r"\b(?:Figs?|Sect|Eq|cf)\.$", text):
                cut[f"{path.name}: {text[:40]}"] = text[-30:]
    assert not cut, cut


def test_study_list_prints_each_first_sentence_whole(capsys):
    """`tippedisk study --list`: a study's description is its docstring's first sentence, not cut at the end of
    the docstring's first line."""
    import importlib

    from tippedisk_analysis.cli import main

    assert main(["study", "--list"]) == 0
    for line in capsys.readouterr().out.splitlines():
        name, text = line.split(maxsplit=1)
        doc = " ".join(importlib.import_module(f"tippedisk_studies.{name}").__doc__.split())
        assert doc.startswith(text) and text[-1] in ".?!", (name, text)

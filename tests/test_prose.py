"""Every figure a reader sees comes from data: the page prose is a template over the page's rows
(experiments/report/prose.py), no report config types a measured figure, the committed pages carry no
volatile provenance, and every figure of the README's Results section is printed on the page its
paragraph links (experiments/report/readme.py)."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import pandas as pd
import pytest

from experiments.config import load_dict, timing_needed, validate
from experiments.report import prose, readme
from experiments.report.pages import report_configs
from experiments.report.prose import ProseError, Sources, config_numbers, fill, typed_figures
from experiments.report.tables import READS

ROOT = Path(__file__).resolve().parents[1]


def _frame(scale: float = 1.0) -> pd.DataFrame:
    rows = []
    for s in ("bunny", "spot"):
        for c in (0.0, 10.0, 50.0):
            for a, k in (("tile", 2.0), ("interval", 3.0)):
                rows.append({"scene.name": s, "camera.coc_px": c, "pipeline.algorithm": a, "status": "ok",
                             "ops.total": scale * (100.0 + k * c + (7.0 if s == "spot" else 0.0))})
    return pd.DataFrame(rows)


TEMPLATE = ("tile costs {ops.total[scene=bunny, coc_px=10, algorithm=tile]:.1f} ops at CoC 10 "
            "({range(ops.total[coc_px=10, algorithm=tile]):.0f} over the scenes), "
            "{range(ops.total[algorithm=tile] / ops.total[algorithm=interval]):.2f} of interval's; "
            "cheapest at CoC 50 on spot: {argmin(ops.total[scene=spot, coc_px=50], algorithm)}; "
            "order {order(ops.total[scene=spot, coc_px=50], algorithm)}; "
            "{'never dearer' if all(ops.total[algorithm=tile] <= ops.total[algorithm=interval]) else 'dearer'}; "
            "{list(ops.total[scene=bunny, algorithm=tile]):.0f}; "
            "{ops.total[scene=bunny, coc_px=50, algorithm=tile] / ops.total[scene=bunny, coc_px=0, algorithm=tile] - 1:+.0%}"
            "; paper {paper: 1.20 / 1.27}; `{h: true}` and {{table:x}} stay.")


def test_placeholders_are_filled_from_the_rows():
    assert fill(TEMPLATE, Sources(_frame())) == (
        "tile costs 120.0 ops at CoC 10 (120–127 over the scenes), 0.80–1.00 of interval's; cheapest at CoC 50 "
        "on spot: tile; order interval > tile; never dearer; 100 / 120 / 200; +100 %; paper 1.20 / 1.27; "
        "`{h: true}` and {{table:x}} stay.")


def test_rerunning_with_other_numbers_rewrites_the_sentence():
    """The same template over rows with other values prints the other values (a claim of ordering too)."""
    flipped = _frame(1.5)
    flipped.loc[flipped["pipeline.algorithm"] == "tile", "ops.total"] *= 3
    a, b = fill(TEMPLATE, Sources(_frame())), fill(TEMPLATE, Sources(flipped))
    assert "tile costs 540.0 ops" in b and "cheapest at CoC 50 on spot: interval" in b and "dearer;" in b
    assert "order tile > interval" in b and "never dearer" not in b
    assert a != b


def test_another_section_and_named_values_are_sources():
    other = _frame(2.0)
    values = {"culling": lambda: pd.DataFrame({"scene": ["bunny", "bunny"], "mode": ["h_i", "H_j"],
                                               "culled": [0.46, 0.35]}).assign()}
    src = Sources(_frame(), {"table9": other}, values)
    assert fill("{table9.ops.total[scene=bunny, coc_px=0, algorithm=tile]:.0f}", src) == "200"
    assert fill("{culling.culled[scene=bunny, mode=h_i]:.0%}", src) == "46 %"


@pytest.mark.parametrize("template, message", [
    ("{ops.total[scene=bunny]}", "selects 6 rows with different values"),
    ("{1.23}", "must come from the page's data"),
    ("{ops.totl[scene=bunny, coc_px=0, algorithm=tile]}", "did you mean ops.total"),
    ("{ops.total[scene=cow]}", "no row of this section matches"),
    ("{ops.total[algorithm=tile] / ops.total[coc_px=0]}", "cannot pair the rows"),
    ("{open(ops.total[scene=bunny, coc_px=0, algorithm=tile])}", "cannot evaluate"),
])
def test_a_placeholder_that_does_not_fit_the_data_is_a_clear_error(template, message):
    with pytest.raises(ProseError, match=re.escape(message)):
        fill(template, Sources(_frame()))


# ---- typed figures ---------------------------------------------------------------------------------

@pytest.mark.parametrize("text, typed", [
    ("tile culls 46 % of the samples", ["46 %"]),
    ("the ratio is 1.23 at CoC 10", ["1.23"]),
    ("3x faster, 683,904 tests, 76 M samples, 5.9k triangles", ["3x", "683,904", "76 M", "5.9k"]),
    ("64 spp, CoC 10, 2x2 tiles, [Akenine-Möller 2012] Table 1 and §6.2, 5D triangles, float32", []),
    ("{ops.total[coc_px=10]:.2f} and {paper: 1.20 / 1.27} and `0.5` in code", []),
    ("a 640x360 frame", ["640x360"]),
])
def test_the_typed_figure_detector(text, typed):
    assert typed_figures(text, {"64", "10", "2"}) == typed


def _report_configs():
    out = []
    for p in report_configs(ROOT / "configs"):
        data, lines = load_dict(p)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            config = validate(data, str(p), lines)
        out.append((p, data, config))
    return out


CONFIGS = _report_configs()
# Sections of the timing model's page (configs/paper/cycles_*.yaml) that still type a ratio ('7x', '4x');
# strict: when they become placeholders, the xfail fails and the entry goes.
PENDING: dict[str, str] = {}


@pytest.mark.parametrize("path", [p for p, _, _ in CONFIGS], ids=[c.name for _, _, c in CONFIGS])
def test_no_report_config_types_a_figure(path, request):
    """Outside placeholders a page's text and summary hold only the config's own numbers, citations and
    names (fails on a hand-typed '46 %' or '1.23': test_the_typed_figure_detector)."""
    _, data, config = next(x for x in CONFIGS if x[0] == path)
    if config.name in PENDING:
        request.applymarker(pytest.mark.xfail(strict=True, reason=PENDING[config.name]))
    allowed = config_numbers(data, config.model_dump(exclude={"outputs"}), config.hardware_config().describe())
    for part in ("text", "summary"):
        text = getattr(config.outputs, part) or ""
        assert not typed_figures(text, allowed), (
            f"{path.name} {part}: typed figures {typed_figures(text, allowed)}; make each a placeholder "
            "over the page's data (docs/reports.md §Prose)")
        for m in re.finditer(r"\{paper:", text):  # a quoted figure sits in a paragraph that cites its paper
            para = text[text.rfind("\n\n", 0, m.start()) + 1:text.find("\n\n", m.end()) % (len(text) + 1)]
            assert re.search(r"\[[A-Z][^\]]* \d{4}\]|paper", para), f"{path.name}: {{paper: ...}} without its source"


def test_named_tables_that_read_timing_sit_on_pages_that_read_it():
    for path, _, config in CONFIGS:
        for name in re.findall(r"\{\{table:(\w+)\}\}", config.outputs.text or ""):
            if any(r.startswith("timing") for r in READS.get(name, ())):
                assert timing_needed(config), f"{path.name}: {{{{table:{name}}}}} reads timing figures"


# ---- the committed pages ---------------------------------------------------------------------------

PAGES = sorted(p for p in (ROOT / "reports").rglob("*.md") if "quick" not in p.parts)
VOLATILE = [r"engine [0-9a-f]{12}", r"revision [0-9a-f]{7}", r"s of render time", r"\d s this run",
            r"CPU-minutes on", r"\*\*Prose error", "\x00"]
# a placeholder left in the prose (the inlined config, a fenced block, keeps its templates)
UNFILLED = re.compile(r"(?<!\{)\{[\w.]+\[[^\]]*\][^{}]*\}(?!\})")


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(ROOT / "reports").as_posix() for p in PAGES])
def test_no_committed_page_carries_volatile_provenance_or_unfilled_prose(page):
    text = page.read_text()
    for pattern in VOLATILE:
        m = re.search(pattern, text)
        assert not m, f"{page.relative_to(ROOT)}: {m.group(0)!r} (run times, engine and revision go to " \
                      "results/provenance/; placeholders are filled when the page is written)"
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    m = UNFILLED.search(prose)
    assert not m, f"{page.relative_to(ROOT)}: unfilled placeholder {m.group(0)!r}"


def _results_section() -> str:
    text = (ROOT / "README.md").read_text()
    return text.split(readme.BEGIN, 1)[1].split(readme.END, 1)[0]


def test_the_readme_results_section_is_generated_from_the_pages():
    body = "\n".join(readme.results_markdown(ROOT / "reports", ROOT)).rstrip()
    assert _results_section().strip() == body.strip(), \
        "README Results section is stale: run `rast5d report` (it rewrites the section from the pages)"


_FIGURE = re.compile(r"(?<![\w.])[-+−]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?(?![\w])")


def test_every_readme_figure_is_printed_on_the_page_its_paragraph_links():
    """Each paragraph of the Results section links its page; each of its figures (but citations and
    locators) appears on that page (fails on a figure typed into the README)."""
    paragraphs = [p for p in _results_section().split("\n\n") if p.strip()]
    summaries = [p for p in paragraphs if re.search(r"\]\((reports/[^)]+\.md)\)", p)]
    assert summaries, "the Results section quotes no page"
    for para in summaries:
        page = ROOT / re.search(r"\]\((reports/[^)]+\.md)\)", para).group(1)
        text = page.read_text()
        body = prose._LINK_TARGET.sub(" ", para)
        for pattern in (prose._CITATION, prose._LOCATOR, prose._NAMES):
            body = pattern.sub(" ", body)
        for fig in _FIGURE.findall(body):
            assert fig in text, f"README figure {fig!r} is not on {page.relative_to(ROOT)}: {para[:120]}"

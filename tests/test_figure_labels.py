"""Figures without code in them: every title, axis label, legend title and panel title of every report
figure is a human label (declared in the config's outputs.column_labels or xlabel/ylabel, or derived
from the counter and parameter declarations), never a dotted counter name or an expression; lines
that would hide each other are drawn distinguishably; log axes carry several labelled ticks."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from experiments.config import PlotSpec, load_dict, validate
from experiments.report import figures as F
from experiments.report.pages import report_configs

pytestmark = pytest.mark.smoke

REPO = Path(__file__).resolve().parents[1]


def spec_labels(spec, outputs, sweep: dict, figures=F) -> list[str]:
    """The labels a report figure shows, from its spec alone: axes, legend titles, panel titles (for
    each swept value of the facet and row columns), the figure title."""
    labs = []
    derived = outputs.derived
    hue = " / ".join(spec.hue) if isinstance(spec.hue, list) else spec.hue
    with figures.column_labels(outputs.column_labels) if hasattr(figures, "column_labels") else _null():
        if spec.x:
            labs.append(spec.xlabel or figures.value_label(spec.x, derived))
        if spec.ys and spec.kind != "image_grid":
            labs.append(spec.ylabel or figures.value_label(spec.ys[0], derived))
        for col in (hue, spec.style):
            if col:
                labs.append(figures.value_label(col, derived))
        for col in (spec.facet, spec.row):
            if col:
                labs += [figures.facet_title(col, v) for v in (sweep.get(col) or [1])]
    if spec.title:
        labs.append(spec.title)
    return labs


class _null:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def report_figures():
    for path in report_configs(REPO / "configs"):
        data, lines = load_dict(path)
        config = validate(data, str(path), lines)  # the outputs checked; the sweep's points need not be
        for i, spec in enumerate(config.outputs.plots):
            if spec.kind != "table":
                yield f"{config.name}_{i + 1}", spec, config


def test_every_report_figure_label_is_human():
    leaks, n = {}, 0
    for name, spec, config in report_figures():
        n += 1
        sweep = {k: v for k, v in config.sweep.items() if k != "zip"}
        for text in spec_labels(spec, config.outputs, sweep):
            if F.label_leaks(text):
                leaks.setdefault(name, []).append((text, F.label_leaks(text)))
    assert n > 60
    assert not leaks, leaks


def _frame() -> pd.DataFrame:
    rows = []
    for alg in ("bruteforce", "interval", "tile", "laine"):
        for coc in (0, 10, 30):
            for lod in (False, True):
                cycles = 1e6 * (1 + coc / 10) * {"bruteforce": 2, "interval": 1.5}.get(alg, 1)
                rows.append({"pipeline.algorithm": alg, "camera.coc_px": coc, "pipeline.lod.enabled": lod,
                             "pipeline.tile_size": 2, "timing.cycles": cycles, "ops.total": 5e7 * (1 + coc),
                             "raster.ste": 0.05 + 0.01 * coc, "metric.rmse": 0.05 / (1 + coc), "status": "ok"})
    return pd.DataFrame(rows)


DERIVED = {"mcycles": "timing.cycles / 1e6",
           "variant": "(pipeline.algorithm == 'interval') * 1 + (pipeline.algorithm == 'tile') * (4 - pipeline.tile_size)"}


def _draw(spec: dict, names=None, derived=DERIVED):
    from experiments.report.frames import apply_derived

    df = apply_derived(_frame(), derived)
    return F.render_plot(PlotSpec(**spec), df, None, derived=derived, names=names)


def test_drawn_figures_show_human_labels():
    """The drawn figure's own texts: a derived 'counter / 1e6' is labelled from the counter's
    declaration, a derived expression used as hue by its declared label, a config key by its
    parameter's."""
    res = _draw({"kind": "line", "x": "camera.coc_px", "y": "mcycles", "hue": "variant", "facet": "pipeline.lod.enabled",
                 "title": "Cycles"}, names={"variant": "method"})
    labels = res["labels"]
    assert "estimated frame time [Mcycles]" in labels and "method" in labels
    assert any(t.startswith("level of detail") for t in labels)
    assert not [t for t in labels if F.label_leaks(t)], labels
    res = _draw({"kind": "scatter", "x": "ops.total", "y": "metric.rmse", "hue": "pipeline.algorithm",
                 "style": "pipeline.lod.enabled", "logx": True, "logy": True})
    assert not [t for t in res["labels"] if F.label_leaks(t)], res["labels"]
    assert "level of detail (marker):" in res["labels"]


def test_the_check_fails_on_code_in_a_label():
    """The broken inputs of the old figures: an expression as axis label, a dotted name in a legend."""
    res = _draw({"kind": "line", "x": "camera.coc_px", "y": "mcycles", "hue": "pipeline.algorithm",
                 "ylabel": "mcycles = timing.cycles / 1e6"})
    assert [t for t in res["labels"] if F.label_leaks(t)] == ["mcycles = timing.cycles / 1e6"]
    assert F.label_leaks("pipeline.lod.enabled (marker): False/True") == ["pipeline.lod.enabled"]
    assert F.label_leaks("variant = (pipeline.algorithm == 'interval') * 1") == ["pipeline.algorithm", "==", "* 1"]
    assert F.label_leaks("operations per pixel [ops/pixel]") == [] and F.label_leaks("area [1e-3 px^2]") == []


def test_lines_with_equal_values_are_drawn_distinguishably():
    """Two algorithms with the same cycles (tile under laine in the old cycles figure): the later line
    is dashed with hollow markers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    df = _frame()
    df.loc[df["pipeline.algorithm"] == "laine", "timing.cycles"] = df.loc[df["pipeline.algorithm"] == "tile",
                                                                         "timing.cycles"].to_numpy()
    spec = PlotSpec(kind="line", x="camera.coc_px", y="timing.cycles", hue="pipeline.algorithm")
    fig, ax = plt.subplots()
    F._draw_line(ax, spec, df, ["bruteforce", "interval", "tile", "laine"])
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert lines["tile"].get_linestyle() == "-" and lines["laine"].get_linestyle() != "-"
    assert lines["laine"].get_markerfacecolor() == "none"
    assert lines["interval"].get_linestyle() == "-"
    plt.close(fig)


def test_log_axes_have_several_labelled_ticks():
    """A log axis over less than a decade (RMSE 0.05 down to 0.0016 here spans 1.5) shows at least
    three labelled ticks, not one power of ten."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([1, 2, 3], [0.021, 0.035, 0.08])
    ax.set_yscale("log")
    F.readable_log_ticks(ax.yaxis)
    fig.canvas.draw()
    lo, hi = ax.get_ylim()
    shown = [t.get_text() for t in ax.get_yticklabels() if t.get_text() and lo <= t.get_position()[1] <= hi]
    assert len(shown) >= 3, shown
    plt.close(fig)

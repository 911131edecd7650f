"""Figures of a report page: an `outputs.plots` spec (experiments.config.PlotSpec, docs/reports.md)
and a result frame become a matplotlib figure (PNG + PDF) in one paper-like style, with the data
table beside it. Kinds: line, bar, scatter, heatmap (one coloured cell per (row, x)), image_grid (the
images of the points, one per (row, x)); tables (kind table) are in tables.py. There are no
per-figure plotting scripts.
"""
from __future__ import annotations

import math
import re
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .frames import (PlotError, apply_where, cell, check_columns, fmt, label, missing, paper_number, paper_value,
                     pareto_front, same, sorted_x, spec_columns, unique)
from .tables import data_table, md_table, powerlaw_table

# Okabe-Ito: distinguishable in colour-blind vision and in greyscale print.
COLORS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000"]
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]
STYLE = {
    "font.family": "serif", "font.size": 8, "axes.titlesize": 9, "axes.labelsize": 8, "legend.fontsize": 7,
    "xtick.labelsize": 7, "ytick.labelsize": 7, "axes.grid": True, "grid.alpha": 0.3, "grid.linewidth": 0.5,
    "axes.spines.top": False, "axes.spines.right": False, "lines.linewidth": 1.2, "lines.markersize": 4,
    "legend.frameon": False, "savefig.bbox": "tight", "savefig.dpi": 200, "pdf.fonttype": 42,
    "figure.constrained_layout.use": True,
}
PANEL_INCHES = (3.3, 2.5)
# One colour per algorithm on every page (the others take COLORS in order).
ALGORITHM_COLORS = {"bruteforce": "#000000", "interval": "#0072B2", "tile": "#D55E00", "tile_interleaved": "#E69F00",
                    "interleave": "#009E73", "hinterleave": "#56B4E9", "laine": "#CC79A7"}
# Axis labels of config columns (counters and derived figures take theirs from sim.counter_docs()).
CONFIG_LABELS = {
    "camera.coc_px": ("CoC radius", "px"), "samples.spp": ("samples per pixel", ""),
    "pipeline.algorithm": ("algorithm", ""), "scene.name": ("scene", ""), "pipeline.tile_size": ("tile size", "px"),
    "pipeline.lens_grid": ("lens grid", "cells per axis"), "hardware.tex_cache.size_bytes": ("texture cache size", "bytes"),
    "camera.width": ("image width", "px"), "camera.height": ("image height", "px"), "samples.kind": ("sample table", ""),
    "pipeline.shading": ("shading", ""), "pipeline.bin_size": ("bin size", "px"), "time.wall_s": ("wall time", "s"),
    "scene.triangles": ("triangles", ""), "camera.u_scale": ("lens u scale", ""), "pipeline.time_splits": ("time splits", ""),
    "scene.params.motion_px": ("motion", "px"), "scene.params.layers": ("occluder layers", ""),
    "samples.views": ("views", ""), "pipeline.texture_layout": ("texture layout", ""),
    "hardware.tex_cache.ways": ("texture cache ways", ""), "samples.n_lens": ("lens positions", ""),
    "pipeline.motion_test": ("motion test", ""), "pipeline.time_strata": ("time strata", ""),
    "ops.total": ("operations per frame", "ops"), "ops.per_pixel": ("operations per pixel", ""),
    "raster.samples_tested": ("samples tested", ""), "raster.samples_hit": ("samples hit", ""),
    "timing.cycles": ("estimated frame time", "cycles"), "pipeline.lod.enabled": ("level of detail", ""),
    "samples.n_lines": ("line samples per pixel", ""), "metric.rmse": ("RMSE against the reference", ""),
    "metric.psnr": ("PSNR against the reference", "dB"), "metric.ssim": ("SSIM against the reference", ""),
    "metric.flip": ("FLIP against the reference", ""),
}


# The config's outputs.column_labels while a figure is drawn (labels(...) sets them).
_COLUMN_LABELS: dict = {}
# Scale factors of derived 'counter / 1e6' columns and the unit prefix they give.
_PREFIX = {1e3: "k", 1e6: "M", 1e9: "G", 1e12: "T", 1e-3: "m", 1e-6: "µ"}
_SCALED = re.compile(r"^\s*`?([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)`?\s*([/*])\s*(1e-?\d+|1000|1000000)\s*$")
_SECTIONS = ("pipeline.", "camera.", "samples.", "hardware.", "scene.params.", "scene.", "point.", "resolved.")


@contextmanager
def column_labels(names: dict | None):
    """Within this block value_label and facet_title use a config's outputs.column_labels first."""
    global _COLUMN_LABELS
    outer = _COLUMN_LABELS
    _COLUMN_LABELS = dict(names or {})
    try:
        yield
    finally:
        _COLUMN_LABELS = outer


def _humanize(col: str) -> str:
    """'pipeline.lod.enabled' -> 'lod enabled', 'tile_size' -> 'tile size': no dots, no underscores."""
    for sec in _SECTIONS:
        if col.startswith(sec) and len(col) > len(sec):
            col = col[len(sec):]
            break
    return col.removesuffix(".name").replace(".", " ").replace("_", " ").strip()


def _what_unit(col: str) -> tuple[str, str] | None:
    """(what, unit) of a counter, derived figure or config key from its declaration, or None."""
    if col in CONFIG_LABELS:
        return CONFIG_LABELS[col]
    import sim

    doc = sim.counter_docs().get(col)
    if doc is not None:
        unit, desc = doc
        what = desc.split(":")[0].split(" (")[0].strip()
        what = re.sub(r"\s*(as in |of )?\b00\d\b( §[\d.–-]+)?", "", what).strip()  # no paper file numbers
        if len(what) > 48 or not what or label_leaks(what):  # a derived figure's doc may be its expression
            what = _humanize(col)
        return what, unit
    return _config_doc(col)


def _config_doc(col: str) -> tuple[str, str] | None:
    """(short description, unit) of a pipeline or camera key from sim's parameter declarations."""
    import sim

    parts = col.split(".")
    if len(parts) == 2 and parts[0] == "pipeline":
        info = sim.PipelineConfig.field_docs().get(parts[1])
        if info:
            what = re.split(r"[:;(]|, ", info["doc"])[0].strip().rstrip(".")
            return (what if 0 < len(what) <= 40 else _humanize(col)), info.get("unit", "")
    return None


def value_label(col: str | None, derived: dict | None = None) -> str:
    """An axis or legend label for a column, never a dotted name or an expression: the config's
    outputs.column_labels, else '<what> [<unit>]' from CONFIG_LABELS, sim.counter_docs() (the
    description up to its first ':' when short) or the pipeline's declarations; a derived
    'counter / 1e6' gets its counter's label with the unit prefixed (M); any other derived column or
    key its name in words. Combined hue columns ('a / b') are labelled part by part."""
    if not col:
        return ""
    if col in _COLUMN_LABELS:
        return _COLUMN_LABELS[col]
    if " / " in col and col not in (derived or {}):
        return " / ".join(value_label(c, derived) for c in col.split(" / "))
    if derived and col in derived:
        m = _SCALED.match(derived[col])
        base = _what_unit(m.group(1)) if m else None
        if base is not None:
            factor = float(m.group(3)) if m.group(2) == "/" else 1.0 / float(m.group(3))
            prefix = _PREFIX.get(factor, f"{factor:g} ")
            what, unit = base
            return f"{what} [{prefix}{unit or ''}]".replace(" []", "")
        return _humanize(col)
    found = _what_unit(col)
    if found is None:
        return _humanize(col)
    what, unit = found
    if unit == "ratio":
        return f"{what} (ratio)"
    return f"{what} [{unit}]" if unit else what


def facet_title(col: str, v) -> str:
    """'CoC radius 10 px' rather than 'coc_px = 10'."""
    if col in _COLUMN_LABELS:
        return f"{_COLUMN_LABELS[col]}: {label(v)}"
    found = _what_unit(col)
    if found is not None:
        what, unit = found
        return f"{what} {label(v)}" + (f" {unit}" if unit and unit != "ratio" else "")
    return f"{_humanize(col)} {label(v)}"


LEAK = re.compile(r"(?<![\w.])[A-Za-z_]\w+(?:\.[A-Za-z_]\w+)+(?![\w(])|==|`|\*\s*\d")
SCALE = re.compile(r"\b\d+e-?\d+\b")


def label_leaks(text: str) -> list[str]:
    """The parts of a figure's label that are code: dotted column names, comparisons, assignments,
    backticks, products, scale factors (1e6) outside a [unit]. Empty for a human label."""
    text = str(text)
    return [m.group(0) for m in LEAK.finditer(text)] + SCALE.findall(re.sub(r"\[[^\]]*\]", "", text))


def figure_labels(fig) -> list[str]:
    """Every text a reader sees on a figure but its tick labels: titles, axis labels, legend titles
    and entries, colour-bar labels, annotations."""
    from matplotlib.text import Text

    ticks = set()
    for ax in fig.get_axes():
        ticks.update(id(t) for t in ax.get_xticklabels() + ax.get_yticklabels()
                     + ax.get_xticklabels(minor=True) + ax.get_yticklabels(minor=True))
    return [t.get_text() for t in fig.findobj(Text) if id(t) not in ticks and t.get_text().strip()]


def color_for(h, i: int) -> str:
    return ALGORITHM_COLORS.get(label(h), COLORS[i % len(COLORS)]) if h is not None else COLORS[i % len(COLORS)]


def grid_shape(n: int) -> tuple[int, int]:
    """(rows, columns) for n panels without empty cells where a shape of at most 4 columns allows it."""
    if n <= 3:
        return 1, max(n, 1)
    for cols in (3, 4, 2):
        if n % cols == 0:
            return n // cols, cols
    cols = min((3, 4, 2), key=lambda c: (-(-n // c) * c - n, c != 3))
    return -(-n // cols), cols


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _panels(plt, n: int):
    rows, cols = grid_shape(n)
    fig, axes = plt.subplots(rows, cols, figsize=(PANEL_INCHES[0] * cols, PANEL_INCHES[1] * rows), squeeze=False)
    flat = [a for row in axes for a in row]
    for a in flat[n:]:
        a.set_visible(False)
    return fig, flat[:n]


def readable_log_ticks(axis, least: int = 3) -> None:
    """A log axis spanning less than a few decades gets ticks at 1, 2 and 5 times the powers of its
    base (or every power of 2), labelled as plain numbers, so it shows at least ``least`` labelled ticks
    instead of one power of ten."""
    from matplotlib.ticker import FuncFormatter, LogLocator

    lo, hi = sorted(axis.get_view_interval())
    if not (lo > 0 and hi > lo):
        return
    base = axis.get_scale() == "log" and getattr(axis.get_transform(), "base", 10) or 10
    decades = math.log(hi / lo, base)
    if decades >= least - 0.5:
        return
    subs = (1.0,) if base == 2 else (1.0, 2.0, 5.0) if decades > 1 else (1.0, 1.5, 2.0, 3.0, 5.0, 7.0)
    axis.set_major_locator(LogLocator(base=base, subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _pos: _tick(v)))


def _tick(v: float) -> str:
    """A tick as a reader writes it: 20, 0.05, 2k, 1.5M."""
    if v == 0:
        return "0"
    for scale, suffix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if abs(v) >= scale:
            return f"{v / scale:g}{suffix}"
    return f"{v:g}"


def _series(spec, hues) -> list[tuple]:
    """[(hue value or None, y column, label)] for every line/bar series."""
    out = []
    for h in hues:
        for y in spec.ys:
            if h is None:
                name = y if len(spec.ys) > 1 else (spec.ylabel or y)
            else:
                name = label(h) if len(spec.ys) == 1 else f"{label(h)}: {y}"
            out.append((h, y, name))
    return out


def _draw_line(ax, spec, d, hues):
    series = _series(spec, hues)
    xs_all = sorted_x(d[spec.x])
    numeric = all(paper_number(x) is not None for x in xs_all)
    pos = {i: x for i, x in enumerate(xs_all)}
    drawn: list[dict] = []
    for i, (h, y, name) in enumerate(series):
        sub = d if h is None else d[[same(v, h) for v in d[spec.hue]]]
        xs = sorted_x(sub[spec.x])
        ys = [cell(sub, {spec.x: x}, y)[0] for x in xs]
        px = [float(x) for x in xs] if numeric else [xs_all.index(x) for x in xs]
        style = {}
        if any(overlaps(dict(zip(px, ys)), other) for other in drawn):
            # the same values as a line drawn before: dashed, with hollow, larger markers, so both show
            style = {"linestyle": (0, (4, 2)), "markerfacecolor": "none", "markersize": 7, "markeredgewidth": 1.2}
        drawn.append(dict(zip(px, ys)))
        ax.plot(px, ys, marker=MARKERS[i % len(MARKERS)], color=color_for(h, i), label=name, **style)
        group = h if h is not None else y
        paper = [(x, paper_number(paper_value(spec, group, x))) for x in (paper_x(spec, group) or [])]
        paper = [(x, v) for x, v in paper if v is not None]
        if paper:
            ppx = [(paper_number(x) if numeric else (xs_all.index(x) if x in xs_all else None)) for x, _ in paper]
            keep = [(a, v) for a, (_, v) in zip(ppx, paper) if a is not None]
            ax.plot([a for a, _ in keep], [v for _, v in keep], linestyle="--", marker="x", color=color_for(h, i),
                    alpha=0.8, label=f"{label(group)} (paper)")
    # Paper curves whose name matches no series (the paper's own scenes): grey, drawn all the same.
    groups = [h if h is not None else y for h, y, _ in series]
    for k, (g, by_x) in enumerate((g, v) for g, v in spec.paper.items() if not any(same(g, x) for x in groups)):
        pts = sorted((float(x), paper_number(v)) for x, v in by_x.items()
                     if paper_number(v) is not None and paper_number(x) is not None)
        if numeric and pts:
            ax.plot([a for a, _ in pts], [v for _, v in pts], linestyle="--", marker=MARKERS[(k + 3) % len(MARKERS)],
                    color=["#555555", "#999999", "#333333", "#BBBBBB"][k % 4], alpha=0.9, label=f"{label(g)} (paper)")
    if not numeric:
        ax.set_xticks(list(pos), [label(x) for x in pos.values()])


def overlaps(a: dict, b: dict, rel: float = 0.02) -> bool:
    """Whether two series {x: y} share at least two x values and lie within ``rel`` of each other at
    every shared x (one would hide the other)."""
    shared = [x for x in a if x in b and not (missing(a[x]) or missing(b[x]))]
    if len(shared) < 2:
        return False
    return all(abs(a[x] - b[x]) <= rel * max(abs(a[x]), abs(b[x]), 1e-300) for x in shared)


def unmatched_paper(spec, d, hues) -> list[str]:
    """Paper values a figure cannot draw: a name matching no series (bar plots) or an x that is not a
    number on a numeric axis, or not one of the x values of a category axis."""
    out = []
    groups = [h if h is not None else y for h in hues for y in spec.ys]
    xs = sorted_x(d[spec.x]) if spec.x and spec.x in d.columns else []
    numeric = all(paper_number(x) is not None for x in xs)
    for g, by_x in spec.paper.items():
        if spec.kind == "bar" and not any(same(g, x) for x in groups):
            out.append(f"{label(g)} (no such {spec.hue or 'column'})")
            continue
        for x, v in by_x.items():
            if paper_number(v) is None:
                continue  # text: tables only
            if (numeric and paper_number(x) is None) or (not numeric and not any(same(x, a) for a in xs)):
                out.append(f"{label(g)} at {spec.x} = {label(x)}")
    return out


def _sectioned(handles):
    """Legend handles in two headed sections when there are paper series: 'measured' and 'paper'."""
    from matplotlib.lines import Line2D

    ours = [h for h in handles if not str(h.get_label()).endswith("(paper)") and h.get_label() != "published value"]
    paper = [h for h in handles if h not in ours]
    if not paper:
        return handles
    head = lambda t: Line2D([], [], linestyle="none", marker="none", label=t)  # noqa: E731
    return [head("measured:")] + ours + [head("paper:")] + paper


def paper_x(spec, group) -> list | None:
    for g, by_x in spec.paper.items():
        if same(g, group):
            return sorted_x(list(by_x))
    return None


def _draw_bar(ax, spec, d, hues):
    xs = unique(d[spec.x])
    if spec.stacked:
        cats = [(x, h) for x in xs for h in hues
                if any(same(a, x) and (h is None or same(b, h))
                       for a, b in zip(d[spec.x], d[spec.hue] if spec.hue else [None] * len(d)))]
        bottom = np.zeros(len(cats))
        for j, y in enumerate(spec.ys):
            vals = np.array([cell(d, {spec.x: x, **({} if h is None else {spec.hue: h})}, y)[0] for x, h in cats],
                            dtype=float)
            ax.bar(range(len(cats)), np.nan_to_num(vals), bottom=bottom, color=COLORS[j % len(COLORS)], label=y,
                   width=0.7)
            bottom += np.nan_to_num(vals)
        ax.set_xticks(range(len(cats)), [label(x) if h is None else f"{label(x)}\n{label(h)}" for x, h in cats],
                      rotation=0 if len(cats) < 6 else 30)
        return
    series = _series(spec, hues)
    width = 0.8 / max(len(series), 1)
    for i, (h, y, name) in enumerate(series):
        sub = d if h is None else d[[same(v, h) for v in d[spec.hue]]]
        vals = [cell(sub, {spec.x: x}, y)[0] for x in xs]
        offs = [k - 0.4 + width * (i + 0.5) for k in range(len(xs))]
        ax.bar(offs, vals, width=width * 0.95, color=color_for(h, i), label=name)
        group = h if h is not None else y
        pts = [(o, paper_number(paper_value(spec, group, x))) for o, x in zip(offs, xs)]
        pts = [(o, v) for o, v in pts if v is not None]
        if pts:
            ax.scatter([o for o, _ in pts], [v for _, v in pts], marker="_", s=120, color="black", zorder=3,
                       label="published value" if i == 0 else None)
    ax.set_xticks(range(len(xs)), [label(x) for x in xs])


def _draw_scatter(ax, spec, d, hues, styles=None):
    """Colour by hue, marker by style; the figure legend shows the two separately (proxies)."""
    y = spec.ys[0]
    styles = styles or [None]
    for i, h in enumerate(hues):
        for j, s in enumerate(styles):
            sub = d
            if h is not None:
                sub = sub[[same(v, h) for v in sub[spec.hue]]]
            if s is not None:
                sub = sub[[same(v, s) for v in sub[spec.style]]]
            if not len(sub):
                continue
            ax.scatter(sub[spec.x].astype(float), sub[y].astype(float), s=14, color=color_for(h, i),
                       marker=MARKERS[j % len(MARKERS)], alpha=0.8, linewidths=0)
    if spec.pareto:
        ok = d[[spec.x, y]].astype(float).dropna()
        idx = pareto_front(ok[spec.x].to_numpy(), ok[y].to_numpy())
        fx, fy = ok[spec.x].to_numpy()[idx], ok[y].to_numpy()[idx]
        ax.step(fx, fy, where="post", color="black", linewidth=0.8, zorder=1)
        ax.scatter(fx, fy, s=40, facecolors="none", edgecolors="black", linewidths=0.8, zorder=3)


def _scatter_legend(spec, hues, styles):
    from matplotlib.lines import Line2D

    handles = []
    head = lambda t: Line2D([], [], linestyle="none", marker="none", label=t)  # noqa: E731
    if any(h is not None for h in hues):  # one headed section per encoding: colour, then marker
        handles.append(head(f"{value_label(spec.hue)} (colour):"))
    for i, h in enumerate(hues):
        if h is not None:
            handles.append(Line2D([], [], linestyle="", marker="o", color=color_for(h, i), label=label(h)))
    if any(s is not None for s in styles):
        handles.append(head(f"{value_label(spec.style)} (marker):"))
    for j, s in enumerate(styles):
        if s is not None:
            handles.append(Line2D([], [], linestyle="", marker=MARKERS[j % len(MARKERS)], color="0.4",
                                  label=label(s)))
    if spec.pareto:
        handles.append(Line2D([], [], color="black", marker="o", markerfacecolor="none", linewidth=0.8,
                              label="Pareto front"))
    return handles


def _save(fig, out_base: Path | None, dpi: int | None = None) -> list[Path]:
    """Write the figure as out_base.png and out_base.pdf (no creation date: reproducible PDFs). The
    layout the PNG's drawing computed is kept for the PDF (the same axes positions; a layout pass is
    a third of a figure's saving time)."""
    files = []
    if out_base is not None:
        out_base.parent.mkdir(parents=True, exist_ok=True)
        for ext in ("png", "pdf"):
            p = out_base.with_suffix(f".{ext}")
            fig.savefig(p, **({"dpi": dpi} if dpi else {}), metadata={"CreationDate": None} if ext == "pdf" else None)
            files.append(p)
            if fig.get_layout_engine() is not None:
                fig.set_layout_engine("none")  # keeps the positions constrained layout set
    return files


def _short(col: str) -> str:
    return col.removesuffix(".name").split(".")[-1]


def grid_table(spec, d) -> list[str]:
    """heatmap and image_grid: one row per (facet, row value), one column per x value."""
    facets = unique(d[spec.facet]) if spec.facet else [None]
    xs = sorted_x(d[spec.x])
    rows = []
    for f in facets:
        df_f = d if f is None else d[[same(v, f) for v in d[spec.facet]]]
        for r in sorted_x(df_f[spec.row]):
            vals = [cell(df_f, {spec.row: r, spec.x: x}, spec.ys[0])[0] for x in xs]
            rows.append(([label(f)] if spec.facet else []) + [label(r)] + [fmt(v, spec.format) for v in vals])
    header = ([spec.facet] if spec.facet else []) + [f"{spec.row} \\ {spec.x}"] + [label(x) for x in xs]
    return md_table(header, rows)


def _draw_heatmap(ax, fig, spec, d):
    xs, rs = sorted_x(d[spec.x]), sorted_x(d[spec.row])
    grid = np.array([[cell(d, {spec.row: r, spec.x: x}, spec.ys[0])[0] for x in xs] for r in rs], dtype=float)
    im = ax.imshow(grid, cmap="viridis", aspect="auto", origin="lower")
    fig.colorbar(im, ax=ax, label=spec.ylabel or value_label(spec.ys[0]))
    lo, hi = np.nanmin(grid), np.nanmax(grid)
    for i in range(len(rs)):
        for j in range(len(xs)):
            if np.isfinite(grid[i, j]):
                bright = hi > lo and (grid[i, j] - lo) / (hi - lo) > 0.6
                ax.text(j, i, fmt(float(grid[i, j]), spec.format), ha="center", va="center", fontsize=6,
                        color="black" if bright else "white")
    ax.set_xticks(range(len(xs)), [label(x) for x in xs])
    ax.set_yticks(range(len(rs)), [label(r) for r in rs])
    ax.grid(False)


def image_grid(spec, d, out_base: Path | None) -> dict:
    """The images of the points (column image.path), one per (row value, x value), captioned with y."""
    from PIL import Image

    if "image.path" not in d.columns:
        raise PlotError(f"plot {spec.title or spec.kind!r}: image_grid needs the points' images (outputs.images: true)")
    if spec.facet:
        raise PlotError(f"plot {spec.title or spec.kind!r}: image_grid has no facets (use where:)")
    plt = _plt()
    import matplotlib

    xs, rs = sorted_x(d[spec.x]), sorted_x(d[spec.row])
    with matplotlib.rc_context(STYLE):
        fig, axes = plt.subplots(len(rs), len(xs), figsize=(1.9 * len(xs), 1.9 * len(rs)), squeeze=False)
        for i, r in enumerate(rs):
            for j, x in enumerate(xs):
                ax = axes[i][j]
                sub = d[[same(a, r) and same(b, x) for a, b in zip(d[spec.row], d[spec.x])]]
                if len(sub) and Path(sub["image.path"].iloc[0]).exists():
                    ax.imshow(Image.open(sub["image.path"].iloc[0]))
                    v = cell(sub, {}, spec.ys[0])[0]
                    ax.set_title(f"{facet_title(spec.x, x)}\n{facet_title(spec.row, r)}\n"
                                 f"{spec.ylabel or value_label(spec.ys[0])} {fmt(v, spec.format or '{:.3f}')}",
                                 fontsize=7)
                ax.set_axis_off()
        if spec.title:
            fig.suptitle(spec.title, fontsize=9)
        files = _save(fig, out_base, dpi=150)
        texts = figure_labels(fig)
        plt.close(fig)
    return {"files": files, "markdown": grid_table(spec, d), "fits": [], "labels": texts}


# ---- entry point ---------------------------------------------------------------------------------

def render_plot(spec, df, out_base: Path | None, derived: dict | None = None, names: dict | None = None) -> dict:
    """Draw one plot spec. Returns {"files": [png, pdf], "markdown": [table lines], "fits": [...],
    "labels": [every title, axis label and legend text of the figure]}. ``df`` already carries the
    derived columns (``derived``: their expressions, for axis labels; ``names``: the config's
    outputs.column_labels); failed rows (status != ok) are left out."""
    with column_labels(names):
        return _render_plot(spec, df, out_base, derived)


def _render_plot(spec, df, out_base: Path | None, derived: dict | None = None) -> dict:
    if "status" in df.columns:
        df = df[df["status"] == "ok"]
    for col, names in spec.labels.items():  # display names replace the values (before where: and paper:)
        if col not in df.columns:
            raise PlotError(f"plot {spec.title or spec.kind!r}: labels: unknown column {col!r}")
        df = df.assign(**{col: [next((n for k, n in names.items() if same(v, k)), v) for v in df[col]]})
    if isinstance(spec.hue, list):  # several hue columns: one combined label column
        for col in spec.hue:
            if col not in df.columns:
                raise PlotError(f"plot {spec.title or spec.kind!r}: unknown hue column {col!r}")
        name = " / ".join(spec.hue)
        df = df.assign(**{name: [" ".join(label(v) for v in vals if not missing(v))
                                 for vals in zip(*(df[c] for c in spec.hue))]})
        spec = spec.model_copy(update={"hue": name})
    if spec.optional and any(c not in df.columns for c in [*spec_columns(spec), *spec.where]):
        return {"files": [], "markdown": [], "fits": [], "skipped": True}
    check_columns(df, spec)
    d = apply_where(df, spec.where)
    if not len(d):
        return {"files": [], "markdown": [f"*No data for this plot (where: {spec.where}).*"], "fits": []}
    hues = unique(d[spec.hue]) if spec.hue else [None]
    if spec.kind == "image_grid":
        return image_grid(spec, d, out_base)
    if spec.kind == "table":
        if spec.fit == "powerlaw":
            lines, fits = powerlaw_table(spec, d, hues)
            return {"files": [], "markdown": lines, "fits": fits}
        return {"files": [], "markdown": data_table(spec, d, hues), "fits": []}
    plt = _plt()
    import matplotlib

    with matplotlib.rc_context(STYLE):
        from matplotlib.ticker import NullFormatter

        facets = unique(d[spec.facet]) if spec.facet else [None]
        styles = unique(d[spec.style]) if spec.style else [None]
        fig, axes = _panels(plt, len(facets))
        for ax, f in zip(axes, facets):
            sub = d if f is None else d[[same(v, f) for v in d[spec.facet]]]
            if spec.kind == "scatter":
                _draw_scatter(ax, spec, sub, hues, styles)
            elif spec.kind == "heatmap":
                _draw_heatmap(ax, fig, spec, sub)
            else:
                {"line": _draw_line, "bar": _draw_bar}[spec.kind](ax, spec, sub, hues)
            if spec.logx:
                ax.set_xscale("log", base=2 if spec.x and "spp" in spec.x else 10)
                ax.xaxis.set_minor_formatter(NullFormatter())
                readable_log_ticks(ax.xaxis)
            if spec.logy:
                ax.set_yscale("log")
                ax.yaxis.set_minor_formatter(NullFormatter())
                readable_log_ticks(ax.yaxis)
            ax.set_xlabel(spec.xlabel or value_label(spec.x, derived))
            if spec.kind == "heatmap":
                ax.set_ylabel(value_label(spec.row, derived))
            else:
                ax.set_ylabel(spec.ylabel or (value_label(spec.ys[0], derived) if len(spec.ys) == 1 else "value"))
            if f is not None:
                ax.set_title(facet_title(spec.facet, f))
        # One legend for the figure (every panel uses the same colours), outside the panels when long.
        if spec.kind == "scatter":
            handles = _scatter_legend(spec, hues, styles)
        else:
            seen = {}
            for ax in axes:
                for hnd, lab in zip(*ax.get_legend_handles_labels()):
                    seen.setdefault(lab, hnd)
            handles = [h.__class__ and h for h in seen.values()]
            for hnd, lab in zip(handles, seen):
                hnd.set_label(lab)
        if len(handles) > 1 or (handles and spec.hue):
            handles = _sectioned(handles)
            title = value_label(spec.hue, derived) if spec.hue and spec.kind != "scatter" else None
            if len(axes) == 1 and len(handles) <= 6:
                axes[0].legend(handles=handles, title=title)
            else:
                fig.legend(handles=handles, loc="outside right center", title=title)
        lost = unmatched_paper(spec, d, hues) if spec.paper and spec.kind in ("line", "bar") else []
        if lost:
            import warnings

            warnings.warn(f"plot {spec.title or spec.kind!r}: paper values not drawn: {'; '.join(lost)}", stacklevel=2)
        if spec.title:
            fig.suptitle(spec.title, fontsize=9)
        files = _save(fig, out_base)
        texts = figure_labels(fig)
        plt.close(fig)
    return {"files": files, "markdown": grid_table(spec, d) if spec.kind == "heatmap" else data_table(spec, d, hues),
            "fits": [], "labels": texts}

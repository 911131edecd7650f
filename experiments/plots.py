"""Declarative plots: an `outputs.plots` spec (experiments.config.PlotSpec, docs/reports.md) and a
result table become a matplotlib figure (PNG + PDF) in one paper-like style and a Markdown table
with the paper's published numbers beside ours. There are no per-figure plotting scripts.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

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
_DOTTED = re.compile(r"(?<![\w`.])([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?![\w`(])")


class PlotError(ValueError):
    """A plot spec does not fit the result table (unknown column, bad derived expression)."""


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


# ---- data ----------------------------------------------------------------------------------------

def apply_derived(df, derived: dict[str, str]):
    """df with the `derived:` columns added, in order (a derived column may use earlier ones).
    Expressions are pandas expressions; dotted column names (raster.samples_tested) may be written bare."""
    df = df.copy()
    for name, expr in derived.items():
        quoted = _DOTTED.sub(lambda m: f"`{m.group(1)}`" if m.group(1) in df.columns else m.group(1), expr)
        try:
            df[name] = df.eval(quoted, engine="python")
        except Exception as e:  # noqa: BLE001 - reported with the expression
            raise PlotError(f"derived {name!r}: cannot evaluate {expr!r}: {type(e).__name__}: {e}") from None
    return df


def _same(a, b) -> bool:
    """Equality of a table value and a YAML value: numbers by value (0 == 0.0), otherwise as text."""
    try:
        return float(a) == float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)


def apply_where(df, where: dict):
    for col, want in where.items():
        if col not in df.columns:
            raise PlotError(f"where: unknown column {col!r}")
        wants = want if isinstance(want, list) else [want]
        df = df[[any(_same(v, w) for w in wants) for v in df[col]]]
    return df


def _unique(values) -> list:
    """Unique values in order of first appearance (the sweep order), NaN/None dropped."""
    out = []
    for v in values:
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        if not any(_same(v, o) and type(v) is type(o) for o in out) and v not in out:
            out.append(v)
    return out


def _sorted_x(values) -> list:
    vals = _unique(values)
    try:
        return sorted(vals, key=float)
    except (TypeError, ValueError):
        return vals


def _check_columns(df, spec):
    for col in [spec.x, spec.hue, spec.facet, spec.style, *spec.ys, *spec.columns]:
        if col is not None and col not in df.columns:
            near = [c for c in df.columns if col.split(".")[-1] in c][:6]
            raise PlotError(f"plot {spec.title or spec.kind!r}: unknown column {col!r}"
                            + (f" (similar: {near})" if near else ""))


def _missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def _label(v) -> str:
    if isinstance(v, float) and v.is_integer():
        return f"{v:g}"
    return str(v)


def _fmt(v, spec: str | None = None) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "n/a"
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v))
    if spec:
        try:
            return spec.format(v)
        except (ValueError, TypeError):
            return str(v)
    if isinstance(v, (int, np.integer)) or (isinstance(v, float) and v.is_integer() and abs(v) < 1e15):
        return f"{int(v):,}"
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    return f"{v:.4g}"


def _cell(df, keys: dict, y: str):
    """Mean of y over the rows matching keys; (value, number of rows)."""
    sub = df
    for k, v in keys.items():
        sub = sub[[_same(a, v) for a in sub[k]]]
    vals = sub[y].dropna()
    if not len(vals):
        return math.nan, 0
    if vals.dtype == object or vals.dtype.kind not in "biufc":  # strings, e.g. timing.bottleneck (Arrow)
        return vals.iloc[0], len(vals)
    return float(vals.mean()), len(vals)


def _paper_value(spec, group, x):
    """The published number for (hue value or y column, x), or None."""
    for g, by_x in spec.paper.items():
        if _same(g, group):
            for k, v in by_x.items():
                if _same(k, x):
                    return v
    return None


def _paper_number(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def md_table(header: list, rows: list[list]) -> list[str]:
    """A Markdown table; cells are formatted with str()."""
    return (["| " + " | ".join(map(str, header)) + " |", "|" + "---|" * len(header)]
            + ["| " + " | ".join(map(str, r)) + " |" for r in rows])


# ---- figures -------------------------------------------------------------------------------------

def _panels(plt, n: int):
    cols = min(n, 3)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(PANEL_INCHES[0] * cols, PANEL_INCHES[1] * rows), squeeze=False)
    flat = [a for row in axes for a in row]
    for a in flat[n:]:
        a.set_visible(False)
    return fig, flat[:n]


def _series(spec, hues) -> list[tuple]:
    """[(hue value or None, y column, label)] for every line/bar series."""
    out = []
    for h in hues:
        for y in spec.ys:
            if h is None:
                label = y if len(spec.ys) > 1 else (spec.ylabel or y)
            else:
                label = _label(h) if len(spec.ys) == 1 else f"{_label(h)}: {y}"
            out.append((h, y, label))
    return out


def _draw_line(ax, spec, d, hues):
    series = _series(spec, hues)
    xs_all = _sorted_x(d[spec.x])
    numeric = all(_paper_number(x) is not None for x in xs_all)
    pos = {i: x for i, x in enumerate(xs_all)}
    for i, (h, y, label) in enumerate(series):
        sub = d if h is None else d[[_same(v, h) for v in d[spec.hue]]]
        xs = _sorted_x(sub[spec.x])
        ys = [_cell(sub, {spec.x: x}, y)[0] for x in xs]
        px = [float(x) for x in xs] if numeric else [xs_all.index(x) for x in xs]
        ax.plot(px, ys, marker=MARKERS[i % len(MARKERS)], color=COLORS[i % len(COLORS)], label=label)
        group = h if h is not None else y
        paper = [(x, _paper_number(_paper_value(spec, group, x))) for x in (_paper_x(spec, group) or [])]
        paper = [(x, v) for x, v in paper if v is not None]
        if paper:
            ppx = [float(x) if numeric else (xs_all.index(x) if x in xs_all else None) for x, _ in paper]
            keep = [(a, v) for a, (_, v) in zip(ppx, paper) if a is not None]
            ax.plot([a for a, _ in keep], [v for _, v in keep], linestyle="--", marker="x", color=COLORS[i % len(COLORS)],
                    alpha=0.8, label=f"{_label(group)} (paper)")
    if not numeric:
        ax.set_xticks(list(pos), [_label(x) for x in pos.values()])


def _paper_x(spec, group) -> list | None:
    for g, by_x in spec.paper.items():
        if _same(g, group):
            return _sorted_x(list(by_x))
    return None


def _draw_bar(ax, spec, d, hues):
    xs = _unique(d[spec.x])
    if spec.stacked:
        cats = [(x, h) for x in xs for h in hues
                if any(_same(a, x) and (h is None or _same(b, h))
                       for a, b in zip(d[spec.x], d[spec.hue] if spec.hue else [None] * len(d)))]
        bottom = np.zeros(len(cats))
        for j, y in enumerate(spec.ys):
            vals = np.array([_cell(d, {spec.x: x, **({} if h is None else {spec.hue: h})}, y)[0] for x, h in cats],
                            dtype=float)
            ax.bar(range(len(cats)), np.nan_to_num(vals), bottom=bottom, color=COLORS[j % len(COLORS)], label=y,
                   width=0.7)
            bottom += np.nan_to_num(vals)
        ax.set_xticks(range(len(cats)), [_label(x) if h is None else f"{_label(x)}\n{_label(h)}" for x, h in cats],
                      rotation=0 if len(cats) < 6 else 30)
        return
    series = _series(spec, hues)
    width = 0.8 / max(len(series), 1)
    for i, (h, y, label) in enumerate(series):
        sub = d if h is None else d[[_same(v, h) for v in d[spec.hue]]]
        vals = [_cell(sub, {spec.x: x}, y)[0] for x in xs]
        offs = [k - 0.4 + width * (i + 0.5) for k in range(len(xs))]
        ax.bar(offs, vals, width=width * 0.95, color=COLORS[i % len(COLORS)], label=label)
        group = h if h is not None else y
        pts = [(o, _paper_number(_paper_value(spec, group, x))) for o, x in zip(offs, xs)]
        pts = [(o, v) for o, v in pts if v is not None]
        if pts:
            ax.scatter([o for o, _ in pts], [v for _, v in pts], marker="_", s=120, color="black", zorder=3,
                       label="paper" if i == 0 else None)
    ax.set_xticks(range(len(xs)), [_label(x) for x in xs])


def pareto_front(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both x and y (lower is better in both), by x."""
    order = np.lexsort((y, x))
    front, best = [], math.inf
    for i in order:
        if y[i] < best:
            front.append(i)
            best = y[i]
    return np.array(front, dtype=int)


def _draw_scatter(ax, spec, d, hues, styles=None):
    """Colour by hue, marker by style; the figure legend shows the two separately (proxies)."""
    y = spec.ys[0]
    styles = styles or [None]
    for i, h in enumerate(hues):
        for j, s in enumerate(styles):
            sub = d
            if h is not None:
                sub = sub[[_same(v, h) for v in sub[spec.hue]]]
            if s is not None:
                sub = sub[[_same(v, s) for v in sub[spec.style]]]
            if not len(sub):
                continue
            ax.scatter(sub[spec.x].astype(float), sub[y].astype(float), s=14, color=COLORS[i % len(COLORS)],
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
    for i, h in enumerate(hues):
        if h is not None:
            handles.append(Line2D([], [], linestyle="", marker="o", color=COLORS[i % len(COLORS)], label=_label(h)))
    for j, s in enumerate(styles):
        if s is not None:
            handles.append(Line2D([], [], linestyle="", marker=MARKERS[j % len(MARKERS)], color="0.4",
                                  label=_label(s)))
    if spec.pareto:
        handles.append(Line2D([], [], color="black", marker="o", markerfacecolor="none", linewidth=0.8,
                              label="Pareto front"))
    return handles


# ---- tables --------------------------------------------------------------------------------------

def data_table(spec, d, hues) -> list[str]:
    """Our numbers, one row per (facet, x) and one column per (y, hue), paper columns beside them."""
    facets = _unique(d[spec.facet]) if spec.facet else [None]
    if spec.kind == "scatter":
        cols = list(dict.fromkeys(c for c in (spec.facet, spec.hue, spec.style, *spec.columns, spec.x, spec.ys[0]) if c))
        rows = [[_fmt(r[c], spec.format) for c in cols] for _, r in d[cols].iterrows()]
        return md_table(cols, rows)
    if spec.x is None:  # plain listing of the y columns
        cols = list(dict.fromkeys([c for c in (spec.facet, spec.hue) if c] + spec.columns + spec.ys))
        rows = [[_fmt(r[c], spec.format) for c in cols] for _, r in d[cols].iterrows()]
        return md_table(cols, rows)
    groups = []  # (hue, y, header)
    for h in hues:
        for y in spec.ys:
            if h is None:
                header = y
            else:
                header = _label(h) if len(spec.ys) == 1 else f"{y} {_label(h)}"
            groups.append((h, y, header))
    header = ([spec.facet] if spec.facet else []) + [spec.x]
    paper_groups = []
    for h, y, head in groups:
        header.append(head)
        g = h if h is not None else y
        if any(_same(g, k) for k in spec.paper):
            header.append(f"{head} (paper)")
            paper_groups.append(g)
    extra = [k for k in spec.paper if not any(_same(k, (h if h is not None else y)) for h, y, _ in groups)]
    header += [f"{_label(k)} (paper)" for k in extra]
    rows = []
    for f in facets:
        df_f = d if f is None else d[[_same(v, f) for v in d[spec.facet]]]
        xs = _sorted_x(list(df_f[spec.x]) + [x for k in spec.paper for x in spec.paper[k]]) if f is facets[0] \
            else _sorted_x(df_f[spec.x])
        for x in xs:
            r = ([_label(f)] if spec.facet else []) + [_label(x)]
            for h, y, _ in groups:
                keys = {spec.x: x}
                if h is not None:
                    keys[spec.hue] = h
                v, n = _cell(df_f, keys, y)
                r.append(_fmt(v, spec.format) + (f" (mean of {n})" if n > 1 else ""))
                g = h if h is not None else y
                if g in paper_groups:
                    p = _paper_value(spec, g, x)
                    r.append("" if p is None else _fmt(p, spec.format))
            for k in extra:
                p = _paper_value(spec, k, x)
                r.append("" if p is None else _fmt(p, spec.format))
            rows.append(r)
    return md_table(header, rows)


def powerlaw_table(spec, d, hues) -> tuple[list[str], list[dict]]:
    """Fit y = c x^-alpha per (facet, hue) in log-log (least squares over the mean y at each x)."""
    facets = _unique(d[spec.facet]) if spec.facet else [None]
    y = spec.ys[0]
    rows, fits = [], []
    for f in facets:
        df_f = d if f is None else d[[_same(v, f) for v in d[spec.facet]]]
        for h in hues:
            sub = df_f if h is None else df_f[[_same(v, h) for v in df_f[spec.hue]]]
            xs = [x for x in _sorted_x(sub[spec.x])]
            pts = [(float(x), _cell(sub, {spec.x: x}, y)[0]) for x in xs]
            pts = [(a, b) for a, b in pts if a > 0 and b > 0 and np.isfinite(b)]
            if len(pts) < 2:
                continue
            lx, ly = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            slope, icpt = np.polyfit(lx, ly, 1)
            pred = slope * lx + icpt
            ss = float(np.sum((ly - ly.mean()) ** 2))
            r2 = 1.0 - float(np.sum((ly - pred) ** 2)) / ss if ss > 0 else 1.0
            fit = {"facet": f, "hue": h, "alpha": -float(slope), "r2": r2, "n": len(pts),
                   "x_min": pts[0][0], "x_max": pts[-1][0]}
            fits.append(fit)
            paper = _paper_value(spec, h if h is not None else y, "alpha") if spec.paper else None
            rows.append(([_label(f)] if spec.facet else []) + ([_label(h)] if spec.hue else [])
                        + [f"{fit['alpha']:.3f}", f"{r2:.3f}", str(len(pts)), f"{pts[0][0]:g}-{pts[-1][0]:g}"]
                        + ([_fmt(paper)] if spec.paper else []))
    header = ([spec.facet] if spec.facet else []) + ([spec.hue] if spec.hue else []) + [
        f"alpha ({y} ∝ {spec.x}^-alpha)", "R²", "points", f"{spec.x} range"] + (["paper alpha"] if spec.paper else [])
    return md_table(header, rows), fits


# ---- entry point ---------------------------------------------------------------------------------

def render_plot(spec, df, out_base: Path | None) -> dict:
    """Draw one plot spec. Returns {"files": [png, pdf], "markdown": [table lines], "fits": [...]}.
    ``df`` already carries the derived columns; failed rows (status != ok) are left out."""
    if "status" in df.columns:
        df = df[df["status"] == "ok"]
    for col, names in spec.labels.items():  # display names replace the values (before where: and paper:)
        if col not in df.columns:
            raise PlotError(f"plot {spec.title or spec.kind!r}: labels: unknown column {col!r}")
        df = df.assign(**{col: [next((n for k, n in names.items() if _same(v, k)), v) for v in df[col]]})
    if isinstance(spec.hue, list):  # several hue columns: one combined label column
        for col in spec.hue:
            if col not in df.columns:
                raise PlotError(f"plot {spec.title or spec.kind!r}: unknown hue column {col!r}")
        name = " / ".join(spec.hue)
        df = df.assign(**{name: [" ".join(_label(v) for v in vals if not _missing(v))
                                 for vals in zip(*(df[c] for c in spec.hue))]})
        spec = spec.model_copy(update={"hue": name})
    if spec.optional and any(c is not None and c not in df.columns
                             for c in [spec.x, spec.facet, spec.style, *spec.ys, *spec.where]):
        return {"files": [], "markdown": [], "fits": [], "skipped": True}
    _check_columns(df, spec)
    d = apply_where(df, spec.where)
    if not len(d):
        return {"files": [], "markdown": [f"*No data for this plot (where: {spec.where}).*"], "fits": []}
    hues = _unique(d[spec.hue]) if spec.hue else [None]
    if spec.kind == "table":
        if spec.fit == "powerlaw":
            lines, fits = powerlaw_table(spec, d, hues)
            return {"files": [], "markdown": lines, "fits": fits}
        return {"files": [], "markdown": data_table(spec, d, hues), "fits": []}
    plt = _plt()
    import matplotlib

    with matplotlib.rc_context(STYLE):
        from matplotlib.ticker import NullFormatter

        facets = _unique(d[spec.facet]) if spec.facet else [None]
        styles = _unique(d[spec.style]) if spec.style else [None]
        fig, axes = _panels(plt, len(facets))
        for ax, f in zip(axes, facets):
            sub = d if f is None else d[[_same(v, f) for v in d[spec.facet]]]
            if spec.kind == "scatter":
                _draw_scatter(ax, spec, sub, hues, styles)
            else:
                {"line": _draw_line, "bar": _draw_bar}[spec.kind](ax, spec, sub, hues)
            if spec.logx:
                ax.set_xscale("log", base=2 if spec.x and "spp" in spec.x else 10)
                ax.xaxis.set_minor_formatter(NullFormatter())
            if spec.logy:
                ax.set_yscale("log")
                ax.yaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(spec.xlabel or spec.x)
            ax.set_ylabel(spec.ylabel or (spec.ys[0] if len(spec.ys) == 1 else "value"))
            if f is not None:
                name = spec.facet.removesuffix(".name").split(".")[-1]
                ax.set_title(f"{name} = {_label(f)}")
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
            if len(axes) == 1 and len(handles) <= 6:
                axes[0].legend(handles=handles)
            else:
                fig.legend(handles=handles, loc="outside right upper")
        if spec.title:
            fig.suptitle(spec.title, fontsize=9)
        files = []
        if out_base is not None:
            out_base.parent.mkdir(parents=True, exist_ok=True)
            for ext in ("png", "pdf"):
                p = out_base.with_suffix(f".{ext}")
                fig.savefig(p, metadata={"CreationDate": None} if ext == "pdf" else None)
                files.append(p)
        plt.close(fig)
    return {"files": files, "markdown": data_table(spec, d, hues), "fits": []}

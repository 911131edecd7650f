"""Result frames: the data side of a report (derived columns, where: filters, the cells of a
table or figure, the published numbers of a plot spec, the Pareto front). No drawing here."""
from __future__ import annotations

import math
import re

import numpy as np

_DOTTED = re.compile(r"(?<![\w`.])([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?![\w`(])")


from ..config.schema import ConfigError  # noqa: E402

def ok_rows(df):
    """The rows of a result table whose point finished (status 'ok'; every row when there is no status)."""
    return df[df["status"] == "ok"] if "status" in df.columns else df


# {config name: (config, rows, rows with derived columns)} of the sections written in this process
# (experiments.report.pages fills it; named tables and prose read it)
PROSE_DATA: dict = {}


class PlotError(ConfigError):
    """A plot spec does not fit the result table (unknown column, bad derived expression)."""


def apply_derived(df, derived: dict[str, str]):
    """df with the `derived:` columns added, in order (a derived column may use earlier ones).
    Expressions are pandas expressions; dotted column names (raster.samples_tested) may be written bare; or
    NAME(), a row function of experiments/config/columns.py ROW_FUNCTIONS."""
    from ..config.columns import row_function

    df = df.copy()
    for name, expr in derived.items():
        fn = row_function(expr)
        if fn is not None:  # a declared row function (experiments/config/columns.py ROW_FUNCTIONS)
            df[name] = list(fn(df)) if len(df) else []
            continue
        quoted = _DOTTED.sub(lambda m: f"`{m.group(1)}`" if m.group(1) in df.columns else m.group(1), expr)
        try:
            df[name] = df.eval(quoted, engine="python")
        except Exception as e:  # noqa: BLE001 - reported with the expression
            raise PlotError(f"derived {name!r}: cannot evaluate {expr!r}: {type(e).__name__}: {e}") from None
    return df


def same(a, b) -> bool:
    """Equality of a table value and a YAML value: numbers by value (0 == 0.0), otherwise as text."""
    try:
        return float(a) == float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)


def apply_where(df, where: dict):
    """The rows whose column equals the value (or one of a list of values); null matches a missing value."""
    for col, want in where.items():
        if col not in df.columns:
            raise PlotError(f"where: unknown column {col!r}")
        wants = want if isinstance(want, list) else [want]
        df = df[[any(missing(v) if w is None else same(v, w) for w in wants) for v in df[col]]]
    return df


def unique(values) -> list:
    """Unique values in order of first appearance (the sweep order), NaN/None dropped."""
    out = []
    for v in values:
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        if not any(same(v, o) and type(v) is type(o) for o in out) and v not in out:
            out.append(v)
    return out


def sorted_x(values) -> list:
    vals = unique(values)
    try:
        return sorted(vals, key=float)
    except (TypeError, ValueError):
        return vals


def spec_columns(spec) -> list[str]:
    """Every result column a plot spec draws (x, hue, facet, style, row, ys, columns)."""
    cols = [spec.x, spec.hue, spec.facet, spec.style, spec.row, *spec.ys, *spec.columns]
    return [c for c in cols if c is not None]


def check_columns(df, spec):
    import difflib

    for col in spec_columns(spec):
        if col not in df.columns:
            near = difflib.get_close_matches(col, [str(c) for c in df.columns], n=2, cutoff=0.6)
            raise PlotError(f"plot {spec.title or spec.kind!r}: unknown column {col!r}"
                            + (f"; did you mean {' or '.join(repr(c) for c in near)}?" if near else ""))


def missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def label(v) -> str:
    if isinstance(v, float) and v.is_integer():
        return f"{v:g}"
    return str(v)


def fmt(v, spec: str | None = None) -> str:
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


def cell(df, keys: dict, y: str):
    """Mean of y over the rows matching keys; (value, number of rows). The keys select row positions
    and only column y is taken (a report frame has hundreds of columns)."""
    rows = range(len(df))
    for k, v in keys.items():
        col = list(df[k])
        rows = [i for i in rows if same(col[i], v)]
    vals = df[y].iloc[list(rows)].dropna()
    if not len(vals):
        return math.nan, 0
    if vals.dtype == object or vals.dtype.kind not in "biufc":  # strings, e.g. timing.bottleneck (Arrow)
        return vals.iloc[0], len(vals)
    return float(vals.mean()), len(vals)


def paper_value(spec, group, x):
    """The published number for (hue value or y column, x), or None."""
    for g, by_x in spec.paper.items():
        if same(g, group):
            for k, v in by_x.items():
                if same(k, x):
                    return v
    return None


def paper_number(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def pareto_front(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both x and y (lower is better in both), by x."""
    order = np.lexsort((y, x))
    front, best = [], math.inf
    for i in order:
        if y[i] < best:
            front.append(i)
            best = y[i]
    return np.array(front, dtype=int)

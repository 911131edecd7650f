"""Page prose as a template over the page's data: every figure in a config's `outputs.text` (and
`outputs.summary`) is a placeholder that the page fills from its tables, so rerunning with other
numbers rewrites the sentence (docs/reports.md §Prose).

    {tested_over_optimal[scene=bunny, coc_px=10]:.2f}       one cell of this section's rows
    {range(tested_over_optimal[coc_px=50]):.2f}             "1.16–1.67" over the matching rows
    {table2_culling.culled[scene=spot, R=10, mode=h_i]:.0%}  a named table's values
    {table1.gops[scene=bunny, coc_px=0]}                     another config on the same page
    {100 * (ops.total[algorithm=tile] / ops.total[algorithm=interval] - 1):+.0f}
    {order(culled[scene=bunny, R=10], mode)}                 "h_i+H_j > INTERVAL > H_j > ..."
    {"yes" if all(ops.total[algorithm=tile] < ops.total[algorithm=interval]) else "no"}
    {paper: 1.20 / 1.22 / 1.27}                              a published figure, quoted as given

A reference is COLUMN[KEY=VALUE, ...]: the rows of the source whose KEY equals VALUE (numbers by value,
text as text; `a|b` for either), COLUMN's values in sweep order. KEY and COLUMN are result columns
(derived ones included); a key may be shortened to a unique last part (`coc_px` for `camera.coc_px`,
`algorithm` for `pipeline.algorithm`) or to the section of a `.name` column (`scene`). The source is this
config's rows, or the config or named value table named before the first dot. Arithmetic between two
references pairs their rows by the config columns that vary and that neither reference fixes.

Functions: range, min, max, mean, sum, count, list (values joined by " / "), distinct (the distinct
values, joined the same way), order(x, KEY) (the KEY
values by falling x, "a > b > c"), argmax(x, KEY), argmin(x, KEY), all, any, abs. The format after the
last colon applies to every number (a range's ends, a list's items); a bool prints yes/no.
"""
from __future__ import annotations

import ast
import math
import re

import numpy as np
import pandas as pd

from .frames import PlotError, fmt, label, missing, same

# A column reference: a dotted name followed by a bracketed selector.
_REF = re.compile(r"(?<![\w.])([A-Za-z_][\w]*(?:\.[A-Za-z_][\w]*)*)\[([^\[\]]*)\]")
_FORMAT = re.compile(r"^[<>=^]?[+\- ]?#?0?\d*[,_]?(?:\.\d+)?[eEfFgGn%d]?$")
_PAPER = re.compile(r"\{paper:\s*([^{}]*)\}")
# A placeholder: one pair of braces that is not part of {{table:NAME}}.
_PLACEHOLDER = re.compile(r"(?<!\{)\{(?!\{)((?:[^{}`]|`[^`]*`)+)\}(?!\})")
_CONFIG_PREFIXES = ("scene.", "camera.", "samples.", "pipeline.", "hardware.", "point.", "metrics.")
DASH = "–"


class ProseError(PlotError):
    """A placeholder of a page's prose does not fit the page's data (names the placeholder)."""


def code_spans(text: str) -> list[tuple[int, int]]:
    """(start, end) of every Markdown code span (`...`) and fenced block in text."""
    spans = [(m.start(), m.end()) for m in re.finditer(r"```.*?```", text, flags=re.S)]
    for m in re.finditer(r"(`+)(?!`)(.+?)(?<!`)\1(?!`)", text, flags=re.S):
        if not any(a <= m.start() < b for a, b in spans):
            spans.append((m.start(), m.end()))
    return sorted(spans)


def placeholders(text: str) -> list[re.Match]:
    """The placeholders of a template, outside code spans ({paper: ...} included)."""
    spans = code_spans(text)
    return [m for m in _PLACEHOLDER.finditer(text) if not any(a <= m.start() < b for a, b in spans)]


# ---- values ---------------------------------------------------------------------------------------

class Cells:
    """The values a reference selects, in sweep order, with their rows; ``ident``: the config columns that
    vary in the source and that the selector does not fix, which pair the rows of two references."""

    def __init__(self, values: list, rows: pd.DataFrame, ident: list[str], source: str):
        self.values = list(values)
        self.rows = rows.reset_index(drop=True)
        self.ident = list(ident)
        self.source = source

    def __len__(self):
        return len(self.values)

    def like(self, values: list) -> "Cells":
        return Cells(values, self.rows, self.ident, self.source)

    def scalar(self):
        if len(self.values) == 1:
            return self.values[0]
        distinct = {str(v) for v in self.values}
        if len(distinct) == 1:
            return self.values[0]
        raise ProseError(f"{self.source} selects {len(self.values)} rows with different values; add keys to the "
                         "selector or use range(), list(), min() or max()")


def _keys(rows: pd.DataFrame, cols: list[str]) -> list[tuple]:
    return [tuple(label(v) for v in row) for row in rows[cols].itertuples(index=False)]


def _pair(a, b, op, what: str):
    """op applied to two values (Cells or scalars), pairing Cells row by row on their shared identity."""
    if not isinstance(a, Cells) and not isinstance(b, Cells):
        return op(a, b)
    if not isinstance(a, Cells):
        return b.like([op(a, v) for v in b.values])
    if not isinstance(b, Cells):
        return a.like([op(v, b) for v in a.values])
    if len(a) == 1 and len(b) == 1:
        return op(a.values[0], b.values[0])
    if len(a) == 1:
        return b.like([op(a.values[0], v) for v in b.values])
    if len(b) == 1:
        return a.like([op(v, b.values[0]) for v in a.values])
    # pair on the swept columns that vary within either side (one held constant on each side, such as the
    # algorithm a derived selector picks, says nothing about which rows go together)
    shared = [c for c in a.ident if c in b.ident and (a.rows[c].nunique(dropna=False) > 1
                                                      or b.rows[c].nunique(dropna=False) > 1)]
    ka, kb = _keys(a.rows, shared), _keys(b.rows, shared)
    if len(set(ka)) != len(ka) or len(set(kb)) != len(kb) or set(ka) != set(kb):
        raise ProseError(f"{what}: cannot pair the rows of {a.source} ({len(a)}) and {b.source} ({len(b)}) by "
                         f"{shared or 'no varying column'}; fix more keys in the selectors")
    index = {k: i for i, k in enumerate(kb)}
    return Cells([op(v, b.values[index[k]]) for v, k in zip(a.values, ka)], a.rows, shared, a.source)


class Joined:
    """A range or list of values, formatted with the placeholder's format."""

    def __init__(self, values: list, kind: str):
        self.values, self.kind = values, kind

    def format(self, spec: str | None) -> str:
        parts = [_format_one(v, spec) for v in self.values]
        if self.kind == "range":
            if parts[0] == parts[-1]:
                return parts[0]
            lo, hi = parts[0], parts[-1]
            if lo.endswith(" %") and hi.endswith(" %"):  # 5–20 %, not 5 %–20 %
                lo = lo[:-2]
            return f"{lo}{DASH}{hi}"
        return ("; " if any("/" in x for x in parts) else " / ").join(parts)


def _format_one(v, spec: str | None) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, str):
        return v
    if spec:
        try:
            return format(float(v) if not isinstance(v, (int, np.integer)) or "%" in spec or "f" in spec else v,
                          spec).replace("%", " %")
        except (TypeError, ValueError):
            return str(v)
    return fmt(float(v) if isinstance(v, np.floating) else v)


# ---- evaluation -----------------------------------------------------------------------------------

def _numbers(x, what: str) -> list:
    vals = x.values if isinstance(x, Cells) else [x]
    out = []
    for v in vals:
        if missing(v):
            continue
        try:
            out.append(float(v))
        except (TypeError, ValueError):
            raise ProseError(f"{what}: {v!r} is not a number") from None
    if not out:
        raise ProseError(f"{what}: no numbers")
    return out


def _labelled(x, key: str, what: str) -> list[tuple[float, str]]:
    if not isinstance(x, Cells):
        raise ProseError(f"{what}: needs a reference")
    col = _resolve_column(x.rows, key, what)
    return [(float(v), label(k)) for v, k in zip(x.values, x.rows[col]) if not missing(v)]


def _order(x, key, what):
    pairs = sorted(_labelled(x, key, what), key=lambda p: -p[0])
    return " > ".join(lab for _, lab in pairs)


FUNCTIONS = {
    "range": lambda x, what: Joined(sorted(set(_numbers(x, what))), "range") if len(set(_numbers(x, what))) > 1
    else _numbers(x, what)[0],
    "min": lambda x, what: min(_numbers(x, what)),
    "max": lambda x, what: max(_numbers(x, what)),
    "mean": lambda x, what: float(np.mean(_numbers(x, what))),
    "sum": lambda x, what: float(np.sum(_numbers(x, what))),
    "count": lambda x, what: len(x.values) if isinstance(x, Cells) else 1,
    "list": lambda x, what: Joined(x.values if isinstance(x, Cells) else [x], "list"),
    "distinct": lambda x, what: Joined(list(dict.fromkeys(x.values if isinstance(x, Cells) else [x])), "list"),
    "all": lambda x, what: bool(all(bool(v) for v in (x.values if isinstance(x, Cells) else [x]))),
    "any": lambda x, what: bool(any(bool(v) for v in (x.values if isinstance(x, Cells) else [x]))),
    "abs": lambda x, what: _pair(x, 0, lambda a, _b: abs(a), what),
}
KEYED = {
    "order": _order,
    "argmax": lambda x, key, what: max(_labelled(x, key, what))[1],
    "argmin": lambda x, key, what: min(_labelled(x, key, what))[1],
}
_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
           ast.Div: lambda a, b: a / b if b else math.nan, ast.Pow: lambda a, b: a ** b}
_COMPARE = {ast.Lt: lambda a, b: a < b, ast.LtE: lambda a, b: a <= b, ast.Gt: lambda a, b: a > b,
            ast.GtE: lambda a, b: a >= b, ast.Eq: lambda a, b: a == b, ast.NotEq: lambda a, b: a != b}


def _dotted(node) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        head = _dotted(node.value)
        return None if head is None else f"{head}.{node.attr}"
    return None


class _Evaluator:
    def __init__(self, refs: dict, what: str):
        self.refs, self.what = refs, what

    def __call__(self, node):
        what = self.what
        if isinstance(node, ast.Expression):
            return self(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float, str, bool)):
            return node.value
        if isinstance(node, ast.Name) and node.id in self.refs:
            return self.refs[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            return _pair(self(node.left), self(node.right), _BINARY[type(node.op)], what)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd, ast.Not)):
            v = self(node.operand)
            f = {ast.USub: lambda a: -a, ast.UAdd: lambda a: +a, ast.Not: lambda a: not a}[type(node.op)]
            return _pair(v, 0, lambda a, _b: f(a), what)
        if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _COMPARE:
            return _pair(self(node.left), self(node.comparators[0]), _COMPARE[type(node.ops[0])], what)
        if isinstance(node, ast.BoolOp):
            vals = [self(v) for v in node.values]
            vals = [all(x.values) if isinstance(x, Cells) else x for x in vals]
            return all(vals) if isinstance(node.op, ast.And) else any(vals)
        if isinstance(node, ast.IfExp):
            test = self(node.test)
            if isinstance(test, Cells):
                test = test.scalar()
            return self(node.body) if test else self(node.orelse)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
            name = node.func.id
            if name in FUNCTIONS and len(node.args) == 1:
                return FUNCTIONS[name](self(node.args[0]), what)
            if name in KEYED and len(node.args) == 2:
                key = _dotted(node.args[1])
                if key is None and isinstance(node.args[1], ast.Constant):
                    key = str(node.args[1].value)
                return KEYED[name](self(node.args[0]), key, what)
        raise ProseError(f"{what}: cannot evaluate {ast.unparse(node)!r} (references, numbers, + - * / **, "
                         f"comparisons, `a if c else b` and {', '.join([*FUNCTIONS, *KEYED])})")


# ---- sources --------------------------------------------------------------------------------------

class Sources:
    """What a page's prose may read: this section's rows (with derived columns), the other configs of the
    page by name, and named value tables (experiments/report/tables.py VALUES) by name."""

    def __init__(self, own: pd.DataFrame, others: dict | None = None, values: dict | None = None):
        self.own = own
        self.others = dict(others or {})
        self.values = dict(values or {})

    def frame(self, dotted: str) -> tuple[pd.DataFrame, str, str]:
        head, _, rest = dotted.partition(".")
        if rest and head in self.values:
            return self.values[head](), rest, head
        if rest and head in self.others:
            return self.others[head], rest, head
        return self.own, dotted, ""


def _resolve_column(df: pd.DataFrame, key: str, what: str) -> str:
    cols = [str(c) for c in df.columns]
    if key in cols:
        return key
    if f"{key}.name" in cols:
        return f"{key}.name"
    tail = [c for c in cols if c.endswith("." + key)]
    if len(tail) == 1:
        return tail[0]
    import difflib

    if len(tail) > 1:
        raise ProseError(f"{what}: {key!r} is ambiguous ({', '.join(tail)})")
    near = difflib.get_close_matches(key, cols, n=2, cutoff=0.6)
    raise ProseError(f"{what}: unknown column {key!r}" + (f"; did you mean {' or '.join(near)}?" if near else ""))


def _value(text: str):
    text = text.strip()
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    if low == "null":
        return None
    try:
        return float(text)
    except ValueError:
        return text


def _matches(v, want) -> bool:
    if want is None:
        return missing(v)
    if isinstance(want, bool):
        return str(v) == str(want)
    return same(v, want)


def _identity(df: pd.DataFrame, fixed: set[str]) -> list[str]:
    """The config columns (a named table's key columns) that vary in df and are not fixed."""
    keys = df.attrs.get("keys")
    out = []
    for c in df.columns:
        c = str(c)
        if c in fixed or not (c in keys if keys else c.startswith(_CONFIG_PREFIXES)):
            continue
        if len({label(v) for v in df[c] if not missing(v)}) > 1:
            out.append(c)
    return out


def reference(sources: Sources, dotted: str, selector: str, what: str) -> Cells:
    df, column, source = sources.frame(dotted)
    col = _resolve_column(df, column, what)
    fixed = set()
    sub = df
    for part in [p for p in _split(selector, ",") if p.strip()]:
        if "=" not in part:
            raise ProseError(f"{what}: expected KEY=VALUE in the selector, got {part.strip()!r}")
        key, _, val = part.partition("=")
        kcol = _resolve_column(df, key.strip(), what)
        wants = [_value(v) for v in _split(val, "|")]
        sub = sub[[any(_matches(v, w) for w in wants) for v in sub[kcol]]]
        if len(wants) == 1:
            fixed.add(kcol)
    if not len(sub):
        raise ProseError(f"{what}: no row of {source or 'this section'} matches [{selector}]")
    vals = [v.item() if hasattr(v, "item") else v for v in sub[col]]
    return Cells(vals, sub, _identity(df, fixed | {col}), f"{dotted}[{selector}]")


def _split(text: str, sep: str) -> list[str]:
    """Split on sep outside quotes."""
    out, cur, quote = [], "", None
    for ch in text:
        if quote:
            cur += ch
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
            cur += ch
        elif ch == sep:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    out.append(cur)
    return out


def _split_format(body: str) -> tuple[str, str | None]:
    depth, quote = 0, None
    for i in range(len(body) - 1, -1, -1):
        ch = body[i]
        if quote:
            if ch == quote:
                quote = None
            continue
        if ch in "'\"":
            quote = ch
        elif ch in ")]":
            depth += 1
        elif ch in "([":
            depth -= 1
        elif ch == ":" and depth == 0:
            spec = body[i + 1:].strip()
            if _FORMAT.match(spec):
                return body[:i], spec
            return body, None
    return body, None


def evaluate(body: str, sources: Sources) -> str:
    """The text of one placeholder body (without braces)."""
    what = "{" + body + "}"
    paper = re.match(r"^\s*paper:\s*(.*)$", body, flags=re.S)
    if paper:
        return paper.group(1).strip()
    expr, spec = _split_format(body)
    refs = {}

    def sub(m):
        name = f"__r{len(refs)}"
        refs[name] = reference(sources, m.group(1), m.group(2), what)
        return name

    code = _REF.sub(sub, expr.strip())
    if not refs:
        raise ProseError(f"{what}: a figure must come from the page's data (no reference in it)")
    try:
        tree = ast.parse(code, mode="eval")
    except SyntaxError as e:
        raise ProseError(f"{what}: not an expression ({e.msg})") from None
    value = _Evaluator(refs, what)(tree)
    if isinstance(value, Cells):
        value = value.scalar()
    if isinstance(value, Joined):
        return value.format(spec)
    return _format_one(value, spec)


def fill(text: str, sources: Sources) -> str:
    """The template with every placeholder replaced by its value (ProseError names the first bad one)."""
    out, last = [], 0
    for m in placeholders(text):
        out.append(text[last:m.start()])
        out.append(evaluate(m.group(1), sources))
        last = m.end()
    out.append(text[last:])
    return "".join(out)


__all__ = ["fill", "evaluate", "Sources", "ProseError", "placeholders", "code_spans"]


# ---- typed figures: what a template may not contain ----------------------------------------------------

_LOCATOR = re.compile(r"(?:§|\bTables?|\bFigs?\.|\bFigures?|\bEqs?\.|\bAppendix|\bSec\.|\bSection|\bSlides?)\s*"
                      r"[A-Z]?\d+(?:\.\d+)*[a-z]?(?:\s*(?:[–-]|,|and)\s*[A-Z]?\d+(?:\.\d+)*[a-z]?)*")
_CITATION = re.compile(r"\[[A-Z][^\]\[]*?\d{4}[a-z]?\]")
_LINK_TARGET = re.compile(r"\]\([^)]*\)|https?://\S+")
_NAMES = re.compile(r"\(\d\+\d\)D|\b\d+D\b|\b[A-Za-z_]+\d+\w*|\b\d+(?:st|nd|rd|th)\b"
                    r"|\b\d+ ?% (?=(?:t |confidence )?(?:intervals?|level|confidence))")  # a statistical level
_NUMBER = re.compile(r"(?<![\w.])[-+−]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?(?:\s*(?:%|×|x(?![a-z\d])|k\b|M\b|G\b))?")
_SHAPE = re.compile(r"(?<![\w.])(\d+)\s*[x×]\s*(\d+)(?![\w.])")


def config_numbers(*dicts) -> set[str]:
    """Every number of the given (nested) config dicts as text ('64', '0.5', '1e-06'), keys included."""
    out: set[str] = set()

    def walk(v):
        if isinstance(v, dict):
            for k, x in v.items():
                walk(k)
                walk(x)
        elif isinstance(v, (list, tuple)):
            for x in v:
                walk(x)
        elif isinstance(v, bool):
            return
        elif isinstance(v, (int, float)):
            out.add(f"{v:g}")
            if float(v).is_integer():
                out.add(str(int(v)))
        elif isinstance(v, str):
            for n in re.findall(r"\d+(?:\.\d+)?", v):
                out.add(f"{float(n):g}")
    for d in dicts:
        walk(d)
    return out


def typed_figures(text: str, allowed: set[str]) -> list[str]:
    """The figures typed into a template instead of read from the data: every number outside placeholders,
    code spans, links, citation keys ([Akenine-Möller 2012]) and locators (§5.1, Table 2, Fig. 15) and
    names (5D, h_i, float32), except the numbers among ``allowed`` (the config's own values: 64 spp,
    CoC 10, 2x2 tiles, focus 3.5) and 0, 1 and 2. A percentage, a ratio (3x), a thousands-separated count
    or a k/M/G count is always a typed figure. {paper: ...} quotes a published figure as given."""
    spans = code_spans(text) + [(m.start(), m.end()) for m in placeholders(text)]
    keep = []
    last = 0
    for a, b in sorted(spans):
        if a >= last:
            keep.append(text[last:a])
            last = b
    keep.append(text[last:])
    rest = " ".join(keep)
    for pattern in (_LINK_TARGET, _CITATION, _LOCATOR, _NAMES):
        rest = pattern.sub(" ", rest)
    found = []
    for m in _SHAPE.finditer(rest):  # 2x2 tiles, 320x180 px: parameters when both sides are
        if not {m.group(1), m.group(2)} <= allowed | {"1", "2"}:
            found.append(m.group(0))
    rest = _SHAPE.sub(" ", rest)
    for m in _NUMBER.finditer(rest):
        tok = m.group(0).strip()
        plain = re.match(r"[-+−]?([\d,]+(?:\.\d+)?)", tok).group(1).replace(",", "")
        if tok.endswith(("%", "×", "x", "k", "M", "G")) or "," in tok:
            found.append(tok)
        elif "." in plain and f"{float(plain):g}" not in allowed:  # a decimal parameter of the config passes
            found.append(tok)
        elif plain not in allowed and plain not in ("0", "1", "2"):
            found.append(tok)
    return found

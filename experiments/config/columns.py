"""The result columns a config's `outputs:` may name, checked when the config is loaded: every plot
and table column (x, y, hue, facet, style, row, columns, the keys of where: and labels:) and every
dotted name in a derived expression must be a counter or derived figure (sim.counter_docs()), a
column of the resolved config, a swept key, a row column the point kind adds, or an earlier derived
column. An unknown one is a ConfigError naming the file and line, with a "did you mean"."""
from __future__ import annotations

import difflib
import re

from .schema import ConfigError, RenderConfig, validate_model
from .sweep import RESULT_EXCLUDE, flatten

# Columns every row has besides the config and the counters (experiments/run/points.py, store.py).
ROW_COLUMNS = {"config_hash", "status", "error", "traceback", "time.wall_s", "engine.version", "engine.git_rev",
               "inputs.files", "scene.triangles", "resolved.lens_grid", "image.path", "query.visible",
               "query.samples_passed", "conservative.pixels_covered"}
# Columns of outputs.metrics (experiments/run/metrics.py).
METRIC_COLUMNS = {"metric.rmse", "metric.psnr", "metric.ssim", "metric.ghosting", "metric.flip"}
# Columns the timing_reference point kind adds besides reference.* and bin.* (the timing figures of the
# cycle-stepped reference and of the model on bin records): CPU seconds of each side on the same records.
TIMING_REFERENCE_COLUMNS = {"time.model_s": "CPU seconds of the timing model on the render's visit records",
                            "time.reference_s": "CPU seconds of the cycle-stepped reference on the same records"}
# Families of columns whose members depend on the point (a named scene's parameters, the camera the
# scene's hint resolved, the point section, per-object level-of-detail figures).
PREFIXES = ("scene.params.", "point.", "camera.", "lod.", "query.")

_DOTTED = re.compile(r"(?<![\w`.'\"])([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?![\w`(])")


def known_columns(config: RenderConfig) -> set[str]:
    """Every column a row of this config can have (before derived columns)."""
    import sim

    docs = set(sim.counter_docs())
    known = docs | {f"{k}.ci95" for k in docs} | ROW_COLUMNS | METRIC_COLUMNS
    known |= set(flatten(config.model_dump(exclude=RESULT_EXCLUDE | {"hardware"})))
    try:
        known |= set(flatten({"hardware": config.hardware_config().describe()}))
    except Exception:  # noqa: BLE001 - reported by validate
        pass
    for k in config.sweep:
        if k != "zip":
            known.add(k)
    if config.point.kind == "timing_reference":  # experiments/run/points.py _timing_reference
        timing = [k[len("timing."):] for k in docs if k.startswith("timing.")]
        known |= {f"{side}.{k}" for side in ("reference", "bin") for k in timing}
        known |= set(TIMING_REFERENCE_COLUMNS)
    return known


def _swept_sections(config: RenderConfig) -> tuple[str, ...]:
    """Prefixes of the columns of swept whole sections (scene: [...] gives scene.name, scene.path)."""
    return tuple(f"{k}." for k, v in config.sweep.items() if k != "zip" and any(isinstance(x, dict) for x in v))


def _suggest(name: str, known) -> str:
    close = difflib.get_close_matches(name, sorted(known), n=2, cutoff=0.6)
    return f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


def validate(data: dict, source: str = "config", lines: dict | None = None) -> RenderConfig:
    """The RenderConfig of a merged config dict (schema.validate_model) with every column its outputs name
    checked (check_output_columns); ConfigError naming file, line, key and value."""
    config = validate_model(data, source, lines)
    check_output_columns(config, source, lines)
    return config


def check_output_columns(config: RenderConfig, source: str = "config", lines: dict | None = None) -> None:
    """ConfigError listing every unknown column of config.outputs (plots, tables, derived expressions),
    each with its file:line and the nearest known names."""
    o = config.outputs
    if not o.plots and not o.derived:
        return
    lines = lines or {}
    known = known_columns(config)
    prefixes = PREFIXES + _swept_sections(config)
    errors = []

    def ok(col: str) -> bool:
        return col in known or col.startswith(prefixes) or (col.endswith(".ci95") and ok(col[:-5]))

    for name, expr in o.derived.items():
        for ref in _DOTTED.findall(expr):
            if not ok(ref) and ref not in o.derived:
                where = lines.get(("outputs", "derived", name), source)
                errors.append(f"{where}: outputs.derived.{name}: unknown column {ref!r} in {expr!r}"
                              f"{_suggest(ref, known | set(o.derived))}")
        known.add(name)
    for i, spec in enumerate(o.plots):
        hue = spec.hue if isinstance(spec.hue, list) else [spec.hue]
        named = {"x": [spec.x], "y": spec.ys, "hue": hue, "facet": [spec.facet], "style": [spec.style],
                 "row": [spec.row], "columns": spec.columns, "where": list(spec.where), "labels": list(spec.labels)}
        if spec.map is not None:
            named["y"] = [] if not spec.y else named["y"]
        for field, cols in named.items():
            for col in cols:
                if col is None or col == "" or ok(col):
                    continue
                where = lines.get(("outputs", "plots", i, field), lines.get(("outputs", "plots", i), source))
                title = f" ({spec.title!r})" if spec.title else ""
                errors.append(f"{where}: outputs.plots[{i}]{title}.{field}: unknown column {col!r}"
                              f"{_suggest(col, known)}")
    for col in o.column_labels:
        if not ok(col):
            where = lines.get(("outputs", "column_labels", col), lines.get(("outputs", "column_labels"), source))
            errors.append(f"{where}: outputs.column_labels: unknown column {col!r}{_suggest(col, known)}")
    if errors:
        raise ConfigError("\n".join(dict.fromkeys(errors)))

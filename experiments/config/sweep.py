"""Sweep expansion (cartesian product and `zip:` groups), the per-point validation, and the identity
of a point in the result store (config_hash, flatten)."""
from __future__ import annotations

import copy
import hashlib
import functools
import itertools
import json
import re

from .inputs import config_inputs
from .schema import ConfigError, RenderConfig, validate_model


def set_dotted(d: dict, dotted: str, value, source: str):
    parts = dotted.split(".")
    node = d
    for p in parts[:-1]:
        child = node.setdefault(p, {})
        if not isinstance(child, dict):
            raise ConfigError(f"{source}: cannot set {dotted!r}: {p!r} is not a section")
        node = child
    node[parts[-1]] = value



def sweep_points(sweep: dict) -> list[dict]:
    """[{dotted key: value}] for a sweep: the cartesian product over the axes, where each `zip` group
    is one axis whose values are taken together (item i of every key in the group)."""
    if not sweep:
        return [{}]
    groups = [list(g) for g in sweep.get("zip", [])]
    in_group = {k for g in groups for k in g}
    axes: list[list[dict]] = []
    for k, values in sweep.items():
        if k == "zip" or k in in_group:
            continue
        axes.append([{k: v} for v in values])
    for g in groups:
        axes.append([{k: sweep[k][i] for k in g} for i in range(len(sweep[g[0]]))])
    # Keep the axis order of the file (first axis varies slowest).
    order = [k for k in sweep if k != "zip"]
    axes.sort(key=lambda ax: min(order.index(k) for k in ax[0]))
    points = []
    for combo in itertools.product(*axes):
        p = {}
        for part in combo:
            p.update(part)
        points.append(p)
    return points


# At most this many bad points are listed in one error (the count of all of them is given).
MAX_LISTED_POINTS = 12


def expand_sweep(config: RenderConfig, source: str = "config", lines: dict | None = None
                 ) -> list[tuple[dict, RenderConfig]]:
    """[(point, config)] for every point of config.sweep (one point without a sweep). Each point is
    validated on its own (the schema, then build.check: scene, camera, sample table, pipeline and the
    algorithm-table combination), all before any render: one ConfigError lists every bad point."""
    from .build import check

    unread: dict = {}
    if not config.sweep:
        _check_point(check, config, source, lines)
        config = _as_read(config, {}, unread)
        _warn_unread(unread, 1, source, lines)
        return [({}, config)]
    base = config.model_dump(exclude={"sweep"})
    if config._auto_bin_size:  # 'auto' depends on the point's sample_fraction: resolved per point
        base["pipeline"]["bin_size"] = "auto"
    points, bad = [], []
    every = sweep_points(config.sweep)
    for point in every:
        d = copy.deepcopy(base)
        for k, v in point.items():
            set_dotted(d, k, v, f"{source} sweep")
        where = f"{source} (sweep point {point})"
        try:
            point_lines = {**(lines or {}), **(_point_lines(lines, point) or {})}
            point_config = validate_model(d, where, point_lines)
            _check_point(check, point_config, where, point_lines)
        except ConfigError as e:
            bad.append((point, str(e)))
            continue
        points.append((point, _as_read(point_config, point, unread)))
    if bad:
        raise ConfigError(f"{source}: {len(bad)} of {len(every)} sweep points are invalid (nothing was "
                          f"rendered):\n{_grouped(bad)}")
    _warn_unread(unread, len(every), source, lines)
    return points


def _as_read(config: RenderConfig, point: dict, unread: dict) -> RenderConfig:
    """The point with every pipeline parameter that its render does not read back at its default
    (sim.pipeline.unread_parameters: `hiz` under an algorithm without a depth-cull stage, `lines` under a
    point-sample algorithm, ...), so it hashes, renders and is stored as what the render sees; each such
    parameter is noted in ``unread`` {(field, why): [points]} for one warning per field."""
    import warnings

    import sim
    from sim.pipeline import unread_parameters, without_unread

    if config.point.kind != "render" and config.point.kind != "retime":
        return config
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sim.UnreadParameterWarning)
        pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
        fields = unread_parameters(pipeline)
        if not fields:
            return config
        read = without_unread(pipeline)
    for f, why in fields.items():
        unread.setdefault((f, why), []).append(point)
    d = config.model_dump()
    for f in fields:  # a group (hiz, lines) is written whole, as the render resolves it
        head = f.partition(".")[0]
        value = getattr(read, head)
        d["pipeline"][head] = dict(value) if isinstance(value, dict) else value
    return RenderConfig.model_validate(d)


def _warn_unread(unread: dict, n_points: int, source: str, lines: dict | None) -> None:
    import warnings

    import sim

    for (field, why), points in unread.items():
        key = ("pipeline", *field.split("."))
        where = (lines or {}).get(key) or (lines or {}).get(("sweep", "pipeline." + field)) or source
        which = "" if n_points == 1 else f" in {len(points)} of {n_points} sweep points (e.g. {points[0]})"
        whom = "the point is" if n_points == 1 else "those points are"
        warnings.warn(f"{where}: pipeline.{field} is set but not read{which}: {why}; {whom} rendered and "
                      "stored as if it were left at its default", sim.UnreadParameterWarning, stacklevel=3)


def _grouped(bad: list[tuple[dict, str]]) -> str:
    """The bad points' errors, one line per distinct error: an error shared by several points (a
    --set value, a base key) is listed once with their count and the first of them."""
    groups: dict[str, list] = {}
    for point, message in bad:
        groups.setdefault(message.replace(f" (sweep point {point})", ""), []).append((point, message))
    out = []
    for key, members in groups.items():
        if len(members) == 1:
            out.append(members[0][1])
        else:
            out.append(f"{key} ({len(members)} points, e.g. sweep point {members[0][0]})")
    listed = "\n".join(f"  {m}" for m in out[:MAX_LISTED_POINTS])
    more = f"\n  ... and {len(out) - MAX_LISTED_POINTS} more" if len(out) > MAX_LISTED_POINTS else ""
    return listed + more


def _point_lines(lines: dict | None, point: dict) -> dict | None:
    """The file:line of each key of a sweep point: its sweep entry (for the errors of validate)."""
    if not lines:
        return None
    out = {}
    for k in point:
        where = lines.get(("sweep", k))
        if where:
            out[tuple(k.split("."))] = f"{where} (sweep point {point})"
    return out or None


_OWNERS = {"PipelineConfig.": "pipeline.", "Camera.": "camera.", "HardwareConfig.": "hardware."}


def _place(message: str, lines: dict | None, where: str) -> str:
    """The file:line (or --set flag) of the key an error message starts with ('samples.spp: ...',
    'PipelineConfig.tile_size: ...'), else ``where``."""
    import re as _re

    m = _re.match(r"([A-Za-z_][\w.]*):", message)
    if not m or not lines:
        return where
    field = m.group(1)
    for owner, section in _OWNERS.items():
        if field.startswith(owner):
            field = section + field[len(owner):]
    parts = tuple(field.split("."))
    for n in range(len(parts), 0, -1):
        if parts[:n] in lines and (n > 1 or str(lines[parts[:n]]).startswith("--set")):
            place = str(lines[parts[:n]])
            point = where[where.index(" (sweep point"):] if " (sweep point" in where else ""
            return place if point in place else place + point
    return where


def _check_point(check, config: RenderConfig, where: str, lines: dict | None = None) -> None:
    """ConfigError naming the point (its file:line or --set flag where the message's key was set) when
    build() or sim.render would reject it (every point before the first render)."""
    try:
        check(config)
    except ValueError as e:  # ConfigError, sim.ConfigError, models.SceneError and the sample tables' errors
        place = _place(str(e), lines, where)
        raise ConfigError(f"{place}: {e}{_set_by_flags(str(e), lines, place)}") from None


_SECTION_KEY = re.compile(r"\b((?:scene|camera|samples|pipeline|hardware|point)\.[A-Za-z_][\w.]*[A-Za-z0-9_])")


def _set_by_flags(message: str, lines: dict | None, place: str) -> str:
    """' (samples.kind set by --set samples.kind=lines)' for the other keys a combination error names
    that a --set flag set: the error is placed at one key, the flag that chose its partner is named too."""
    if not lines:
        return ""
    named = []
    for key in dict.fromkeys(_SECTION_KEY.findall(message)):
        flag = str(lines.get(tuple(key.split(".")), ""))
        if flag.startswith("--set") and flag not in place:
            named.append(f"{key} set by {flag}")
    return f" ({'; '.join(named)})" if named else ""


RESULT_EXCLUDE = {"name", "description", "extends", "sweep", "outputs", "executor", "point"}


def point_columns(config: RenderConfig) -> dict:
    """The point section as result columns (none for a plain render, so render rows stay as they are)."""
    if config.point.kind == "render":
        return {}
    d = config.point.model_dump()
    if config.point.kind != "occlusion_query":
        d.pop("query")
        d.pop("mode")
    return flatten({"point": d})


# Plot fields that are presentation only (never a result column).
_PRESENTATION = ("title", "xlabel", "ylabel", "format", "paper", "kind", "logx", "logy", "stacked", "pareto",
                 "fit", "echo", "optional")
# A placeholder of the page prose (experiments/report/prose.py): {...} but not {{table:NAME}}.
_PLACEHOLDER = re.compile(r"(?<!\{)\{(?!\{)([^{}]+)\}(?!\})")


def reads_timing(outputs) -> bool:
    """Whether a page's outputs read the timing and memory model: one of its figures
    (sim.timing.model_figures: timing.*, dram.*, the tile caches', depth compression, the energy that
    reads them) named by a derived expression, a plot (its columns, `where:` and `labels:` keys; titles
    and labels aside) or a placeholder of the page prose (`text:`, `summary:`). A named table that reads
    timing figures says so where it is registered (experiments/report/tables.py), and
    tests/test_prose.py checks that every page placing one reads timing by one of these."""
    named = list(outputs.derived.values())
    for spec in outputs.plots:
        d = spec.model_dump(exclude=set(_PRESENTATION))
        named += [*d.pop("where", {}), *d.pop("labels", {})]
        named += [json.dumps(v) for v in d.values() if v is not None]
    for text in (outputs.text, getattr(outputs, "summary", None)):
        named += _PLACEHOLDER.findall(text or "")
    figures = _model_figures()
    return any(m in figures for n in named for m in _DOTTED_NAME.findall(str(n)))


_DOTTED_NAME = re.compile(r"(?<![A-Za-z0-9_.])([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)")


@functools.lru_cache(maxsize=1)
def _model_figures() -> frozenset[str]:
    import sim

    return sim.timing.model_figures()


def timing_needed(config: RenderConfig) -> bool:
    """Whether a render point runs the timing model: always, except for the points of a report page
    (``outputs.page``) whose outputs do not read it (reads_timing): with records per shading visit the
    model can cost as much as the render, and those pages do not read it. Such points hash apart
    (config_hash), so a row without timing figures never serves a config that reads them."""
    if config.point.kind == "render" and not config.hardware_config().timing.enabled:
        return False  # switched off (hardware.timing.enabled false, the command line's --no-timing)
    if config.point.kind != "render" or not config.outputs.page:
        return True
    return reads_timing(config.outputs)


def config_hash(config: RenderConfig) -> str:
    """Stable hash of everything that determines a point's result row: scene, camera, samples,
    pipeline (not the thread count: results are identical for any), hardware, the metrics spec, and
    the contents of every file its scenes read (inputs.py)."""
    d = config.model_dump(exclude=RESULT_EXCLUDE)
    d["pipeline"].pop("threads", None)
    d["metrics"] = config.outputs.metrics.model_dump() if config.outputs.metrics else None
    if config.point.kind != "render":
        d["point"] = config.point.model_dump()
    if not timing_needed(config):
        d["timing"] = False
    d["inputs"] = config_inputs(config)  # the contents of every file the point's scenes read
    blob = json.dumps(d, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]


def flatten(d: dict, prefix: str = "") -> dict:
    """{'camera': {'coc_px': 10}} -> {'camera.coc_px': 10}; lists become JSON text (one cell)."""
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v:
            out.update(flatten(v, key + "."))
        elif isinstance(v, dict):
            continue
        elif isinstance(v, (list, tuple)):
            out[key] = json.dumps(v)
        else:
            out[key] = v
    return out

"""The parameter declaration seen from Python.

Every render parameter is declared once, in ``sim/engine/core/params.def`` (layer, user name,
type, default, unit, domain and a one-line doc); the engine exports the rows as
``_core.param_specs()``. This module parses them into :class:`ParamSpec`, validates values against
their domains, copies a layer's values into ``_core.RenderParams`` and generates the RenderParams
section of ``sim/_core.pyi`` (``python -m sim.gen_stub`` rewrites it; tests/test_params.py fails
when it is stale).
"""
from __future__ import annotations

import copy
import dataclasses
import functools
import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import _core
from .errors import ConfigError, check_float, check_int

_SENTINELS = {"auto": "auto", "null": None}
PY_TYPES = {"int": int, "float": float, "bool": bool, "str": str, "range": list, "precision": str | dict}
# The largest fixed-point formats (core/params.h: kFixedMaxIntBits, kFixedMaxFracBits, kFixedMaxRegisterBits).
FIXED_MAX_INT_BITS, FIXED_MAX_FRAC_BITS, FIXED_MAX_REGISTER_BITS = 62, 24, 100


@dataclass(frozen=True)
class ParamSpec:
    """One row of params.def. ``name`` is the user's (``hiz.tile_size``), ``engine`` the
    RenderParams field (``hiz_tile_size``, None for Python-only rows and groups)."""

    kind: str  # "engine", "python" or "group"
    stage: str  # the pipeline stage of its params.def section ("intervals", "shading", ...)
    layer: str  # "camera", "pipeline", "hardware" or "frame"
    name: str
    doc: str
    engine: str | None = None
    group: str | None = None
    type: str = "dict"
    default: Any = None  # the engine's default (a group: see user_default)
    unit: str = ""
    domain: str = ""
    choices: tuple | None = None  # names, for a registry domain "@registry"
    registry: str | None = None
    values: tuple | None = None  # "{a, b, c}"
    bounds: tuple | None = None  # "[lo, hi]": (lo, hi, lo_open, hi_open), None for an infinite end
    sentinel: tuple = ()  # (value,) when the user may also write "auto" / null
    keys: str = ""  # groups: "all" or "any"
    members: tuple = field(default=(), repr=False)  # groups: their rows

    @property
    def key(self) -> str:
        """The name inside its group (``tile_size`` of ``hiz.tile_size``)."""
        return self.name.rsplit(".", 1)[-1]

    @property
    def user_default(self):
        if self.kind == "group":
            return {m.key: m.user_default for m in self.members} if self.keys == "all" else {}
        return self.sentinel[0] if self.sentinel else self.default

    @property
    def py_type(self):
        """The annotation of the user's value."""
        if self.kind == "group":
            return dict
        t = PY_TYPES[self.type]
        if self.sentinel:
            return t | (type(None) if self.sentinel[0] is None else str)
        return t

    def domain_text(self) -> str:
        """The accepted values in words, as error messages quote them."""
        if self.choices is not None:
            return _alternatives([repr(c) for c in self.choices])
        if self.values is not None:
            return _alternatives([_text(v) for v in self.values])
        return self.domain

    # ---- validation ----
    def check(self, owner: str, value, label: str | None = None):
        """``value`` if it is in the domain (groups: the completed dict), else ConfigError naming
        ``owner.label`` (label defaults to the user name)."""
        label = label or self.name
        if self.kind == "group":
            return self._check_group(owner, value, label)
        if self.sentinel and _same(value, self.sentinel[0]):
            return value
        if self.type == "bool":
            if not isinstance(value, bool):
                raise ConfigError(f"{owner}.{label}: expected a bool, got {value!r}")
            return value
        if self.type == "range":
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                raise ConfigError(f"{owner}.{label}: expected [lo, hi], got {value!r}")
            lo = check_float(owner, f"{label}[0]", value[0])
            hi = check_float(owner, f"{label}[1]", value[1])
            if not lo <= hi:
                raise ConfigError(f"{owner}.{label}: expected lo <= hi, got {list(value)!r}")
            return [lo, hi]
        if self.type == "precision":
            return self._check_precision(owner, value, label)
        if self.registry is not None:
            if not isinstance(value, str) or value not in self.choices:
                if self.registry == "algorithms":  # a registry of units, open to additions
                    raise ConfigError(f"{owner}.{label}: unknown {value!r} (known: {', '.join(self.choices)})")
                raise ConfigError(f"{owner}.{label}: expected {self.domain_text()}, got {value!r}")
            return value
        if self.values is not None:
            if isinstance(value, bool) or not _member(value, self.values):
                items = [_text(v) for v in self.values] + [repr(v) for v in self.sentinel]
                raise ConfigError(f"{owner}.{label}: expected {_alternatives(items)}, got {value!r}")
            return value
        if self.bounds is not None:
            lo, hi, lo_open, hi_open = self.bounds
            if self.type == "int":  # integer ranges are closed
                check_int(owner, label, value, -(1 << 63) if lo is None else lo, (1 << 63) - 1 if hi is None else hi)
            else:
                check_float(owner, label, value, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)
            return value
        if self.type == "int":
            if isinstance(value, bool) or not isinstance(value, numbers.Integral):
                raise ConfigError(f"{owner}.{label}: expected an integer, got {value!r}")
        elif self.type == "float":
            check_float(owner, label, value)
        return value

    def _check_precision(self, owner, value, label):
        """A stage's arithmetic: 'float64', 'float32' or {fixed: {int_bits, frac_bits}}, of the kinds in
        the domain ("{float64, float32, fixed}")."""
        kinds = [k for k in self.values if k != "fixed"]
        shape = _alternatives([repr(k) for k in kinds] + (["{fixed: {int_bits: int, frac_bits: int}}"]
                                                          if "fixed" in self.values else []))
        if isinstance(value, str) and value in kinds:
            return value
        if isinstance(value, dict) and "fixed" in self.values and set(value) == {"fixed"}:
            bits = value["fixed"]
            if isinstance(bits, dict) and set(bits) == {"int_bits", "frac_bits"}:
                ib = check_int(owner, f"{label}.fixed.int_bits", bits["int_bits"], 1, FIXED_MAX_INT_BITS)
                fb = check_int(owner, f"{label}.fixed.frac_bits", bits["frac_bits"], 0, FIXED_MAX_FRAC_BITS)
                if 1 + ib + 2 * fb > FIXED_MAX_REGISTER_BITS:
                    raise ConfigError(f"{owner}.{label}.fixed: expected 1 + int_bits + 2 frac_bits <= "
                                      f"{FIXED_MAX_REGISTER_BITS} register bits, got {1 + ib + 2 * fb} ({bits!r})")
                return {"fixed": {"int_bits": ib, "frac_bits": fb}}
        raise ConfigError(f"{owner}.{label}: expected {shape}, got {value!r}")

    def _check_group(self, owner, value, label):
        keys = [m.key for m in self.members]
        shape = "{" + ", ".join(f"{m.key}: {_shape(m)}" for m in self.members) + "}"
        if not isinstance(value, dict) or set(value) - set(keys):
            raise ConfigError(f"{owner}.{label}: expected {shape}, got {value!r}")
        given = {**self.user_default, **value} if self.keys == "all" else value
        out = {}
        for k, v in given.items():
            out[k] = self.member(k).check(owner, v, f"{label}.{k}")
        return out

    def member(self, key: str) -> "ParamSpec":
        return next(m for m in self.members if m.key == key)

    # ---- the engine ----
    def engine_values(self, value) -> dict:
        """{RenderParams field: value} for a user value (the sentinel keeps the engine default)."""
        if self.kind == "group":
            out = {}
            for k, v in value.items():
                out.update(self.member(k).engine_values(v))
            return out
        if self.engine is None or (self.sentinel and _same(value, self.sentinel[0])):
            return {}
        return {self.engine: list(value) if self.type == "range" else value}


def _same(a, b) -> bool:
    return a is b if b is None else (isinstance(a, type(b)) and a == b)


def _member(value, values) -> bool:
    try:
        return value in values
    except TypeError:
        return False


def _text(value) -> str:
    return repr(value) if isinstance(value, str) else str(value)


def _alternatives(items: list[str]) -> str:
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} or {items[-1]}"


def _shape(spec: ParamSpec) -> str:
    return {"range": "[lo, hi]", "int": spec.unit or "int",
            "precision": "float64 | float32 | {fixed: {int_bits, frac_bits}}"}.get(spec.type, spec.type)


def _number(text: str):
    text = text.strip()
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _parse_domain(row: dict) -> dict:
    """domain text -> ParamSpec fields (grammar in params.def)."""
    out: dict = {}
    text = row["domain"]
    if " | " in text:
        text, sentinel = text.split(" | ")
        out["sentinel"] = (_SENTINELS[sentinel.strip()],)
    text = text.strip()
    if text.startswith("@"):
        out["registry"] = text[1:]
        out["choices"] = tuple(row["choices"])
    elif text.startswith("{"):
        out["values"] = tuple(_number(v) for v in text[1:-1].split(","))
    elif text[:1] in ("[", "("):
        lo, hi = (_number(v) for v in text[1:-1].split(","))
        lo = None if isinstance(lo, float) and math.isinf(lo) else lo
        hi = None if isinstance(hi, float) and math.isinf(hi) else hi
        if row["type"] == "float":
            lo, hi = (None if v is None else float(v) for v in (lo, hi))
        out["bounds"] = (lo, hi, text[0] == "(", text[-1] == ")")
    return out


@functools.cache
def specs() -> tuple[ParamSpec, ...]:
    """Every row of params.def in order; a group's rows are also its ``members``."""
    rows, groups = [], {}
    for row in _core.param_specs():
        if row["kind"] == "group":
            groups[row["name"]] = dict(kind="group", stage=row["stage"], layer=row["layer"], name=row["name"], doc=row["doc"],
                                       keys=row["keys"], members=[])
            rows.append(row["name"])
            continue
        fields = {k: row[k] for k in ("kind", "stage", "layer", "name", "doc", "engine", "group", "type", "default",
                                      "unit", "domain")}
        spec = ParamSpec(**fields, **_parse_domain(row))
        if spec.group in groups:
            groups[spec.group]["members"].append(spec)
        rows.append(spec)
    return tuple(ParamSpec(**{**groups[r], "members": tuple(groups[r]["members"])}) if isinstance(r, str) else r
                 for r in rows)


@functools.cache
def layer(name: str) -> tuple[ParamSpec, ...]:
    """The top-level parameters one layer sets (a group, not its rows), in declaration order."""
    grouped = {s.name for s in specs() if s.kind == "group"}
    return tuple(s for s in specs() if s.layer == name and s.group not in grouped)


def set_layer(params, name: str, values, only=None) -> None:
    """Copy a layer's values into RenderParams. ``values`` is an object with the layer's user names
    as attributes (sim.PipelineConfig) or a nested dict (HardwareConfig.describe()); ``only``
    restricts the copy to these user names. Keys absent from a dict keep the engine defaults."""
    for spec in layer(name):
        if only is not None and spec.name not in only:
            continue
        value = values
        for part in spec.name.split("."):
            if isinstance(value, dict):
                if part not in value:
                    break
                value = value[part]
            else:
                value = getattr(value, part)
        else:
            for engine, v in spec.engine_values(value).items():
                setattr(params, engine, v)


def declare(cls, specs, name=lambda spec: spec.name):
    """``cls`` as a frozen dataclass with one field per spec, in declaration order: the field is
    ``name(spec)``, its default the user default, its metadata the doc, the unit and the spec itself
    (for ``field_docs`` and ``check_declared``)."""
    annotations = {}
    for spec in specs:
        metadata = {"doc": spec.doc, **({"unit": spec.unit} if spec.unit else {}), "spec": spec}
        default = spec.user_default
        if isinstance(default, (dict, list)):
            f = dataclasses.field(default_factory=lambda d=default: copy.deepcopy(d), metadata=metadata)
        else:
            f = dataclasses.field(default=default, metadata=metadata)
        annotations[name(spec)] = spec.py_type
        setattr(cls, name(spec), f)
    cls.__annotations__ = {**annotations, **cls.__dict__.get("__annotations__", {})}
    from .errors import suggest_keywords

    return suggest_keywords(dataclasses.dataclass(frozen=True)(cls))


def check_declared(obj, owner: str) -> None:
    """Check every declared field of ``obj`` (a ``declare``d dataclass) against its domain, naming
    ``owner.field``; a group's value is replaced by its completed, normalised dict."""
    for f in dataclasses.fields(obj):
        spec = f.metadata["spec"]
        value = spec.check(owner, getattr(obj, f.name), f.name)
        if spec.kind == "group":
            object.__setattr__(obj, f.name, value)


def choices(registry: str) -> list[str]:
    """Names in a registry (``shading_modes``, ``texture_filters``, ``lens_shapes``, ...), in engine
    order."""
    return [name for name, _desc in _core.choices()[registry]]


def stage(layer_name: str, stage_name: str) -> tuple[str, ...]:
    """The user names of a layer's parameters declared in one pipeline stage of params.def."""
    return tuple(s.name for s in layer(layer_name) if s.stage == stage_name)


# ---- the generated RenderParams stub in sim/_core.pyi ----
STUB_BEGIN = "    # ---- generated from params.def by `python -m sim.gen_stub`: do not edit ----"
STUB_END = "    # ---- end of the generated fields ----"
_LAYER_SETTERS = {"camera": "set from sim.Camera", "pipeline": "from sim.PipelineConfig",
                  "hardware": "from sim.HardwareConfig", "frame": "set by sim.render for this render"}
_STUB_TYPES = {"int": "int", "float": "float", "bool": "bool", "str": "str", "range": "list[float]",
               "precision": "str | dict"}


def stub_fields() -> str:
    """The RenderParams attributes of sim/_core.pyi, one per engine row, grouped by layer."""
    lines = [STUB_BEGIN]
    last = None
    order = ("camera", "pipeline", "hardware", "frame")
    for s in sorted((s for s in specs() if s.kind == "engine"), key=lambda s: order.index(s.layer)):
        if s.layer != last:
            lines.append(f"    # {s.layer}: {_LAYER_SETTERS[s.layer]}")
            last = s.layer
        from .references import cite

        what = cite(s.doc)
        if s.choices is not None and s.registry != "algorithms":  # algorithms: an open registry
            what += f" ({s.registry}: {', '.join(s.choices)})"
        if s.unit:
            what += f" [{s.unit}]"
        lines.append(f"    {s.engine}: {_STUB_TYPES[s.type]}  # {what}; default {s.default!r}")
    lines.append(STUB_END)
    return "\n".join(lines) + "\n"


STUB_PATH = Path(__file__).resolve().parent / "_core.pyi"


def stub_text(current: str) -> str:
    """``current`` (the text of sim/_core.pyi) with its generated section replaced."""
    head, rest = current.split(STUB_BEGIN + "\n", 1)
    _old, tail = rest.split(STUB_END + "\n", 1)
    return head + stub_fields() + tail

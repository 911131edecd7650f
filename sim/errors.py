"""Exceptions raised for bad input. Every message names the field and the offending value.

One hierarchy (re-exported as ``rast5d.Error`` and friends; docs/errors.md lists each refused input
with its type)::

    Error                      every refused input (catch this to catch them all)
    ├── ConfigError            a camera, sample-table, pipeline, hardware or render parameter
    │   ├── MemoryLimitError   a render would allocate more than PipelineConfig.memory_limit_bytes
    │   ├── KeywordError       an unknown keyword to PipelineConfig, Camera, ... (also a TypeError)
    │   ├── ConfigFileError    a config file, --set override or sweep point (experiments.config.ConfigError)
    │   │   └── PlotError      a report spec that does not fit the result table
    │   └── OutputDirError     a results or pages directory that cannot be written
    └── SceneError             a scene: a file (models.SceneError is this class) or arrays
        └── SceneInputError    scene arrays handed to sim.render are malformed

Every class also derives from ValueError, so ``except ValueError`` keeps working.
"""


class Error(ValueError):
    """Base of every exception rast5d raises for bad input (``rast5d.Error``)."""


class ConfigError(Error):
    """A camera, pipeline or render parameter is invalid (or a resource limit would be exceeded)."""


class MemoryLimitError(ConfigError):
    """A render would allocate more than PipelineConfig.memory_limit_bytes; the message gives the
    estimate, its largest parts and what to lower."""


class KeywordError(ConfigError, TypeError):
    """An unknown keyword argument to a parameter class (sim.PipelineConfig, sim.Camera, ...); the
    message suggests the nearest known name. Also a TypeError, as Python's own would be."""


class SceneError(Error):
    """A scene is invalid: a scene file, a named scene's parameters, or its arrays."""


class SceneInputError(SceneError):
    """Scene arrays handed to sim.render are malformed (shape, dtype, non-finite values)."""


class EmptyFrameWarning(UserWarning):
    """A render tested no sample at all; the message gives the setup cull counts (near plane, off
    screen, degenerate, back-facing), usually a camera inside or facing away from the scene."""


class UnreadParameterWarning(UserWarning):
    """A parameter was set that the render does not read (``pipeline.hiz.enabled`` under an algorithm
    without a depth-cull stage, ``pipeline.lines`` under a point-sample algorithm, ...): it has no
    effect. The message names the parameter, its value and why; sweeps hash such a point as if the
    parameter were left at its default (sim.pipeline.unread_parameters)."""


class FewStrataWarning(UserWarning):
    """A sampled render (PipelineConfig.sample_fraction < 1) drew its bins from so few strata that
    its 95% intervals can cover far below 95%; the message says what to raise."""


def check_int(owner: str, field: str, value, lo: int, hi: int) -> int:
    """Return value as int if it is an integer in [lo, hi], else raise ConfigError."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{owner}.{field}: expected an integer in {lo}..{hi}, got {value!r}")
    v = int(value)
    if not lo <= v <= hi:
        raise ConfigError(f"{owner}.{field}: expected an integer in {lo}..{hi}, got {v}")
    return v


def check_float(owner: str, field: str, value, *, lo=None, hi=None, lo_open=False, hi_open=False) -> float:
    """Return value as a finite float within the given bounds, else raise ConfigError."""
    import math

    if isinstance(value, bool):
        raise ConfigError(f"{owner}.{field}: expected a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{owner}.{field}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ConfigError(f"{owner}.{field}: expected a finite number, got {value!r}")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise ConfigError(f"{owner}.{field}: expected {'>' if lo_open else '>='} {lo}, got {v:g}")
    if hi is not None and (v > hi or (hi_open and v == hi)):
        raise ConfigError(f"{owner}.{field}: expected {'<' if hi_open else '<='} {hi}, got {v:g}")
    return v


def field_docs(cls) -> dict[str, dict]:
    """{field: {"default", "unit", "doc"[, "fields"]}} of a dataclass whose fields carry their
    documentation in metadata (the single declaration of every parameter); nested dataclass
    sections carry their own "fields" and a dict default."""
    import dataclasses

    out = {}
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        from .references import cite

        entry = {"default": default, "unit": f.metadata.get("unit", ""), "doc": cite(f.metadata["doc"])}
        if dataclasses.is_dataclass(default):
            entry["fields"] = field_docs(type(default))
            entry["default"] = dataclasses.asdict(default)
            for name, sub in entry["fields"].items():  # this field's defaults, not the section class's
                if "fields" not in sub:
                    sub["default"] = entry["default"][name]
        out[f.name] = entry
    return out


def suggest_keywords(cls):
    """Class decorator: an unknown keyword argument to ``cls(...)`` raises KeywordError naming it and
    the nearest known keyword ('did you mean'), instead of a bare TypeError."""
    import difflib
    import functools
    import inspect

    init = cls.__init__
    params = inspect.signature(init).parameters
    names = [n for n, p in params.items() if n != "self" and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    if any(p.kind == p.VAR_KEYWORD for p in params.values()):
        return cls

    @functools.wraps(init)
    def __init__(self, *args, **kwargs):
        unknown = [k for k in kwargs if k not in names]
        if unknown:
            k = unknown[0]
            close = difflib.get_close_matches(k, names, n=2, cutoff=0.6)
            hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
            raise KeywordError(f"{cls.__name__}: unknown keyword {k!r}{hint} (known: {', '.join(names)})")
        init(self, *args, **kwargs)

    cls.__init__ = __init__
    return cls

"""Exceptions raised for bad input. Every message names the field and the offending value."""


class ConfigError(ValueError):
    """A camera, pipeline or render parameter is invalid (or a resource limit would be exceeded)."""


class SceneInputError(ValueError):
    """Scene arrays handed to sim.render are malformed (shape, dtype, non-finite values)."""


class EmptyFrameWarning(UserWarning):
    """A render tested no sample at all; the message gives the setup cull counts (near plane, off
    screen, degenerate, back-facing), usually a camera inside or facing away from the scene."""


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
        entry = {"default": default, "unit": f.metadata.get("unit", ""), "doc": f.metadata["doc"]}
        if dataclasses.is_dataclass(default):
            entry["fields"] = field_docs(type(default))
            entry["default"] = dataclasses.asdict(default)
            for name, sub in entry["fields"].items():  # this field's defaults, not the section class's
                if "fields" not in sub:
                    sub["default"] = entry["default"][name]
        out[f.name] = entry
    return out

"""Loading a config file: YAML with line numbers, `extends:` (deep merge, recursive, cycles are
errors), `--set` overrides, then validation and a check of every sweep point."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from models.loader import UniqueKeyLoader

from .schema import ConfigError, RenderConfig, deep_merge, validate
from .sweep import expand_sweep, set_dotted


def _node_lines(node, source: str, path: tuple = (), out: dict | None = None) -> dict:
    """{key path: 'file:line'} for every mapping key and sequence item of a composed YAML tree."""
    out = {} if out is None else out
    if isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            key = path + (str(k.value),)
            out[key] = f"{source}:{k.start_mark.line + 1}"
            _node_lines(v, source, key, out)
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            key = path + (i,)
            out[key] = f"{source}:{v.start_mark.line + 1}"
            _node_lines(v, source, key, out)
    return out


def _read_yaml(path: Path) -> tuple[dict, dict]:
    if not path.exists():
        raise ConfigError(f"config: file not found: {path}")
    text = path.read_text()
    try:
        data = yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 (a SafeLoader subclass)
        lines = _node_lines(yaml.compose(text, Loader=yaml.SafeLoader), str(path))
    except yaml.constructor.ConstructorError as e:
        if not (e.problem or "").startswith("duplicate key"):
            raise ConfigError(f"{path}: not valid YAML: {e}") from None
        raise ConfigError(f"{path}: {e.problem} at line {e.problem_mark.line + 1}") from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level, got {type(data).__name__}")
    return data, lines


def _load_with_extends(path: Path, chain: tuple[Path, ...] = ()) -> tuple[dict, dict]:
    path = path.resolve()
    if path in chain:
        cycle = " -> ".join(str(p) for p in chain + (path,))
        raise ConfigError(f"{chain[-1]}: extends: cycle {cycle}")
    data, lines = _read_yaml(path)
    bases = data.pop("extends", None)
    if bases is None:
        return data, lines
    if isinstance(bases, str):
        bases = [bases]
    if not isinstance(bases, list) or not all(isinstance(b, str) for b in bases):
        raise ConfigError(f"{lines.get(('extends',), path)}: extends: expected a file name or a list of them, "
                          f"got {bases!r}")
    merged, merged_lines = {}, {}
    for b in bases:
        base_path = path.parent / b
        if not base_path.exists():
            raise ConfigError(f"{lines.get(('extends',), path)}: extends: base config {b!r} not found "
                              f"(looked for {base_path})")
        bdata, blines = _load_with_extends(base_path, chain + (path,))
        bdata.pop("name", None)  # the name identifies a file's result table: never inherited
        merged = deep_merge(merged, bdata)
        merged_lines.update(blines)
    merged = deep_merge(merged, data)
    merged_lines.update(lines)
    return merged, merged_lines


def parse_override(text: str) -> tuple[str, Any]:
    """'camera.coc_px=10' -> ('camera.coc_px', 10); the value is parsed as YAML."""
    if "=" not in text:
        raise ConfigError(f"--set: expected key=value, got {text!r}")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key:
        raise ConfigError(f"--set: empty key in {text!r}")
    try:
        value = yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError as e:
        raise ConfigError(f"--set {key}: cannot parse value {raw!r}: {e}") from None
    return key, value



def load_dict(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> tuple[dict, dict]:
    """(merged data, {key path: 'file:line'}) after extends and --set overrides, not validated."""
    path = Path(path)
    data, lines = _load_with_extends(path)
    data.setdefault("name", path.stem)
    for text in overrides:
        key, value = parse_override(text)
        set_dotted(data, key, value, f"{path} --set")
        lines[tuple(key.split("."))] = f"--set {text}"
    return data, lines


def load_config(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> RenderConfig:
    """Load a YAML config (following extends), apply --set overrides, validate. Raises ConfigError."""
    data, lines = load_dict(path, overrides)
    config = validate(data, str(path), lines)
    expand_sweep(config, str(path), lines)  # every point is checked up front, not mid-sweep
    return config

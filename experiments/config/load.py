"""Loading a config file: YAML with line numbers, `extends:` (deep merge, recursive, cycles are
errors), `--set` overrides, then validation and a check of every sweep point."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from models.loader import UniqueKeyLoader, python_parser_error

from .columns import validate
from .schema import ConfigError, RenderConfig, deep_merge
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
        loader = UniqueKeyLoader(text)  # a SafeLoader subclass: parsed once, then built from its nodes
        try:
            node = loader.get_single_node()
            data = loader.construct_document(node) if node is not None else None
        finally:
            loader.dispose()
        lines = _node_lines(node, str(path)) if node is not None else {}
    except yaml.constructor.ConstructorError as e:
        if not (e.problem or "").startswith("duplicate key"):
            raise ConfigError(f"{path}: not valid YAML: {e}") from None
        raise ConfigError(f"{path}: {e.problem} at line {e.problem_mark.line + 1}") from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML: {python_parser_error(text) or e}") from None
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
        if isinstance(bdata.get("outputs"), dict):  # a section's summary speaks of its own rows only
            bdata["outputs"].pop("summary", None)
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
    """(merged data, {key path: 'file:line'}) after extends and --set overrides, not validated.
    Relative scene paths are resolved (resolve_scene_paths)."""
    path = Path(path)
    data, lines = _load_with_extends(path)
    data.setdefault("name", path.stem)
    for text in overrides:
        key, value = parse_override(text)
        if key.startswith("sweep.") and len(key) > 6:  # --set sweep.camera.coc_px=[0, 10]: one swept key
            sweep = data.setdefault("sweep", {})
            if not isinstance(sweep, dict):
                raise ConfigError(f"--set {text}: sweep is not a mapping in {path}")
            sweep[key[6:]] = value
            lines[("sweep", key[6:])] = f"--set {text}"
            continue
        set_dotted(data, key, value, f"--set {text}")
        lines[tuple(key.split("."))] = f"--set {text}"
    resolve_scene_paths(data, lines, path)
    return data, lines


def _defining_file(lines: dict, key: tuple, default: Path) -> Path | None:
    """The config file whose line set key (extends: a base file), None for a --set override."""
    where = lines.get(key)
    if where is None:
        return default
    if where.startswith("--set"):
        return None
    return Path(where.rsplit(":", 1)[0])


def _resolve_one(text, where: str, config_file: Path | None):
    """A scene file path relative to the config file that names it, then the working directory (then
    the repository root, where the bundled scenes live), as a path relative to the working directory
    when it is under it (so results keep the same key from any checkout) or absolute."""
    from models.loader import candidate_paths

    if not isinstance(text, str) or not text:
        return text
    bases = (config_file.parent,) if config_file is not None else ()
    tried = candidate_paths(text, *bases)
    for option in tried:
        if option.exists():
            resolved = option.resolve()
            try:
                return str(resolved.relative_to(Path.cwd().resolve()))
            except ValueError:
                return str(resolved)
    raise ConfigError(f"{where}: scene file not found: {text} (tried {', '.join(map(str, tried))})")


def resolve_scene_paths(data: dict, lines: dict, path: Path) -> None:
    """Rewrite every relative scene path (scene.path, point.query.path and their sweep values) to the
    file it names, looked for against the config file that sets it, then the working directory; a
    ConfigError names every place tried."""
    path = path.resolve()
    for section in (("scene",), ("point", "query")):
        node = data
        for part in section:
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, dict) and "path" in node and node.get("name") is None:  # both: the schema says so
            key = section + ("path",)
            node["path"] = _resolve_one(node["path"], lines.get(key, str(path)), _defining_file(lines, key, path))
    sweep = data.get("sweep")
    if not isinstance(sweep, dict):
        return
    for swept, values in sweep.items():
        if not isinstance(values, list):
            continue
        where = lines.get(("sweep", swept), str(path))
        config_file = _defining_file(lines, ("sweep", swept), path)
        if swept in ("scene.path", "point.query.path"):
            sweep[swept] = [_resolve_one(v, where, config_file) for v in values]
        elif swept in ("scene", "point.query"):
            for v in values:
                if isinstance(v, dict) and "path" in v:
                    v["path"] = _resolve_one(v["path"], where, config_file)


def load_config(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> RenderConfig:
    """Load a YAML config (following extends), apply --set overrides, validate. Raises ConfigError."""
    data, lines = load_dict(path, overrides)
    config = validate(data, str(path), lines)
    expand_sweep(config, str(path), lines)  # every point is checked up front, not mid-sweep
    return config

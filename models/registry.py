"""Named scenes: a registry filled by the @register_scene decorator. The scene modules are found by
walking the models package, so adding a module with decorated builders needs no other edit."""
from __future__ import annotations

import functools
import importlib
import inspect
import pkgutil
from typing import Any, Callable

from .scene import Scene, SceneError

__all__ = ["register_scene", "named", "scene_names", "scene_parameters"]

SceneBuilder = Callable[..., Scene]

_REGISTRY: dict[str, SceneBuilder] = {}


def register_scene(name: str) -> Callable[[SceneBuilder], SceneBuilder]:
    """Register a scene builder under name. The builder takes keyword parameters only, each with a
    default, and has a one-line docstring; it returns a Scene with a camera_hint."""

    def decorate(builder: SceneBuilder) -> SceneBuilder:
        if name in _REGISTRY:
            raise ValueError(f"register_scene: {name!r} is already registered by {_REGISTRY[name].__module__}")
        for param in inspect.signature(builder).parameters.values():
            if param.kind is not inspect.Parameter.KEYWORD_ONLY or param.default is inspect.Parameter.empty:
                raise TypeError(
                    f"register_scene({name!r}): parameter {param.name!r} of {builder.__qualname__} "
                    "must be keyword-only with a default"
                )
        if not (builder.__doc__ or "").strip():
            raise TypeError(f"register_scene({name!r}): {builder.__qualname__} needs a one-line docstring")
        _REGISTRY[name] = builder
        return builder

    return decorate


@functools.cache
def _ensure_loaded() -> None:
    """Import every module of the models package (once); importing runs their @register_scene
    decorators. Lazy, so that a scene module may import the package while it is initialised."""
    package = __name__.rpartition(".")[0]
    for module in pkgutil.iter_modules(importlib.import_module(package).__path__):
        if not module.name.startswith("_"):
            importlib.import_module(f"{package}.{module.name}")


def scene_names() -> list[str]:
    """Sorted names of all registered scenes."""
    _ensure_loaded()
    return sorted(_REGISTRY)


def scene_parameters(name: str) -> dict[str, Any]:
    """{parameter: default} of a named scene."""
    builder = _builder(name)
    return {p.name: p.default for p in inspect.signature(builder).parameters.values()}


def scene_description(name: str) -> str:
    """The one-line docstring of a named scene."""
    return inspect.getdoc(_builder(name)).splitlines()[0]


def _builder(name: str) -> SceneBuilder:
    _ensure_loaded()
    if not isinstance(name, str) or name not in _REGISTRY:
        import difflib

        close = difflib.get_close_matches(str(name), list(_REGISTRY), n=2, cutoff=0.6)
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        raise SceneError(f"scene: unknown scene {name!r}{hint}; known scenes: {', '.join(sorted(_REGISTRY))}")
    return _REGISTRY[name]


def named(name: str, **params: Any) -> Scene:
    """Build the registered scene name with the given keyword parameters (others keep defaults)."""
    builder = _builder(name)
    accepted = inspect.signature(builder).parameters
    unknown = sorted(set(params) - set(accepted))
    if unknown:
        raise SceneError(
            f"scene {name!r}: unknown parameter(s) {', '.join(unknown)}; "
            f"accepted: {', '.join(accepted) or '(none)'}"
        )
    try:
        scene = builder(**params)
    except SceneError as exc:
        raise SceneError(f"scene {name!r}: {exc}") from None
    except (TypeError, ValueError) as exc:  # a parameter of the wrong type or out of range
        raise SceneError(f"scene {name!r}: bad parameter value: {exc}") from exc
    if scene.name == "scene":
        scene.name = name
    return scene

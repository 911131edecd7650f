"""Construction of the sim objects of one (non-swept) point: scene, camera, sample table, pipeline."""
from __future__ import annotations

import warnings

import sim

from .inputs import input_digests, tracking_reads
from .schema import ConfigError, RenderConfig, SceneSpec


class WideLensCamera(sim.Camera):
    """A camera whose lens is ``u_scale`` times wider in u than in v: V views on a camera line, each
    with a full-size lens, the samples of view k in the k-th u-interval ([Nilsson 2012] §8, Fig. 16)."""

    def __init__(self, u_scale: float, **kw):
        super().__init__(**kw)
        if not u_scale >= 1.0:
            raise ConfigError(f"camera.u_scale: expected >= 1, got {u_scale!r}")
        self.u_scale = float(u_scale)

    def engine_params(self) -> dict:
        p = super().engine_params()
        p["coc_x_px"] *= self.u_scale
        return p


# The points of a sweep share a few scenes and sample tables. A worker builds each once and keeps the
# last few (least recently used first out): a named scene's build and a table's generation and engine
# index cost more than many small renders. Only what was built from the package alone is kept: a
# scene file, or any file a build opened outside the package, is read again for every point (it may
# change, and the point's inputs record it: experiments/config/inputs.py).
_MEMO_SIZE = 4
_MEMO_TABLE_BYTES = 64 << 20  # a larger table is built for each point: a few of them would fill a worker
_SCENES: dict = {}
_TABLES: dict = {}


def forget() -> None:
    """Drop the kept scenes and sample tables (the next point builds its own)."""
    _SCENES.clear()
    _TABLES.clear()


def _memo_get(memo: dict, key):
    value = memo.pop(key, None)
    if value is not None:
        memo[key] = value  # most recently used last
    return value


def _memo_put(memo: dict, key, value) -> None:
    memo[key] = value
    while len(memo) > _MEMO_SIZE:
        memo.pop(next(iter(memo)))


def _frozen(scene):
    """A scene kept for later points: its arrays read-only, so a consumer that wrote into one would
    raise instead of changing the next point's scene."""
    for name in ("positions", "positions_t1", "colors", "uvs", "texture_ids", "alpha"):
        array = getattr(scene, name)
        if array is not None:
            array.flags.writeable = False
    for texture in scene.textures:
        texture.flags.writeable = False
    return scene


def _handed_out(scene):
    """A point's own copy of a kept scene: its attributes and camera hint are its own, the read-only
    arrays are shared."""
    import copy

    out = copy.copy(scene)
    out.camera_hint = dict(scene.camera_hint)
    out.textures = list(scene.textures)
    return out


def build_scene(spec: SceneSpec):
    """The models.Scene of a scene section: a named scene (models.scene_names()) or a file (a YAML
    scene, Mitsuba XML, glTF or mesh). A relative path was resolved when the config was loaded
    (against the config file, then the working directory: experiments/config/load.py)."""
    import json

    import models

    if spec.name is None:
        return models.load(spec.path)
    key = (spec.name, json.dumps(spec.params, sort_keys=True, default=repr))
    scene = _memo_get(_SCENES, key)
    if scene is not None:
        return _handed_out(scene)
    with tracking_reads() as reads:
        scene = models.named(spec.name, **spec.params)
    if input_digests(reads):
        return scene
    _memo_put(_SCENES, key, _frozen(scene))
    return _handed_out(scene)


def _camera(config: RenderConfig, hint: dict) -> sim.Camera:
    """The camera of a point: sim.Camera.for_scene(hint, **the camera section), as Python users write it."""
    given = {k: v for k, v in config.camera.model_dump().items() if v is not None}
    u_scale = given.pop("u_scale", None)
    if u_scale in (None, 1):
        return sim.Camera.for_scene(dict(hint or {}), **given)
    return WideLensCamera.for_scene(dict(hint or {}), **given, u_scale=u_scale)


def _table_params(config: RenderConfig) -> dict:
    t = config.samples
    params = dict(spp=t.spp, seed=t.seed, period=t.period, lens=t.lens, time=t.time)
    if t.kind == "interleaved":
        if t.n_lens is not None:
            params["n_lens"] = t.n_lens
    elif t.n_lens is not None:
        raise ConfigError(f"samples.n_lens: only for the interleaved kind, got kind={t.kind!r}")
    if t.views is not None:
        if t.kind != "multiview":
            raise ConfigError(f"samples.views: only for the multiview kind, got kind={t.kind!r}")
        params["views"] = t.views
    for key in ("n_lines", "wheel"):
        if t.kind != "lines" and getattr(t, key) is not None:
            raise ConfigError(f"samples.{key}: only for the lines kind, got kind={t.kind!r}")
    return params


def _make_table(kind: str, params: dict, samples) -> "sim.SampleTable":
    """The sample table of a config: a generator's, or line samples (SampleTable.lines)."""
    if kind == "lines":
        extra = {k: v for k, v in (("n_lines", samples.n_lines), ("wheel", samples.wheel)) if v is not None}
        return sim.SampleTable.lines(seed=params["seed"], period=params["period"], **extra)
    return sim.SampleTable.create(kind, **params)


_CHECKED_TABLES: dict = {}


def _table_key(config: RenderConfig, params: dict) -> tuple:
    return config.samples.kind, tuple(sorted(params.items())), config.samples.n_lines, config.samples.wheel


def check(config: RenderConfig) -> None:
    """Everything build() and sim.render would reject, without building the scene: the named scene and
    its parameters, the camera, the sample table (each distinct one built once per process), the
    pipeline, and whether the algorithm can render with that table and lens (sim.render's
    check_combination). Run on every point of a sweep before the first render. Raises ConfigError,
    ValueError (sim's and models' input errors)."""
    from sim.render import check_combination

    import models
    from models.registry import scene_parameters

    spec = config.scene
    if spec.name is not None:
        accepted = scene_parameters(spec.name)  # SceneError for an unknown name
        unknown = sorted(set(spec.params) - set(accepted))
        if unknown:
            raise models.SceneError(f"scene {spec.name!r}: unknown parameter(s) {', '.join(unknown)}; "
                                    f"accepted: {', '.join(accepted) or '(none)'}")
    camera = _camera(config, {})
    params = _table_params(config)
    key = _table_key(config, params)
    if key not in _CHECKED_TABLES:  # the points of a sweep share a few tables: build each once
        try:
            _CHECKED_TABLES[key] = _make_table(config.samples.kind, params, config.samples)
        except ValueError as e:  # "spp: expected ..." -> "samples.spp: expected ..."
            raise ConfigError(f"samples.{e}") from None
    with warnings.catch_warnings():  # a parameter the render does not read: sweep.expand_sweep warns once
        warnings.simplefilter("ignore", sim.UnreadParameterWarning)
        pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
    try:
        check_combination(pipeline, _CHECKED_TABLES[key], camera.lens)
    except sim.ConfigError as e:  # name the config's keys: pipeline.algorithm, samples.kind
        raise ConfigError(f"pipeline.{e} (samples.kind {config.samples.kind!r})") from None


def build(config: RenderConfig):
    """(scene, camera, table, pipeline) for one (non-swept) config."""
    scene = build_scene(config.scene)
    camera = _camera(config, scene.camera_hint)
    params = _table_params(config)
    key = _table_key(config, params)
    table = _memo_get(_TABLES, key)  # immutable: its engine index, built by the first render, is reused
    if table is None:
        try:
            with tracking_reads() as reads:
                table = _make_table(config.samples.kind, params, config.samples)
        except ValueError as e:  # "spp: expected ..." -> "samples.spp: expected ..."
            raise ConfigError(f"samples.{e}") from None
        if not input_digests(reads) and table.period ** 2 * table.spp * 5 * 8 <= _MEMO_TABLE_BYTES:
            _memo_put(_TABLES, key, table)
    pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
    if pipeline.lod["enabled"]:  # blur-based level of detail (models/lod.py)
        from models import lod

        scene, _ = lod.apply(scene, camera, pipeline.lod, textured=pipeline.texture_count > 0)
    return scene, camera, table, pipeline

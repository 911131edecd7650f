"""Construction of the sim objects of one (non-swept) point: scene, camera, sample table, pipeline."""
from __future__ import annotations

import sim

from .schema import ConfigError, RenderConfig, SceneSpec


class WideLensCamera(sim.Camera):
    """A camera whose lens is ``u_scale`` times wider in u than in v: V views on a camera line, each
    with a full-size lens, the samples of view k in the k-th u-interval (002 §8, Fig. 16)."""

    def __init__(self, u_scale: float, **kw):
        super().__init__(**kw)
        if not u_scale >= 1.0:
            raise ConfigError(f"camera.u_scale: expected >= 1, got {u_scale!r}")
        self.u_scale = float(u_scale)

    def engine_params(self) -> dict:
        p = super().engine_params()
        p["coc_x_px"] *= self.u_scale
        return p


def build_scene(spec: SceneSpec):
    """The models.Scene of a scene section: a named scene (models.scene_names()) or a file (a YAML
    scene, Mitsuba XML, glTF or mesh). A relative path was resolved when the config was loaded
    (against the config file, then the working directory: experiments/config/load.py)."""
    import models

    if spec.name is not None:
        return models.named(spec.name, **spec.params)
    return models.load(spec.path)


def _camera(config: RenderConfig, hint: dict) -> sim.Camera:
    cam_args = dict(hint or {})
    given = {k: v for k, v in config.camera.model_dump().items() if v is not None}
    if "coc_px" in given:  # the config's blur replaces any blur in the hint
        cam_args.pop("aperture_radius", None)
    if "aperture_radius" in given:
        cam_args.pop("coc_px", None)
    cam_args.update(given)
    if cam_args.get("shutter") is not None:
        cam_args["shutter"] = tuple(cam_args["shutter"])
    u_scale = cam_args.pop("u_scale", None)
    return sim.Camera(**cam_args) if u_scale in (None, 1) else WideLensCamera(u_scale, **cam_args)


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
    return params


_CHECKED_TABLES: set = set()


def check(config: RenderConfig) -> None:
    """Everything build() would reject, without building the scene: the named scene and its
    parameters, the camera, the sample table (each distinct one built once per process) and the
    pipeline. Run on every point of a sweep before the first render. Raises ConfigError,
    ValueError (sim's and models' input errors)."""
    import models
    from models.registry import scene_parameters

    spec = config.scene
    if spec.name is not None:
        accepted = scene_parameters(spec.name)  # SceneError for an unknown name
        unknown = sorted(set(spec.params) - set(accepted))
        if unknown:
            raise models.SceneError(f"scene {spec.name!r}: unknown parameter(s) {', '.join(unknown)}; "
                                    f"accepted: {', '.join(accepted) or '(none)'}")
    _camera(config, {})
    params = _table_params(config)
    key = (config.samples.kind, tuple(sorted(params.items())))
    if key not in _CHECKED_TABLES:  # the points of a sweep share a few tables: build each once
        try:
            sim.SampleTable.create(config.samples.kind, **params)
        except ValueError as e:  # "spp: expected ..." -> "samples.spp: expected ..."
            raise ConfigError(f"samples.{e}") from None
        _CHECKED_TABLES.add(key)
    sim.PipelineConfig(**config.pipeline.model_dump())


def build(config: RenderConfig):
    """(scene, camera, table, pipeline) for one (non-swept) config."""
    scene = build_scene(config.scene)
    camera = _camera(config, scene.camera_hint)
    try:
        table = sim.SampleTable.create(config.samples.kind, **_table_params(config))
    except ValueError as e:  # "spp: expected ..." -> "samples.spp: expected ..."
        raise ConfigError(f"samples.{e}") from None
    pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
    return scene, camera, table, pipeline

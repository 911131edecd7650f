"""Construction of the sim objects of one (non-swept) point: scene, camera, sample table, pipeline."""
from __future__ import annotations

from pathlib import Path

import sim

from .schema import REPO, ConfigError, RenderConfig, SceneSpec


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
    """The models.Scene of a scene section: a named scene (models.scene_names()) or a file relative
    to the repository."""
    import models

    if spec.name is not None:
        return models.named(spec.name, **spec.params)
    p = Path(spec.path)
    return models.load(str(p if p.is_absolute() else REPO / p))


def build(config: RenderConfig):
    """(scene, camera, table, pipeline) for one (non-swept) config."""
    scene = build_scene(config.scene)
    cam_args = dict(scene.camera_hint or {})
    given = {k: v for k, v in config.camera.model_dump().items() if v is not None}
    if "coc_px" in given:  # the config's blur replaces any blur in the hint
        cam_args.pop("aperture_radius", None)
    if "aperture_radius" in given:
        cam_args.pop("coc_px", None)
    cam_args.update(given)
    if cam_args.get("shutter") is not None:
        cam_args["shutter"] = tuple(cam_args["shutter"])
    u_scale = cam_args.pop("u_scale", None)
    camera = sim.Camera(**cam_args) if u_scale in (None, 1) else WideLensCamera(u_scale, **cam_args)
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
    try:
        table = sim.SampleTable.create(t.kind, **params)
    except ValueError as e:  # "spp: expected ..." -> "samples.spp: expected ..."
        raise ConfigError(f"samples.{e}") from None
    pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
    return scene, camera, table, pipeline

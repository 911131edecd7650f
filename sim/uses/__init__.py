"""Uses of the 5D rasterizer beyond blur ([Nilsson 2012] §4-§7) and stochastic
transparency ([McGuire 2010]): each is a scene (models/uses.py) run through the shared
engine (sim.render, sim.conservative_raster) plus a little numpy around it, returning a UseResult
(image, counters of its passes and its own figures, declared once in FIGURES).

=====================  ==========================================================================
stochastic_transparency  per-sample alpha coverage (engine: backend/alpha.h) vs sorted blending
sample_simploids         the rasterizer as a sampler: points inside moving triangles, voids
soft_shadows             one-pass 5D shadow map over fixed (u, v, t) + motion-blurred camera pass
caustic_volumes          caustic beams as moving triangles, conservative mode with t̂ and ẑ
glossy_reflection        the lens as a glossy lobe: 4D reflection map, then a look-up
=====================  ==========================================================================

USES maps each point-kind name to (function, {option: default}); a use's options are the keyword
arguments after (scene, camera, table, pipeline).
"""
from __future__ import annotations

import inspect

from .common import FIGURES, UseResult, check_options, figure_docs
from .caustics import caustic_volumes, exact_time_intervals
from .glossy import glossy_reflection
from .sampler import sample_simploids
from .shadows import soft_shadows
from .transparency import sorted_blend, stochastic_transparency

USES: dict[str, object] = {
    "transparency": stochastic_transparency,
    "sampler": sample_simploids,
    "caustics": caustic_volumes,
    "glossy": glossy_reflection,
    "soft_shadows": soft_shadows,
}


def use_options(kind: str) -> dict:
    """{option: default} of a use: its keyword-only arguments."""
    fn = USES[kind]
    return {p.name: p.default for p in inspect.signature(fn).parameters.values()
            if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name != "hardware"}


def run_use(kind: str, scene, camera, table, pipeline=None, *, hardware=None, options: dict | None = None) -> UseResult:
    """The use ``kind`` (a key of USES) with ``options`` (unknown keys are ConfigErrors)."""
    opts = check_options(f"point.options ({kind})", dict(options or {}), use_options(kind))
    return USES[kind](scene, camera, table, pipeline, hardware=hardware, **opts)


__all__ = ["FIGURES", "caustic_volumes", "exact_time_intervals", "glossy_reflection", "USES", "UseResult", "figure_docs", "run_use", "sample_simploids", "soft_shadows", "sorted_blend", "stochastic_transparency",
           "use_options"]

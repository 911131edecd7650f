"""rast5d engine: a functional, operation-counting 5D stochastic rasterizer (C++ via pybind11).

Public contract (docs/architecture.md)::

    camera = sim.Camera.for_scene(scene, width=256, height=256, coc_px=10)  # the scene's camera hint
    table  = sim.SampleTable.stratified(spp=16, seed=1)
    result = sim.render(scene, camera, table, sim.PipelineConfig(algorithm="tile", tile_size=2))
    result.image, result.stats, result.flat_stats
"""
from . import _core

from .errors import (ConfigError, EmptyFrameWarning, Error, MemoryLimitError, SceneError, SceneInputError,
                     UnreadParameterWarning)
from .hardware import (ColorBufferConfig, DepthBufferConfig, DramConfig, HardwareConfig, TextureCacheConfig,
                       UnitConfig)
from .errors import suggest_keywords as _suggest_keywords

for _cls in (HardwareConfig, TextureCacheConfig, DepthBufferConfig, ColorBufferConfig, DramConfig,
             UnitConfig):  # unknown keywords: KeywordError, did you mean
    _suggest_keywords(_cls)
from .pipeline import (AlgorithmInfo, PipelineConfig, algorithm_docs, algorithm_info, algorithm_names,
                       interleaved_algorithms, shading_modes, texture_filters, texture_layouts)
from .pipeline import line_algorithms
from .png import linear_to_srgb8, write_png

from .camera import Camera
from .render import Result, memory_estimate, render, trace_pixel
from .sample_table import SampleTable
from .intervals import ConservativeResult, OcclusionResult, conservative_raster, occlusion_query
from .stats import counter_docs
from . import energy, pixel_stats, references, timing
from . import uses

__all__ = [
    "AlgorithmInfo",
    "Camera",
    "ConservativeResult",
    "OcclusionResult",
    "conservative_raster",
    "occlusion_query",
    "ConfigError",
    "EmptyFrameWarning",
    "Error",
    "MemoryLimitError",
    "SceneError",
    "HardwareConfig",
    "PipelineConfig",
    "Result",
    "SampleTable",
    "SceneInputError",
    "TextureCacheConfig",
    "DepthBufferConfig",
    "ColorBufferConfig",
    "DramConfig",
    "UnitConfig",
    "UnreadParameterWarning",
    "algorithm_docs",
    "algorithm_info",
    "algorithm_names",
    "counter_docs",
    "interleaved_algorithms",
    "line_algorithms",
    "linear_to_srgb8",
    "memory_estimate",
    "pixel_stats",
    "render",
    "shading_modes",
    "texture_filters",
    "texture_layouts",
    "timing",
    "trace_pixel",
    "uses",
    "write_png",
]

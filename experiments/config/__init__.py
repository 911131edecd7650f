"""Experiment configuration: the YAML schema (schema.py), loading with `extends:` and `--set`
overrides (load.py), sweep expansion and the identity of a point (sweep.py), the sim objects of one
point (build.py), and the generated reference docs (docs.py, ``python -m experiments.config.docs``).
"""
from .build import build, build_scene
from .columns import validate
from .load import load_config, load_dict, parse_override
from .schema import (REPO, CameraSpec, ConfigError, ExecutorSpec, HardwareSpec, MetricsSpec, OutputsSpec,
                     PipelineSpec, PlotSpec, PointSpec, RenderConfig, SamplesSpec, SceneSpec, deep_merge)
from .sweep import (RESULT_EXCLUDE, config_hash, expand_sweep, flatten, point_columns, set_dotted, sweep_points,
                    timing_needed)

__all__ = ["REPO", "ConfigError", "RenderConfig", "SceneSpec", "CameraSpec", "SamplesSpec", "PipelineSpec",
           "HardwareSpec", "PlotSpec", "MetricsSpec", "OutputsSpec", "ExecutorSpec", "PointSpec", "build",
           "build_scene",
           "load_config", "load_dict", "parse_override", "validate", "deep_merge", "expand_sweep", "sweep_points",
           "set_dotted", "config_hash", "flatten", "point_columns", "RESULT_EXCLUDE", "timing_needed"]

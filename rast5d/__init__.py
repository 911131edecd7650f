"""rast5d: a simulator of a hardware 5D stochastic rasterizer (screen, lens, time).

The package's pieces are ``sim`` (the engine: scenes in, images and operation counts out),
``models`` (scenes and assets) and ``experiments`` (configs, sweeps, the result store, report pages
and the ``rast5d`` command line). This module gathers what every user needs from all three: the
version and the one exception hierarchy (sim/errors.py)::

    Error                      every refused input (catch this to catch them all)
    ├── ConfigError            a camera, sample-table, pipeline, hardware or render parameter
    │   ├── MemoryLimitError   a render would allocate more than PipelineConfig.memory_limit_bytes
    │   ├── ConfigFileError    a config file, --set override or sweep point (experiments.config.ConfigError)
    │   │   └── PlotError      a report spec that does not fit the result table
    │   └── OutputDirError     a results or pages directory that cannot be written
    └── SceneError             a scene: a file or a named scene's parameters (models.SceneError)
        └── SceneInputError    scene arrays handed to sim.render are malformed

Every class also derives from ValueError. Warnings: EmptyFrameWarning, FewStrataWarning (sim),
SceneImportWarning (models), StoreWarning (experiments).
"""
from experiments import __version__
from experiments.config.schema import ConfigError as ConfigFileError
from experiments.paths import OutputDirError
from experiments.report.frames import PlotError
from experiments.run.store import StoreWarning
from models.mitsuba import SceneImportWarning
from sim.errors import (ConfigError, EmptyFrameWarning, Error, FewStrataWarning, MemoryLimitError, SceneError,
                        SceneInputError)

__all__ = ["__version__", "Error", "ConfigError", "MemoryLimitError", "ConfigFileError", "PlotError",
           "OutputDirError", "SceneError", "SceneInputError", "EmptyFrameWarning", "FewStrataWarning",
           "SceneImportWarning", "StoreWarning"]

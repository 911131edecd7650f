"""rast5d engine: a functional, operation-counting 5D stochastic rasterizer (C++ via pybind11)."""
from . import _core

__all__ = ["_core"]

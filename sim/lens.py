"""Lens apertures: area-preserving maps from the unit square onto each lens shape, and membership.

Contract: for every shape Ω ⊆ [-1, 1]² (docs/conventions.md), `map_to_lens`
sends the uniform distribution on [0, 1)² to the uniform distribution on Ω (the map's Jacobian is
constant), and every image point satisfies `inside_lens`. Sample tables store canonical (a, b) in
[0, 1)² and call `map_to_lens` when they are asked for a concrete shape.

Shapes:
- ``square``: Ω = [-1, 1]², (u, v) = (2a - 1, 2b - 1).
- ``disk``: the unit disk, through the Shirley–Chiu concentric map (area preserving; the naive
  polar map r = a, θ = 2πb is *not*, it crowds the centre).
- ``hexagon``: the regular hexagon inscribed in the unit circle, vertices (±1, 0) and
  (±1/2, ±√3/2). It is split into three congruent rhombi that share the centre; the first
  coordinate chooses the rhombus by thirds and the rescaled square is mapped affinely onto it.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ConfigError

from . import params

# The engine's lens_shapes registry (core/params.h ChoiceTraits<LensShape>), in engine order.
LENS_SHAPES = tuple(params.choices("lens_shapes"))

_SQRT3 = math.sqrt(3.0)

# Rhombus k of the hexagon is {s·E[k] + r·E[k+1] : s, r ∈ [0, 1]}, E[k] the hexagon vertex at angle
# 120°·k; consecutive rhombi share an edge, and each has area |E[k] × E[k+1]| = √3/2.
_HEX_EDGES = np.array(
    [[math.cos(2.0 * math.pi * k / 3.0), math.sin(2.0 * math.pi * k / 3.0)] for k in range(4)]
)
_HEX_EDGES[np.abs(_HEX_EDGES) < 1e-15] = 0.0


def check_shape(shape: str) -> str:
    """Return `shape` if it is a known lens shape; otherwise raise ValueError naming it."""
    if not isinstance(shape, str) or shape not in LENS_SHAPES:
        raise ConfigError(f"lens: unknown shape {shape!r} (known: {', '.join(LENS_SHAPES)})")
    return shape


def lens_area(shape: str) -> float:
    """Area of the lens shape Ω in (u, v) units (square 4, disk π, hexagon 3√3/2)."""
    check_shape(shape)
    return {"square": 4.0, "disk": math.pi, "hexagon": 1.5 * _SQRT3}[shape]


def map_to_lens(a, b, shape: str) -> tuple[np.ndarray, np.ndarray]:
    """Map canonical (a, b) ∈ [0, 1)² to (u, v) ∈ Ω, area preserving; float64, vectorised."""
    check_shape(shape)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a, b = np.broadcast_arrays(a, b)
    if shape == "square":
        return 2.0 * a - 1.0, 2.0 * b - 1.0
    if shape == "disk":
        return _concentric_disk(a, b)
    return _hexagon(a, b)


def _concentric_disk(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # Shirley & Chiu 1997, "A low distortion map between disk and square": the square's concentric
    # squares go to concentric circles, and each of the four triangular wedges to a quarter disk.
    sx = 2.0 * a - 1.0
    sy = 2.0 * b - 1.0
    horizontal = np.abs(sx) > np.abs(sy)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(horizontal, sx, sy)
        theta = np.where(
            horizontal,
            (math.pi / 4.0) * (sy / sx),
            (math.pi / 2.0) - (math.pi / 4.0) * (sx / sy),
        )
    centre = (sx == 0.0) & (sy == 0.0)
    theta = np.where(centre, 0.0, theta)
    r = np.where(centre, 0.0, r)
    return r * np.cos(theta), r * np.sin(theta)


def _hexagon(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    scaled = 3.0 * a
    k = np.clip(np.floor(scaled), 0, 2).astype(np.intp)
    s = scaled - k
    e0 = _HEX_EDGES[k]
    e1 = _HEX_EDGES[k + 1]
    u = s * e0[..., 0] + b * e1[..., 0]
    v = s * e0[..., 1] + b * e1[..., 1]
    return u, v


def inside_lens(u, v, shape: str, eps: float = 1e-6) -> np.ndarray:
    """True where (u, v) lies in Ω, with tolerance `eps` (float32 rounding of boundary points)."""
    check_shape(shape)
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    if shape == "square":
        return (np.abs(u) <= 1.0 + eps) & (np.abs(v) <= 1.0 + eps)
    if shape == "disk":
        return u * u + v * v <= (1.0 + eps) ** 2
    return (np.abs(v) <= 0.5 * _SQRT3 + eps) & (_SQRT3 * np.abs(u) + np.abs(v) <= _SQRT3 + 2.0 * eps)

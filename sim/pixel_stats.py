"""Per-pixel statistics and the pixel trace: where the work of a frame goes.

``sim.render(..., pixel_stats=True)`` returns ``Result.pixel_stats``: counter name -> (H, W) uint64
array. Each counter's work is charged to the pixels it was done for (sim/engine/core/pixel_stats.h):
a sample test to its pixel, a tile test to the tile's pixels, a triangle's setup to its pixel
bounds (in each bin, for per-algorithm setup), work with no pixel bounds (triangles culled at the
near plane or off screen) evenly over the frame. A count is spread as evenly as integers allow (the
remainder to the first pixels in raster order), so every map sums exactly to its frame counter.
Tile-level events (``tile.culled_H``, ...) land on one pixel of their tile: sum them over tiles
(``tile_blocks``) to see them per tile.

``sim.trace_pixel(...)`` renders the bin of one pixel on the counting path and returns a
``PixelTrace``: the triangles that reached the pixel, each tile test's verdict, each sample tested
and hit, with the operations charged.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import ConfigError

# The maps of pixel_stats=True.
DEFAULT = (
    "raster.samples_tested", "raster.samples_hit",
    "ops.setup", "ops.tile", "ops.sample_region", "ops.sample_inside", "ops.ps_setup",
    "tile.visited", "tile.accepted", "tile.culled_2d", "tile.culled_h", "tile.culled_lens", "tile.culled_H",
    "interval.culled_t", "interval.culled_clip",
)
# Maps computed from the counter maps (same formulas as sim/stats.py, exact integer sums).
DERIVED = {
    "ops.sample": ("ops.sample_region", "ops.sample_inside"),
    "ops.total": ("ops.setup", "ops.tile", "ops.sample_region", "ops.sample_inside", "ops.ps_setup"),
    "tile.culled": ("tile.culled_2d", "tile.culled_h", "tile.culled_lens", "tile.culled_H"),
}
# Counted after the traversal, not per pixel.
_NOT_PER_PIXEL = ("frame.", "tex.cache.")
# Tile verdicts of a tile test, in the order the tile algorithm tries them (the cull reason).
TILE_VERDICTS = ("tile.culled_2d", "tile.culled_h", "interval.culled_clip", "tile.culled_lens", "tile.culled_H",
                 "interval.culled_t", "tile.accepted")


def channels(request) -> tuple[list[str], list[str]]:
    """(engine counters to map, derived maps to add) for a pixel_stats argument: True (DEFAULT),
    or names of counters and derived maps. Raises ValueError naming an unknown or unmappable name."""
    from .stats import counter_docs
    from . import _core

    if request is True:
        names = list(DEFAULT) + list(DERIVED)
    elif isinstance(request, str):
        names = [request]
    else:
        try:
            names = [str(n) for n in request]
        except TypeError:
            raise ConfigError(f"pixel_stats: expected True or a list of counter names, got {request!r}") from None
    counters = set(_core.counter_docs())
    engine: list[str] = []
    derived: list[str] = []
    for n in names:
        if n in DERIVED:
            derived.append(n)
            engine.extend(c for c in DERIVED[n] if c not in engine)
        elif n in counters:
            if n.startswith(_NOT_PER_PIXEL):
                raise ConfigError(f"pixel_stats: '{n}' is counted after the traversal and has no per-pixel map")
            if n not in engine:
                engine.append(n)
        else:
            known = ", ".join(sorted(c for c in counters if not c.startswith(_NOT_PER_PIXEL)))
            hint = " (a derived figure; maps exist for " + ", ".join(DERIVED) + ")" if n in counter_docs() else ""
            raise ConfigError(f"pixel_stats: unknown counter '{n}'{hint}; known: {known}")
    return engine, derived


def assemble(engine: list[str], derived: list[str], maps: np.ndarray) -> dict[str, np.ndarray]:
    out = {n: maps[i] for i, n in enumerate(engine)}
    for d in derived:
        out[d] = sum((out[c] for c in DERIVED[d]), np.zeros_like(maps[0]))
    return out


def tile_blocks(a: np.ndarray, tile: int) -> np.ndarray:
    """Sum an (H, W) map over tile x tile blocks: (ceil(H/tile), ceil(W/tile))."""
    h, w = a.shape
    ph, pw = -(-h // tile) * tile, -(-w // tile) * tile
    padded = np.zeros((ph, pw), dtype=a.dtype)
    padded[:h, :w] = a
    return padded.reshape(ph // tile, tile, pw // tile, tile).sum(axis=(1, 3))


def cull_reason(stats: dict[str, np.ndarray], tile: int) -> tuple[np.ndarray, list[str]]:
    """Per tile, the test that culled the most (triangle, tile) pairs there ('tile.accepted' where
    every tested triangle was accepted; -1 where no triangle was tested): the tile-level cull reason
    map, as indices into the returned names."""
    names = [n for n in TILE_VERDICTS if n in stats]
    if "tile.accepted" not in names or len(names) < 2:
        raise ConfigError("cull_reason: no tile verdict maps in pixel_stats (use pixel_stats=True)")
    blocks = np.stack([tile_blocks(stats[n], tile) for n in names])
    acc = names.index("tile.accepted")
    culls = blocks.copy()
    culls[acc] = 0
    reason = np.argmax(culls, axis=0).astype(np.int64)
    reason[culls.sum(axis=0) == 0] = acc
    reason[blocks.sum(axis=0) == 0] = -1
    return reason, names


_KINDS = {0: "triangle bounds", 1: "tile", 2: "pixel", 3: "setup"}


@dataclass
class PixelTrace:
    """One pixel's work: ``events`` (triangle, where, rect, {counter: count}) in the order counted,
    ``samples`` (triangle, sample, covered, hit) of every sample tested at the pixel."""

    x: int
    y: int
    spp: int
    algorithm: str
    events: list = field(default_factory=list)
    samples: list = field(default_factory=list)

    def triangles(self) -> list[int]:
        """Triangles whose rasterization reached the pixel (had work charged on it), in order."""
        seen: list[int] = []
        for tri, kind, _, _ in self.events:
            if tri >= 0 and kind != 3 and tri not in seen:
                seen.append(tri)
        return seen

    def tile_verdicts(self) -> list[tuple[int, str, tuple]]:
        """(triangle, verdict counter, tile rect) of each tile test of a tile holding the pixel."""
        out = []
        for tri, kind, rect, d in self.events:
            if kind == 1:
                for v in TILE_VERDICTS:
                    if d.get(v):
                        out.append((tri, v, rect))
        return out

    def tested(self, triangle: int) -> list[int]:
        return [s for t, s, _, _ in self.samples if t == triangle]

    def hit(self, triangle: int) -> list[int]:
        return [s for t, s, _, h in self.samples if t == triangle and h]

    def ops(self, triangle: int | None = None) -> int:
        """Operations (ops.total) charged to work that touched the pixel (whole tiles, whole bounds)."""
        parts = DERIVED["ops.total"]
        return sum(d.get(c, 0) for tri, _, _, d in self.events if triangle is None or tri == triangle for c in parts)

    def __str__(self) -> str:
        lines = [f"pixel ({self.x}, {self.y}), {self.spp} spp, algorithm {self.algorithm}"]
        tris = self.triangles()
        lines.append(f"triangles that reached it: {len(tris)}")
        by_tri: dict[int, list] = {}
        for ev in self.events:
            by_tri.setdefault(ev[0], []).append(ev)
        for tri in sorted(by_tri, key=lambda t: (t < 0, t)):
            head = f"triangle {tri}" if tri >= 0 else "outside any triangle"
            lines.append(f"- {head}:")
            for _, kind, rect, d in by_tri[tri]:
                x0, y0, x1, y1 = rect
                what = ", ".join(f"{k} {v:,}" for k, v in sorted(d.items()))
                where = _KINDS.get(kind, str(kind))
                verdict = ""
                if kind == 1:
                    v = [n for n in TILE_VERDICTS if d.get(n)]
                    verdict = f" verdict {v[0].split('.', 1)[1] if v else '-'};"
                lines.append(f"    {where} [{x0},{x1})x[{y0},{y1}):{verdict} {what}")
            if tri >= 0:
                t, h = self.tested(tri), self.hit(tri)
                if t:
                    lines.append(f"    samples tested ({len(t)}): {_ranges(t)}")
                    lines.append(f"    samples hit ({len(h)}): {_ranges(h) if h else '-'}")
        lines.append(f"operations charged (ops.total over the work that touched the pixel): {self.ops():,}")
        return "\n".join(lines)


def _ranges(xs: list[int]) -> str:
    xs = sorted(xs)
    out, i = [], 0
    while i < len(xs):
        j = i
        while j + 1 < len(xs) and xs[j + 1] == xs[j] + 1:
            j += 1
        out.append(str(xs[i]) if i == j else f"{xs[i]}-{xs[j]}")
        i = j + 1
    return ", ".join(out)

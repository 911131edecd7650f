"""Continuous collision detection with a conservative 3D rasterizer ([Nilsson 2012] §3,
Fig. 4-6).

Two moving objects are rasterized conservatively (sim.conservative_raster: 1 x 1 tiles, no sample
test, motion blur only) in three views, along z, x and y. Per pixel, each object's fragments are
reduced in C++ to a tz-box (the union of their [t_lo, t_hi] x [z_lo, z_hi]). Two objects can only
collide at time t at point X if, in every view that sees X, both objects have a fragment in X's
pixel whose t̂ and ẑ contain (t, depth of X): so if some view has no pixel where the two tz-boxes
overlap, the pair is not in the potentially colliding set (PCS).

Departure from the paper: the three views use perspective cameras (far away, narrow field of
view) instead of orthographic projections; the argument above holds for any central projection
whose frustum contains both objects over the whole shutter, which `views()` ensures for the
example's extent. Run `python -m experiments.examples.ccd` for the example (writes reports/ccd/).
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import sim

REPO = Path(__file__).resolve().parents[2]
from experiments.paths import bundled_configs, reports_dir, results_dir  # noqa: E402,F401


@dataclass
class Tris:
    positions: np.ndarray
    positions_t1: np.ndarray
    colors: np.ndarray | None = None


def cube(center, size) -> np.ndarray:
    """(12, 3, 3) triangles of an axis-aligned cube."""
    c = np.asarray(center, dtype=np.float64)
    h = 0.5 * size
    corners = np.array([[x, y, z] for x in (-h, h) for y in (-h, h) for z in (-h, h)]) + c
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, cc, d in faces:
        tris += [[corners[a], corners[b], corners[cc]], [corners[a], corners[cc], corners[d]]]
    return np.array(tris)


def moving_cube(start, end, size) -> Tris:
    p0 = cube(start, size)
    return Tris(p0, p0 + (np.asarray(end, dtype=np.float64) - np.asarray(start, dtype=np.float64)))


def views(resolution: int = 64, distance: float = 12.0, fov_y_deg: float = 20.0) -> dict[str, sim.Camera]:
    """Three cameras looking at the origin along -z (xy), -y (xz) and -x (yz); the frustum at the
    origin spans +-distance * tan(fov / 2) = +-2.1 units."""
    kw = dict(width=resolution, height=resolution, fov_y_deg=fov_y_deg, focus_distance=distance, coc_px=0.0,
              near=1.0, target=(0.0, 0.0, 0.0))
    return {
        "xy": sim.Camera(eye=(0.0, 0.0, distance), up=(0.0, 1.0, 0.0), **kw),
        "xz": sim.Camera(eye=(0.0, distance, 0.0), up=(0.0, 0.0, -1.0), **kw),
        "yz": sim.Camera(eye=(distance, 0.0, 0.0), up=(0.0, 1.0, 0.0), **kw),
    }


def boxes_overlap(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel: (t-overlap, z-overlap) of two (H, W, 4) tz-box buffers (empty pixels: False)."""
    t = (a[..., 0] <= b[..., 2]) & (b[..., 0] <= a[..., 2])
    z = (a[..., 1] <= b[..., 3]) & (b[..., 1] <= a[..., 3])
    return t, z


@dataclass
class ViewResult:
    t_overlap: np.ndarray  # (H, W) bool
    z_overlap: np.ndarray
    stats_a: dict
    stats_b: dict

    @property
    def tz_pixels(self) -> int:
        return int((self.t_overlap & self.z_overlap).sum())

    @property
    def z_pixels(self) -> int:
        return int(self.z_overlap.sum())


def overlap(a: Tris, b: Tris, cameras: dict[str, sim.Camera] | None = None,
            pipeline: sim.PipelineConfig | None = None) -> dict[str, ViewResult]:
    cameras = cameras or views()
    pipeline = pipeline or sim.PipelineConfig(time_splits=4)
    out = {}
    for name, cam in cameras.items():
        ra = sim.conservative_raster(a, cam, pipeline, reduce="tz_box")
        rb = sim.conservative_raster(b, cam, pipeline, reduce="tz_box")
        t, z = boxes_overlap(ra.tz_box, rb.tz_box)
        out[name] = ViewResult(t, z, ra.flat_stats, rb.flat_stats)
    return out


def may_collide(a: Tris, b: Tris, **kw) -> bool:
    """False when some view has no pixel where the tz-boxes overlap (the pair is not in the PCS);
    True means "potentially colliding" (conservative)."""
    return all(v.tz_pixels > 0 for v in overlap(a, b, **kw).values())


def may_collide_depth_only(a: Tris, b: Tris, **kw) -> bool:
    """Govindaraju et al.'s test as [Nilsson 2012] describes it: overlap in depth only (time ignored)."""
    return all(v.z_pixels > 0 for v in overlap(a, b, **kw).values())


def example(same_time: bool) -> tuple[Tris, Tris]:
    """Cube A crosses the origin along x at t = 0.5; cube B crosses it along y at t = 0.5
    (same_time) or at t = 0.9 (they pass through the same place at different times)."""
    a = moving_cube((-1.0, 0.0, 0.0), (1.0, 0.0, 0.0), 0.2)
    if same_time:
        b = moving_cube((0.0, -1.0, 0.0), (0.0, 1.0, 0.0), 0.2)
    else:
        b = moving_cube((0.0, -1.8, 0.0), (0.0, 0.2, 0.0), 0.2)
    return a, b


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(reports_dir() / "ccd"))
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    lines = ["# Continuous collision detection ([Nilsson 2012] §3, Fig. 4-6)", "",
             "Command: `python -m experiments.examples.ccd`. Per view: pixels whose tz-boxes overlap in depth only, "
             "and in time and depth. Images: blue = overlap in depth, red = overlap in time (purple: both).", "",
             "| case | view | depth-overlap px | tz-overlap px |", "|---|---|---|---|"]
    for same in (False, True):
        a, b = example(same)
        res = overlap(a, b)
        case = "same time" if same else "different times"
        for name, v in res.items():
            lines.append(f"| {case} | {name} | {v.z_pixels} | {v.tz_pixels} |")
            img = np.zeros(v.t_overlap.shape + (3,), np.float32)
            img[..., 2] = v.z_overlap
            img[..., 0] = v.t_overlap & v.z_overlap
            sim.write_png(out / f"{'same' if same else 'different'}_{name}.png", img)
        verdict = all(v.tz_pixels > 0 for v in res.values())
        depth_only = all(v.z_pixels > 0 for v in res.values())
        lines.append(f"| {case} | **verdict** | PCS by depth only: {depth_only} | PCS by time and depth: {verdict} |")
        print(f"{case}: potentially colliding (time+depth) = {verdict}; (depth only) = {depth_only}")
    (out / "README.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'README.md'} and {2 * len(res)} images")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Conservativeness at scale: 10^5 adversarial triangles at 1024 x 1024 px, rendered by every
culling algorithm with every sample-table kind it accepts, against brute force on the same table.

Brute force tests every sample of every triangle's (near-clipped) bounding box, so it is the
reference for which samples a triangle covers. An algorithm that culls a tile, a lens cell or a
time interval a covered sample lies in would leave that sample empty or showing a farther
triangle: the test counts the samples whose exported depth (``export_samples``) is nearer under
brute force than under the algorithm ("missed") and the reverse ("extra"), and requires both to be 0
(and the images to be identical).

The triangles (``adversarial_scene``): small ones spread over the frame, ones crossing the focus
plane, with a vertex exactly on it, with vertices behind the camera or between it and the near
plane, moving through the near plane, far off screen (10^2 to 10^6 px out), slivers, and ones so
close to the lens that their blur covers much of the frame. Slow: run with `-m slow`; the counts
are printed (``-s``). RAST5D_ADVERSARIAL_TABLES and RAST5D_ADVERSARIAL_ALGORITHMS (comma-separated
names) restrict a run to some table kinds or algorithms, so the full product (about 15 algorithms x 7
table kinds, one to a few CPU-minutes per render) can be split over processes or machines."""
from __future__ import annotations

import os
import time

import numpy as np
import pytest

import sim
from experiments.reference.raycaster import screen_to_world

pytestmark = pytest.mark.slow

N = int(os.environ.get("RAST5D_ADVERSARIAL_N", 100_000))
SIZE = int(os.environ.get("RAST5D_ADVERSARIAL_SIZE", 1024))
SPP = 4


def camera():
    return sim.Camera(width=SIZE, height=SIZE, fov_y_deg=50.0, focus_distance=5.0, coc_px=12.0, near=0.1)


def adversarial_scene(n: int = N, seed: int = 17):
    """(positions, positions_t1, {class: count}) of n adversarial world triangles for camera()."""
    cam = camera()
    rng = np.random.default_rng(seed)
    F, W = cam.focus_distance, cam.width
    # Triangles that cover much of the frame (clipped at the near plane, behind the camera, huge
    # blur, long ones through the frame from far off screen) cost brute force up to the whole frame
    # each: they are a few hundred (at 10^5 triangles, brute force tests about 2e9 samples per table
    # with these shares, two thirds of them for the far-off-screen and near-plane classes); the rest
    # are cheap.
    shares = {"small": 0.6, "crosses_focus": 0.15, "vertex_on_focus": 0.05, "sliver": 0.08, "moving": 0.08,
              "far_off_screen": 0.003, "behind_camera": 0.0005, "behind_near": 0.0005, "through_near": 0.0005,
              "huge_blur": 0.001}
    counts = {k: int(round(v * n)) for k, v in shares.items()}
    counts["small"] += n - sum(counts.values())
    p0s, p1s = [], []

    def at(px, py, w):
        return screen_to_world(cam, px, py, w)

    def tri_px(m, size_lo, size_hi, spread=1.0):
        c = rng.uniform(-0.05 * W, 1.05 * W, (m, 1, 2))
        size = np.exp(rng.uniform(np.log(size_lo), np.log(size_hi), (m, 1, 1)))
        return c + rng.normal(0, 1, (m, 3, 2)) * size * spread

    for kind, m in counts.items():
        if m == 0:
            continue
        if kind == "small":
            pix = tri_px(m, 0.5, 12)
            w = np.repeat(np.exp(rng.uniform(np.log(0.4 * F), np.log(8 * F), (m, 1))), 3, axis=1)
            w = w * rng.uniform(0.97, 1.03, (m, 3))
        elif kind == "crosses_focus":
            pix = tri_px(m, 1, 25)
            w = F * np.stack([rng.uniform(0.4, 0.98, m), rng.uniform(1.02, 3, m), rng.uniform(0.4, 3, m)], 1)
            w = np.take_along_axis(w, rng.permuted(np.tile([0, 1, 2], (m, 1)), axis=1), axis=1)
        elif kind == "vertex_on_focus":
            pix = tri_px(m, 1, 25)
            w = F * rng.uniform(0.5, 2.5, (m, 3))
            w[np.arange(m), rng.integers(0, 3, m)] = F
            if m > 1:
                w[: m // 2] = F  # the whole triangle in the focus plane
        elif kind == "sliver":
            c = rng.uniform(0, W, (m, 1, 2))
            d = rng.normal(0, 1, (m, 1, 2))
            d /= np.linalg.norm(d, axis=2, keepdims=True)
            length = np.exp(rng.uniform(np.log(20), np.log(400), (m, 1, 1)))
            normal = d[..., ::-1] * [1, -1]
            width = np.exp(rng.uniform(np.log(1e-4), np.log(0.5), (m, 1, 1)))
            pix = np.concatenate([c - d * length / 2, c + d * length / 2, c + normal * width], axis=1)
            w = np.repeat(F * rng.uniform(0.5, 3, (m, 1)), 3, axis=1) * rng.uniform(0.95, 1.05, (m, 3))
        elif kind == "moving":
            pix = tri_px(m, 1, 10)
            w = np.repeat(F * rng.uniform(0.4, 4, (m, 1)), 3, axis=1)
        elif kind == "far_off_screen":
            far = np.exp(rng.uniform(np.log(1e2), np.log(1e6), (m, 3, 1)))
            direction = rng.normal(0, 1, (m, 3, 2))
            direction /= np.linalg.norm(direction, axis=2, keepdims=True)
            pix = W / 2 + direction * far
            if m > 40:  # a few keep one vertex on screen: long triangles through the frame
                pix[: m // 40, 0] = rng.uniform(0, W, (m // 40, 2))
            w = F * rng.uniform(0.5, 3, (m, 3))
        elif kind == "huge_blur":  # close to the lens: CoC of hundreds of pixels
            pix = tri_px(m, 2, 30)
            w = np.repeat(rng.uniform(0.15, 0.4, (m, 1)), 3, axis=1)
        else:  # behind_camera, behind_near, through_near
            pix = tri_px(m, 2, 40)
            w = F * rng.uniform(0.5, 2, (m, 3))
            j = rng.integers(0, 3, m)
            if kind == "behind_camera":
                w[np.arange(m), j] = -rng.uniform(0.1, 5, m)
            elif kind == "behind_near":
                w[np.arange(m), j] = cam.near * rng.uniform(-0.5, 0.99, m)
        p0 = at(pix[..., 0], pix[..., 1], w)
        p1 = p0.copy()
        if kind == "moving":
            p1 = p0 + rng.normal(0, 0.05, (m, 1, 3)) * np.exp(rng.uniform(0, 3, (m, 1, 1)))
        elif kind == "through_near":  # moves from in front to behind the near plane
            view_back = cam.view_matrix()[2, :3]
            p1 = p0 + view_back * (w.mean(axis=1, keepdims=True)[..., None] * rng.uniform(1.0, 1.5, (m, 1, 1)))
        p0s.append(p0)
        p1s.append(p1)
    return np.concatenate(p0s), np.concatenate(p1s), counts


class _Scene:
    def __init__(self, p0, p1):
        self.positions, self.positions_t1 = p0, p1
        rng = np.random.default_rng(5)
        self.colors = rng.uniform(0.1, 1, (len(p0), 3, 3))


def _chosen(env: str, names):
    """names, restricted to the comma-separated list in the environment variable env if set."""
    wanted = [n for n in os.environ.get(env, "").split(",") if n]
    unknown = sorted(set(wanted) - set(names))
    if unknown:
        raise ValueError(f"{env}: unknown {unknown}; choose from {sorted(names)}")
    return [n for n in names if not wanted or n in wanted]


def _tables():
    out = {}
    for kind in _chosen("RAST5D_ADVERSARIAL_TABLES", sim.SampleTable.generators()):
        params = dict(spp=SPP, seed=3, period=32)
        if kind == "multiview":
            params["views"] = 2
        out[kind] = sim.SampleTable.create(kind, **params)
    return out


def _render(scene, table, algorithm):
    cfg = sim.PipelineConfig(algorithm=algorithm, count_optimal=False, memory_limit_bytes=16 * 2**30)
    return sim.render(scene, camera(), table, cfg, export_samples=True, timing=False)


class _Report(list):
    """Lines printed as they come (a long run shows its progress with -s)."""

    def __init__(self, lines):
        super().__init__(lines)
        print(*lines, sep="\n", flush=True)

    def append(self, line):
        super().append(line)
        print(line, flush=True)


def test_no_algorithm_misses_a_sample_brute_force_hits():
    p0, p1, classes = adversarial_scene()
    scene = _Scene(p0, p1)
    interleaved = set(sim.interleaved_algorithms())
    report = _Report([f"{len(p0)} triangles at {SIZE}x{SIZE}, {SPP} spp: {classes}"])
    total_missed = total_extra = 0
    for kind, table in _tables().items():
        has_lens_index = bool(getattr(table, "n_lens", 0))
        t0 = time.perf_counter()
        ref = _render(scene, table, "bruteforce")
        report.append(f"{kind}: bruteforce {time.perf_counter() - t0:.1f} s, "
                      f"{int(np.isfinite(ref.sample_depth).sum()):,} samples hit, "
                      f"setup: {({k: v for k, v in ref.flat_stats.items() if k.startswith('setup.') and v})}")
        for algorithm in _chosen("RAST5D_ADVERSARIAL_ALGORITHMS", sim.algorithm_names("points")):
            if algorithm == "bruteforce" or (algorithm in interleaved and not has_lens_index):
                continue
            t0 = time.perf_counter()
            r = _render(scene, table, algorithm)
            missed = int((ref.sample_depth < r.sample_depth).sum())
            extra = int((r.sample_depth < ref.sample_depth).sum())
            same_image = bool(np.array_equal(r.image, ref.image))
            report.append(f"  {algorithm}: missed {missed}, extra {extra}, same image {same_image}, "
                          f"tested {r.flat_stats['raster.samples_tested']:,} vs {ref.flat_stats['raster.samples_tested']:,}"
                          f" ({time.perf_counter() - t0:.1f} s)")
            total_missed += missed
            total_extra += extra
            assert missed == 0 and extra == 0 and same_image, "\n".join(report)
    assert total_missed == 0 and total_extra == 0

"""`make bench`: the whole-render sample-test rate of brute force on medium triangles, against the
sample-test kernels alone.

Workload: 2,000 triangles of about 0.25 scene units (random orientation, seeded) in a 4 x 4 x 2 box
centred 5 units in front of the camera, focused at 5, CoC 12 px, 256x256, 16 spp (SampleTable.
stratified), `bruteforce`, one thread, timing model off. Rate: samples tested / process CPU time of
`sim.render` (the minimum of the repeats), and the same over the engine's wall time (Python's share
left out); the kernels alone: sim._core.simd_batch_bench (1024-sample batches).

Where the render's CPU time goes: the sample-test kernels (samples tested of each class / the
kernels-alone rate of that class), the per-render fixed cost (the CPU time of the same render with one
triangle of the workload: image and bin buffers, clearing and resolve, the engine call and the Python
around it, of which the Python side is that render's CPU time outside the engine call), and the rest
(triangle set-up, binning, gathering the samples into batches, the backend's depth test and colour)
as the remainder.

Writes reports/bench/bench_rate.md. `python -m experiments.bench.bench_rate --help`."""
from __future__ import annotations

import contextlib
import importlib
import os
import time
from pathlib import Path

import numpy as np

from experiments.bench import machine, bench_parser, write_page
from experiments.paths import reports_dir

N_TRIANGLES = 2000
EDGE = 0.25
COC_PX = 12.0
SIZE = 256
SPP = 16


def workload(n: int = N_TRIANGLES, edge: float = EDGE, seed: int = 1):
    """The scene: n triangles of edge about ``edge``, random centres in [-2, 2]^2 x [-6, -4], random
    orientation, random vertex colours."""
    from models.scene import Scene

    rng = np.random.default_rng(seed)
    centres = np.column_stack([rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-6, -4, n)])
    # an equilateral triangle of side `edge` in a random plane
    a = rng.normal(size=(n, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(a, rng.normal(size=(n, 3)))
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    r = edge / np.sqrt(3.0)
    ang = np.array([0.0, 2 * np.pi / 3, 4 * np.pi / 3])
    pos = centres[:, None, :] + r * (np.cos(ang)[None, :, None] * a[:, None, :] + np.sin(ang)[None, :, None] * b[:, None, :])
    colors = rng.uniform(0.2, 1.0, size=(n, 3, 3))
    return Scene.from_arrays(pos, colors=colors)


@contextlib.contextmanager
def _engine_cpu():
    """Within the block, [process CPU seconds spent inside the engine call] of every sim.render (the
    engine's worker threads included)."""
    module = importlib.import_module("sim.render")
    core = module._core
    spent = [0.0]

    class Timed:
        def __getattr__(self, name):
            return getattr(core, name)

        def render(self, *args, **kwargs):
            c0 = time.process_time()
            try:
                return core.render(*args, **kwargs)
            finally:
                spent[0] += time.process_time() - c0

    module._core = Timed()
    try:
        yield spent
    finally:
        module._core = core


def measure(repeats: int = 5, threads: int = 1) -> dict:
    import sim

    scene = workload()
    cam = sim.Camera(width=SIZE, height=SIZE, fov_y_deg=45.0, focus_distance=5.0, coc_px=COC_PX)
    table = sim.SampleTable.stratified(spp=SPP, seed=1)
    cfg = sim.PipelineConfig(algorithm="bruteforce", threads=threads)
    sim.render(scene, cam, table, cfg, timing=False)
    cpu = wall = engine = float("inf")
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        r = sim.render(scene, cam, table, cfg, timing=False)
        cpu, wall = min(cpu, time.process_time() - c0), min(wall, time.perf_counter() - t0)
        engine = min(engine, r.flat_stats["time.wall_s"])
    tested = r.flat_stats["raster.samples_tested"]
    one = workload(n=1)
    sim.render(one, cam, table, cfg, timing=False)
    fixed = fixed_python = float("inf")
    with _engine_cpu() as engine_cpu:
        for _ in range(repeats):
            c0, e0 = time.process_time(), engine_cpu[0]
            sim.render(one, cam, table, cfg, timing=False)
            c1 = time.process_time() - c0
            fixed, fixed_python = min(fixed, c1), min(fixed_python, c1 - (engine_cpu[0] - e0))
    kernels = {c: sim._core.simd_batch_bench(k, 1024, 2000)[:2] for c, k in (("4D", 2), ("5D", 3))}
    classes = {k: r.flat_stats[f"raster.samples_tested_{k}"] for k in ("2d", "3d", "4d", "5d")}
    # the 4D and 5D kernels' own rates; 2D and 3D samples are charged at the 4D kernel's (an upper bound)
    kernel_s = sum(n / kernels["5D" if k == "5d" else "4D"][1] for k, n in classes.items())
    return dict(tested=tested, cpu=cpu, wall=wall, engine=engine, rate_cpu=tested / cpu / 1e6,
                rate_engine=tested / engine / 1e6, hit=r.flat_stats["raster.samples_hit"], kernels=kernels,
                classes=classes, kernel_s=kernel_s, fixed=fixed, fixed_python=fixed_python,
                rest=max(0.0, cpu - kernel_s - fixed))


def run(out=None, repeats: int = 5) -> dict:
    out = reports_dir() / "bench" if out is None else Path(out)
    load0 = os.getloadavg()[0]
    m = measure(repeats)
    load1 = os.getloadavg()[0]
    lines = ["# bench_rate: the whole render's sample-test rate", "",
             f"`python -m experiments.bench.bench_rate` (part of `make bench`), {machine()}, "
             f"load average {load0:.1f} at the start and {load1:.1f} at the end. Rates are from "
             f"the minima of {repeats} renders; compare rates measured in one run.", "",
             " ".join(__doc__.split("\n\n")[1].split()), "",
             "| samples tested | 4D share | CPU [s] | engine wall [s] | M tests/s (CPU) | M tests/s (engine) |",
             "|---|---|---|---|---|---|",
             f"| {m['tested']:,.0f} | {m['classes']['4d'] / m['tested']:.2f} | {m['cpu']:.3f} | {m['engine']:.3f} | "
             f"{m['rate_cpu']:.0f} | {m['rate_engine']:.0f} |", "",
             "The kernels alone (sim._core.simd_batch_bench: edge functions and flags of 1024-sample batches):", "",
             "| class | M tests/s |", "|---|---|"]
    for c, (_, rate) in m["kernels"].items():  # (scalar, explicit SIMD): the engine's fast path is the latter
        lines.append(f"| {c} | {rate / 1e6:.0f} |")
    parts = [("sample-test kernels (samples tested / the kernels-alone rate)", m["kernel_s"]),
             ("per-render fixed cost (the same render with one triangle)", m["fixed"]),
             ("of which outside the engine call (Python)", m["fixed_python"]),
             ("the rest: triangle set-up, binning, batching, depth test and colour", m["rest"])]
    lines += ["", " ".join(__doc__.split("\n\n")[2].split()) + " The first, second and fourth rows add up to the "
              "render's CPU time; the second includes the third.", "",
              "| part | CPU [ms] | share of the render |", "|---|---|---|"]
    for what, t in parts:
        lines.append(f"| {what} | {t * 1e3:.1f} | {t / m['cpu']:.2f} |")
    page = write_page(out, "bench_rate.md", lines)
    return {"page": page, **m}


def main(argv=None) -> int:
    ap = bench_parser(__doc__)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args(argv)
    run(a.out, a.repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""`make bench`: what a render and a run cost outside the engine.

1. Fixed cost of a render: `sim.render`'s wall time minus the engine call's (flat stat time.wall_s:
   setup, traversal, resolve), at 160x120, 256 spp, spot (a small built-in scene), `tile`, one thread,
   timing off and on. Once on a fresh table (the table's lens mapping and engine index are built in
   the render) and as the median of repeated renders on the same table (a sweep that reuses one
   table: they are cached on it, per lens shape).
2. Start-up of a cached run: the wall time of `rast5d run` (a new Python process) of a small sweep
   (two points, both already in the store), the minimum of the repeats, beside the same run computing
   its points into an empty store, and the heavy libraries the cached run imported (none expected:
   tests/test_startup.py keeps it that way).

Writes reports/bench/bench_overhead.md. `python -m experiments.bench.bench_overhead --help`."""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from experiments.bench import machine, bench_parser, write_page
from experiments.paths import reports_dir

SIZE = (160, 120)
SPP = 256
SCENE = "spot"
SWEEP = """\
name: lean
scene: {name: spot_wall}
camera: {width: 16, height: 16}
samples: {kind: stratified, spp: 1, seed: 1}
sweep:
  camera.coc_px: [0, 6]
"""
# Libraries a run served wholly from the store has no use for: mesh import (trimesh and the scipy it
# pulls in), tables (pandas), plots, the cluster, images, the local pool, and pyarrow's dataset layer
# (a point file is one Parquet file). tests/test_startup.py holds a cached run to this list.
HEAVY = ("trimesh", "scipy", "pandas", "matplotlib", "dask", "distributed", "PIL.Image", "skimage",
         "flip_evaluator", "tqdm", "concurrent.futures.process", "pyarrow.dataset")
PROBE = """
import json, sys
from experiments.cli import main
rc = main(["run", sys.argv[1], "--quiet"])
print(json.dumps({"rc": rc, "loaded": sorted(m for m in json.loads(sys.argv[2]) if m in sys.modules)}))
"""


def fixed_cost(repeats: int = 15) -> list[dict]:
    import models
    import sim

    scene = models.named(SCENE)
    cam = sim.Camera.for_scene(scene, width=SIZE[0], height=SIZE[1], coc_px=10.0)
    cfg = sim.PipelineConfig(algorithm="tile", threads=1)
    rows = []
    for timing in (False, True):
        table = sim.SampleTable.stratified(spp=SPP, seed=7 + timing)  # a table no render has seen
        t0 = time.perf_counter()
        r = sim.render(scene, cam, table, cfg, timing=timing)
        fresh_total = time.perf_counter() - t0
        fresh = fresh_total - r.flat_stats["time.wall_s"]
        outside, totals = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            r = sim.render(scene, cam, table, cfg, timing=timing)
            total = time.perf_counter() - t0
            totals.append(total)
            outside.append(total - r.flat_stats["time.wall_s"])
        rows.append(dict(timing="on" if timing else "off", fresh_total=fresh_total, fresh=fresh,
                         total=statistics.median(totals), outside=statistics.median(outside),
                         outside_min=min(outside)))
        print(f"timing {rows[-1]['timing']}: fresh table {fresh * 1e3:.1f} ms outside the engine, reused "
              f"{rows[-1]['outside'] * 1e3:.1f} ms (median of {repeats})", flush=True)
    return rows


def probe_run(path, env) -> dict:
    """`rast5d run` of the sweep file `path` in a new process with environment `env`: its exit code and
    which of HEAVY it imported ({"rc": ..., "loaded": [...]})."""
    out = subprocess.run([sys.executable, "-c", PROBE, str(path), json.dumps(HEAVY)], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def startup(repeats: int = 5) -> dict:
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "lean.yaml"
        path.write_text(SWEEP)
        env = {**os.environ, "RAST5D_RESULTS": str(Path(d) / "results")}

        def once():
            t0, c0 = time.perf_counter(), _child_cpu()
            loaded = probe_run(path, env)
            return time.perf_counter() - t0, _child_cpu() - c0, loaded

        first, first_cpu, _ = once()
        runs = [once() for _ in range(repeats)]
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        bare = time.perf_counter() - t0
    cached = min(t for t, _, _ in runs)
    cached_cpu = min(c for _, c, _ in runs)
    loaded = sorted({m for _, _, j in runs for m in j["loaded"]})
    print(f"cached run {cached:.3f} s wall, {cached_cpu:.3f} s CPU (first {first:.3f} s, bare interpreter "
          f"{bare:.3f} s), heavy imports: {loaded}")
    return dict(first=first, first_cpu=first_cpu, cached=cached, cached_cpu=cached_cpu, bare=bare, loaded=loaded,
                repeats=repeats)


def _child_cpu() -> float:
    import resource

    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def run(out=None, repeats: int = 15) -> dict:
    out = reports_dir() / "bench" if out is None else Path(out)
    load = os.getloadavg()[0]
    fc = fixed_cost(repeats)
    st = startup()
    lines = ["# bench_overhead: what a render and a run cost outside the engine", "",
             f"`python -m experiments.bench.bench_overhead` (part of `make bench`), {machine()}, "
             f"load average {load:.1f} at the start.", "",
             "Fixed cost: `sim.render`'s wall time minus the engine call's (flat stat time.wall_s: setup, traversal, "
             "resolve), once on a fresh table (its lens mapping and engine index are built in the render) and as the "
             "median of repeated renders on the same table (a sweep that reuses one table: they are cached on it, "
             "per lens shape).", "",
             f"## Fixed cost of a render ({SIZE[0]}x{SIZE[1]}, {SPP} spp, {SCENE}, `tile`, one thread)", "",
             "| timing | fresh table: render [ms] | fresh table: outside the engine [ms] | reused table: render [ms] "
             "| reused table: outside the engine [ms] (median) | (minimum) |",
             "|---|---|---|---|---|---|"]
    for r in fc:
        lines.append(f"| {r['timing']} | {r['fresh_total'] * 1e3:.1f} | {r['fresh'] * 1e3:.1f} | {r['total'] * 1e3:.1f} | "
                     f"{r['outside'] * 1e3:.1f} | {r['outside_min'] * 1e3:.1f} |")
    lines += ["", "## Start-up of a cached run", "",
              f"`rast5d run` of a two-point sweep of spot_wall (16x16, 1 spp) in a new process, minimum of "
              f"{st['repeats']} runs with both points in the store, beside the first run (empty store) and a bare "
              "interpreter's start.", "",
              "CPU is the child process's user and system time, which other processes' load disturbs less than wall "
              "time.", "",
              "| cached run: wall [s] | cached run: CPU [s] | first run: wall [s] | first run: CPU [s] | "
              "bare interpreter: wall [s] | heavy libraries the cached run imported |",
              "|---|---|---|---|---|---|",
              f"| {st['cached']:.3f} | {st['cached_cpu']:.3f} | {st['first']:.3f} | {st['first_cpu']:.3f} | "
              f"{st['bare']:.3f} | {', '.join(st['loaded']) or 'none'} |"]
    page = write_page(out, "bench_overhead.md", lines)
    return {"page": page, "fixed": fc, "startup": st}


def main(argv=None) -> int:
    ap = bench_parser(__doc__)
    ap.add_argument("--repeats", type=int, default=15)
    a = ap.parse_args(argv)
    run(a.out, a.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""`make bench`: simulator speed against the work it simulates, and the explicit-SIMD sample tests.

1. Wall time per algorithm, scene and thread count, timing model off and on, beside the operations each counts, as ratios
   to brute force measured in one run: bunny 512^2 at CoC 10 and 50 px, modern_hall (a
   1920x1080 frame scaled by --hall-scale, default 1/2) and motion_field (400 moving triangles,
   640x480, CoC 10 px: the moving, defocused triangles of the 5D paths), 64 spp. The renders of one (scene,
   threads) cell are interleaved (A, B, C, A, B, C, ...) over several repeats and the minimum is
   kept, so load from other processes shifts all of them alike; no figure is compared against a
   fixed time. ``tile+optimal`` is tile with ``count_optimal: true`` (the Table 1 instrumentation).
2. The brute-force sample test per class (4D, 5D) with `pipeline.simd` off and on, in samples tested
   per second of CPU time, and the kernels alone.

Sampled simulation and the timing model's granularity are measured by bench_sampling.py.

Writes reports/bench/bench_speed.md. `python -m experiments.bench.bench_speed --help`."""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from experiments.bench import machine, scene_camera as _camera, write_page

REPO = Path(__file__).resolve().parents[2]
from experiments.paths import bundled_configs, reports_dir, results_dir  # noqa: E402,F401
ALGORITHMS = (("bruteforce", {}), ("tile", {}), ("tile+optimal", {"count_optimal": True}), ("interval", {}))
# Work-proportional simulation: CPU / bruteforce <= 1 wherever ops / bruteforce <= WORK_PROPORTIONAL_OPS,
# and in these cells (scene, CoC px, algorithm) besides (tile on the bunny at CoC 10 counts 0.55x).
WORK_PROPORTIONAL_OPS = 0.5
WORK_PROPORTIONAL_ALSO = (("bunny", 10.0, "tile"),)


def work_proportional_due(row: dict) -> bool:
    """Whether the rule (CPU / bruteforce <= 1) applies to a row of wall_table()."""
    if row["algorithm"] == "tile+optimal":
        return False
    return row["ops_ratio"] <= WORK_PROPORTIONAL_OPS or (row["scene"], row["coc"], row["algorithm"]) in WORK_PROPORTIONAL_ALSO


def _scenes(hall_scale: float, quick: bool):
    import models

    bunny = models.named("bunny")
    hall = models.named("modern_hall")
    size = 256 if quick else 512
    hw, hh = int(1920 * hall_scale), int(1080 * hall_scale)
    if quick:
        hw, hh = 480, 270
    scenes = [("bunny", bunny, size, size, 10.0), ("bunny", bunny, size, size, 50.0), ("modern_hall", hall, hw, hh, 10.0)]
    if not quick and (hw, hh) != (1920, 1080):  # the large interior at 1080p (modern_hall stands in)
        scenes.append(("modern_hall", hall, 1920, 1080, 10.0))
    mw, mh = (320, 240) if quick else (640, 480)
    scenes.append(("motion_field", models.named("motion_field"), mw, mh, 10.0))
    return scenes


def wall_table(hall_scale: float, threads, repeats: int, spp: int, quick: bool):
    """Rows (scene, size, coc, algorithm, threads, timing, wall, ops) of interleaved minima, timing model
    off and on (the opt-in instrumentation tile+optimal with timing off only)."""
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    rows = []
    for name, scene, w, h, coc in _scenes(hall_scale, quick):
        cam = _camera(scene, w, h, coc)
        for n_threads in threads:
            best: dict[tuple[str, bool], tuple[float, dict, float]] = {}
            cpu_best: dict[tuple[str, bool], float] = {}
            variants = [(a, e, t) for t in (False, True) for a, e in ALGORITHMS if not (t and e)]
            for _ in range(repeats):
                for algo, extra, timing in variants:
                    key = (algo, timing)
                    cfg = sim.PipelineConfig(algorithm=algo.split("+")[0], threads=n_threads, **extra)
                    t0, c0 = time.perf_counter(), time.process_time()
                    r = sim.render(scene, cam, table, cfg, timing=timing)
                    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
                    f = r.flat_stats
                    if key not in best or wall < best[key][0]:
                        best[key] = (wall, f, cpu_best.get(key, cpu))
                    cpu_best[key] = min(cpu_best.get(key, cpu), cpu)
                    best[key] = (*best[key][:2], cpu_best[key])
            for algo, _, timing in variants:
                bw, bf, bc = best[("bruteforce", timing)]
                wall, f, cpu = best[(algo, timing)]
                rows.append(dict(scene=name, size=f"{w}x{h}", coc=cam.coc_px, algorithm=algo, threads=n_threads,
                                 timing="on" if timing else "off", wall=wall, cpu=cpu, ops=f["ops.total"],
                                 tested=f["raster.samples_tested"], wall_ratio=wall / bw, cpu_ratio=cpu / bc,
                                 ops_ratio=f["ops.total"] / bf["ops.total"]))
                print(f"{name:12} {w}x{h} CoC {cam.coc_px:5.1f} {algo:13} thr {n_threads} timing {rows[-1]['timing']:3}: "
                      f"{wall:7.3f} s (x{wall / bw:.2f} of bruteforce), CPU {cpu:7.3f} s (x{cpu / bc:.2f}), "
                      f"ops x{f['ops.total'] / bf['ops.total']:.3f}", flush=True)
    return rows


def simd_table(spp: int, quick: bool, repeats: int):
    """Rows: brute-force sample tests per second per class, explicit SIMD on and off (pipeline.simd),
    one thread, interleaved; rates from the process CPU time (other processes' load inflates wall
    time, much less CPU time), and the kernels alone (sim._core.simd_batch_bench)."""
    import time

    import models
    import sim

    bunny = models.named("bunny")
    table = sim.SampleTable.stratified(spp=spp, seed=1)
    size = 256 if quick else 512
    rows = []
    for cls, moving, coc in (("4d", False, 10.0), ("4d", False, 30.0), ("5d", True, 10.0), ("5d", True, 30.0)):
        scene = bunny.with_motion(translation_t1=(0.15, 0.05, 0.0)) if moving else bunny
        cam = _camera(scene, size, size, coc)
        best = {}
        for _ in range(repeats):
            for flag in (False, True):
                c0 = time.process_time()
                r = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1, simd=flag),
                               timing=False)
                cpu = time.process_time() - c0
                best[flag] = min(cpu, best.get(flag, cpu))
        tested = r.flat_stats[f"raster.samples_tested_{cls}"]
        rows.append(dict(cls=cls.upper(), coc=coc, tested=tested, off=tested / best[False] / 1e6,
                         on=tested / best[True] / 1e6))
        print(f"{cls.upper()} CoC {coc:g}: {rows[-1]['off']:.0f} -> {rows[-1]['on']:.0f} M tests/s (CPU time)")
    kernels = {c: sim._core.simd_batch_bench(k, 1024, 2000)[:2] for c, k in (("4D", 2), ("5D", 3))}
    return rows, kernels


def sim_isa() -> str:
    import sim

    return sim._core.simd_isa()


def run(hall_scale: float = 0.5, threads=(1, 2), repeats: int = 3, spp: int = 64,
        quick: bool = False, out=None) -> dict:
    out = reports_dir() / "bench" if out is None else out
    if quick:
        repeats, spp = 1, 16
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = ["# bench_speed: simulator speed against simulated work", "",
             f"`make bench` (`python -m experiments.bench.bench_speed`), {machine()}, "
             f"load average {load:.1f} at the start. Wall times are minima over "
             f"{repeats} interleaved repeats; compare the ratios (measured in one run), not the seconds.", "",
             f"## Wall time against operations ({spp} spp; one thread and two)", "",
             "`tile+optimal` is `tile` with `count_optimal: true` (the exact-region instrumentation of [Akenine-Möller 2012] "
             "Table 1, off by default). Ratios are to brute force in the same cell.", "",
             "CPU: process CPU time of the render (all threads; minimum over the repeats), which other processes' "
             "load disturbs less than wall time. Timing: the timing and memory model (default hardware) off or on; "
             "ratios are to brute force with the same setting. Work-proportional simulation means CPU / bruteforce "
             f"<= 1 wherever ops / bruteforce <= {WORK_PROPORTIONAL_OPS:g}, and also for "
             + ", ".join(f"{a} on {s} at CoC {c:g}" for s, c, a in WORK_PROPORTIONAL_ALSO) + ".", "",
             "| scene | size | CoC px | algorithm | threads | timing | wall [s] | CPU [s] | ops | wall / bruteforce | "
             "CPU / bruteforce | ops / bruteforce |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = wall_table(hall_scale, threads, repeats, spp, quick)
    for r in rows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['coc']:g} | {r['algorithm']} | {r['threads']} | {r['timing']} | "
                     f"{r['wall']:.3f} | {r['cpu']:.3f} | {r['ops']:,.0f} | {r['wall_ratio']:.2f} | {r['cpu_ratio']:.2f} | "
                     f"{r['ops_ratio']:.3f} |")
    for timing in ("off", "on"):
        due = [r for r in rows if r["timing"] == timing and work_proportional_due(r)]
        late = [r for r in due if r["cpu_ratio"] > 1.0]
        lines += ["", f"Work-proportional rows with timing {timing}: {len(due)}; CPU / bruteforce above 1 in {len(late)}"
                  + (": " + ", ".join(f"{r['algorithm']} {r['scene']} {r['size']} CoC {r['coc']:g} {r['threads']} thr "
                                      f"({r['cpu_ratio']:.2f})" for r in late) if late else "") + "."]
    lines += ["", "`tile` against `tile+optimal` (the cost of the opt-in instrumentation):", "",
              "| scene | size | CoC px | threads | tile+optimal / tile |", "|---|---|---|---|---|"]
    by = {(r["scene"], r["size"], r["coc"], r["threads"], r["algorithm"]): r["wall"] for r in rows if r["timing"] == "off"}
    for (s, size, coc, t, a), w in by.items():
        if a == "tile":
            lines.append(f"| {s} | {size} | {coc:g} | {t} | {by[(s, size, coc, t, 'tile+optimal')] / w:.2f} |")
    vrows, kernels = simd_table(16, quick, max(2, repeats))
    lines += ["", f"## Explicit-SIMD sample tests (sampletest/simd_batch.h, {sim_isa()})", "",
              "Brute force, bunny, 16 spp, one thread; `pipeline.simd` off (the auto-vectorised scalar kernels) "
              "and on, interleaved, best of the repeats. Rates are samples tested per second of process CPU time "
              "of the whole render (engine setup, binning, the backend and Python included), so they are lower "
              "bounds of the sample-test rate; the target is 300 M/s per core.", "",
              "| class | CoC px | samples tested | simd off [M/s] | simd on [M/s] | on / off |", "|---|---|---|---|---|---|"]
    for r in vrows:
        lines.append(f"| {r['cls']} | {r['coc']:g} | {r['tested']:,} | {r['off']:.0f} | {r['on']:.0f} | {r['on'] / r['off']:.2f} |")
    lines += ["", "The kernels alone (1024-sample batches, minimum of 2000 interleaved passes, one thread):", "",
              "| class | scalar [M tests/s] | SIMD [M tests/s] | ratio |", "|---|---|---|---|"]
    for c, (a, b) in kernels.items():
        lines.append(f"| {c} | {a / 1e6:.0f} | {b / 1e6:.0f} | {b / a:.2f} |")
    page = write_page(out, "bench_speed.md", lines)
    return {"page": page, "rows": rows, "simd": vrows, "kernels": kernels}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--hall-scale", type=float, default=0.5, help="modern_hall at 1920x1080 times this")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(reports_dir() / "bench"))
    args = parser.parse_args(argv)
    run(args.hall_scale, args.threads, args.repeats, args.spp, args.quick, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

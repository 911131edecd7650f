"""`make bench`: simulator speed against the work it simulates, and sampled simulation.

1. Wall time per algorithm, scene and thread count beside the operations each counts, as ratios
   to brute force measured in one run: bunny 512^2 at CoC 10 and 50 px and modern_hall (a
   1920x1080 frame scaled by --hall-scale, default 1/2), 64 spp. The renders of one (scene,
   threads) cell are interleaved (A, B, C, A, B, C, ...) over several repeats and the minimum is
   kept, so load from other processes shifts all of them alike; no figure is compared against a
   fixed time. ``tile+optimal`` is tile with ``count_optimal: true`` (the Table 1 instrumentation).
2. Sampled simulation (PipelineConfig.sample_fraction): for fractions 1 ... 0.01 on three scenes,
   the speed-up over the whole frame and the error of the estimated frame totals against the
   whole-frame values (median over seeds), with the 95% half-width and how often it covered.
3. The timing model's granularity (hardware.timing.granularity): cycles and utilisation with records
   per (triangle, bin) against records per shading visit, and the simulator time of each.

Writes reports/bench/bench_speed.md. `python -m experiments.bench.bench_speed --help`."""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
ALGORITHMS = (("bruteforce", {}), ("tile", {}), ("tile+optimal", {"count_optimal": True}), ("interval", {}))
FRACTIONS = (1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01)
FIGURES = ("ops.total", "raster.samples_tested", "raster.samples_hit")


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
    return scenes


def _camera(scene, w, h, coc):
    import sim

    hint = scene.camera_hint
    return sim.Camera(width=w, height=h, fov_y_deg=hint.get("fov_y_deg", 45.0),
                      focus_distance=hint["focus_distance"], coc_px=coc)


def wall_table(hall_scale: float, threads, repeats: int, spp: int, quick: bool):
    """Rows (scene, size, coc, algorithm, threads, wall, ops) of interleaved minima."""
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    rows = []
    for name, scene, w, h, coc in _scenes(hall_scale, quick):
        cam = _camera(scene, w, h, coc)
        for n_threads in threads:
            best: dict[str, tuple[float, dict, float]] = {}
            cpu_best: dict[str, float] = {}
            for _ in range(repeats):
                for algo, extra in ALGORITHMS:
                    cfg = sim.PipelineConfig(algorithm=algo.split("+")[0], threads=n_threads, **extra)
                    c0 = time.process_time()
                    r = sim.render(scene, cam, table, cfg, timing=False)
                    cpu = time.process_time() - c0
                    f = r.flat_stats
                    if algo not in best or f["time.wall_s"] < best[algo][0]:
                        best[algo] = (f["time.wall_s"], f, cpu_best.get(algo, cpu))
                    cpu_best[algo] = min(cpu_best.get(algo, cpu), cpu)
                    best[algo] = (*best[algo][:2], cpu_best[algo])
            bw, bf, bc = best["bruteforce"]
            for algo, _ in ALGORITHMS:
                wall, f, cpu = best[algo]
                rows.append(dict(scene=name, size=f"{w}x{h}", coc=cam.coc_px, algorithm=algo, threads=n_threads,
                                 wall=wall, cpu=cpu, ops=f["ops.total"], tested=f["raster.samples_tested"],
                                 wall_ratio=wall / bw, cpu_ratio=cpu / bc, ops_ratio=f["ops.total"] / bf["ops.total"]))
                print(f"{name:12} {w}x{h} CoC {cam.coc_px:5.1f} {algo:13} thr {n_threads}: {wall:7.3f} s "
                      f"(x{wall / bw:.2f} of bruteforce), CPU {cpu:7.3f} s (x{cpu / bc:.2f}), "
                      f"ops x{f['ops.total'] / bf['ops.total']:.3f}", flush=True)
    return rows


def sampling_table(threads: int, seeds: int, spp: int, quick: bool, bin_size: int = 16):
    """Rows (scene, fraction, speedup, median |error| per figure, median relative half-width, coverage)."""
    import numpy as np

    import models
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    size = 256 if quick else 512
    cases = [("bunny", models.named("bunny"), size, size, 10.0, "tile"),
             ("spot", models.named("spot"), size, size, 10.0, "tile"),
             ("modern_hall", models.named("modern_hall"), 2 * size, size * 9 // 8, 10.0, "tile")]
    rows = []
    for name, scene, w, h, coc, algo in cases:
        cam = _camera(scene, w, h, coc)
        base = sim.PipelineConfig(algorithm=algo, threads=threads, bin_size=bin_size)
        full_walls, full = [], None
        for _ in range(2):
            r = sim.render(scene, cam, table, base, timing=False)
            full_walls.append(r.flat_stats["time.wall_s"])
            full = r.flat_stats
        t_full = min(full_walls)
        n_bins = (-(-w // bin_size)) * (-(-h // bin_size))
        for frac in FRACTIONS:
            if frac == 1.0:
                rows.append(dict(scene=name, size=f"{w}x{h}", bins=n_bins, fraction=1.0, speedup=1.0,
                                 **{f"err {k}": 0.0 for k in FIGURES}, **{f"ci {k}": 0.0 for k in FIGURES},
                                 coverage=1.0, wall=t_full))
                continue
            walls, errs, cis, cover = [], {k: [] for k in FIGURES}, {k: [] for k in FIGURES}, 0
            for seed in range(seeds):
                try:
                    r = sim.render(scene, cam, table, base.replace(sample_fraction=frac, sample_seed=seed), timing=False)
                except sim.ConfigError as e:  # too few bins with triangles for an interval
                    print(f"{name:12} f={frac:<5g} skipped: {e}")
                    break
                walls.append(r.flat_stats["time.wall_s"])
                ok = True
                for k in FIGURES:
                    truth = full[k]
                    errs[k].append(abs(r.flat_stats[k] - truth) / truth)
                    cis[k].append(r.ci95[k] / truth)
                    ok &= abs(r.flat_stats[k] - truth) <= r.ci95[k]
                cover += ok
            if not walls:
                continue
            wall = min(walls)
            row = dict(scene=name, size=f"{w}x{h}", bins=f"{n_bins} / {int(r.flat_stats['sample.candidates'])}", fraction=frac, speedup=t_full / wall,
                       **{f"err {k}": float(np.median(errs[k])) for k in FIGURES},
                       **{f"ci {k}": float(np.median(cis[k])) for k in FIGURES},
                       coverage=cover / seeds, wall=wall)
            rows.append(row)
            print(f"{name:12} f={frac:<5g} speed-up x{row['speedup']:.1f}  median |err| "
                  + ", ".join(f"{k} {row['err ' + k]:.2%}" for k in FIGURES)
                  + f"  all three covered {row['coverage']:.0%}")
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


UNITS = ("setup", "tile_test", "sample_test", "depth", "shader", "texture", "memory")


def granularity_table(spp: int, quick: bool, threads: int = 1):
    """Rows: the timing model with records per (triangle, bin) against records per shading visit
    (hardware.timing.granularity), on three scenes: cycles, per-unit utilisation, records, and the
    simulator time (render + timing model) each costs."""
    import time

    import models
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    size = 256 if quick else 512
    cases = [("bunny", models.named("bunny"), size, size), ("spot", models.named("spot"), size, size),
             ("modern_hall", models.named("modern_hall"), 2 * size, size * 9 // 8)]
    cfg = sim.PipelineConfig(algorithm="tile", shading="msaa", texture_count=1, threads=threads)
    rows = []
    for name, scene, w, h in cases:
        cam = _camera(scene, w, h, 10.0)
        out = {}
        for gran in ("bin", "visit", "bin", "visit"):  # interleaved twice; minimum time kept
            hw = sim.HardwareConfig(timing={"granularity": gran})
            t0 = time.perf_counter()
            r = sim.render(scene, cam, table, cfg, hardware=hw)
            wall = time.perf_counter() - t0
            prev = out.get(gran)
            out[gran] = (min(wall, prev[0]) if prev else wall, r.flat_stats, len(r.timing_records))
        (tb, fb, nb), (tv, fv, nv) = out["bin"], out["visit"]
        util = {u: fb[f"timing.{u}.utilization"] - fv[f"timing.{u}.utilization"] for u in UNITS}
        worst = max(util, key=lambda u: abs(util[u]))
        row = dict(scene=name, size=f"{w}x{h}", cycles_bin=fb["timing.cycles"], cycles_visit=fv["timing.cycles"],
                   err=fb["timing.cycles"] / fv["timing.cycles"] - 1, util_unit=worst, util_diff=util[worst],
                   bottleneck_bin=fb["timing.bottleneck"], bottleneck_visit=fv["timing.bottleneck"],
                   records_bin=nb, records_visit=nv, time_bin=tb, time_visit=tv)
        rows.append(row)
        print(f"{name:12} cycles bin {row['cycles_bin']:,.0f} visit {row['cycles_visit']:,.0f} ({row['err']:+.2%}); "
              f"largest utilisation change {worst} {util[worst]:+.3f}; records {nb:,} / {nv:,}; "
              f"time x{tv / tb:.2f}")
    return rows


def run(hall_scale: float = 0.5, threads=(1, 2), repeats: int = 3, seeds: int = 5, spp: int = 64,
        quick: bool = False, out=REPO / "reports" / "bench") -> dict:
    if quick:
        repeats, seeds, spp = 1, 3, 16
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = ["# bench_speed: simulator speed against simulated work; sampled simulation", "",
             f"`make bench` (`python -m experiments.bench.bench_speed`), {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} hardware threads, load average {load:.1f} at the start. Wall times are minima over "
             f"{repeats} interleaved repeats; compare the ratios (measured in one run), not the seconds.", "",
             f"## Wall time against operations ({spp} spp; one thread and two)", "",
             "`tile+optimal` is `tile` with `count_optimal: true` (the exact-region instrumentation of 001 "
             "Table 1, off by default). Ratios are to brute force in the same cell.", "",
             "CPU: process CPU time of the render (all threads; minimum over the repeats), which other processes' "
             "load disturbs less than wall time. Work-proportional simulation means CPU / bruteforce <= 1 wherever "
             "ops / bruteforce <= 0.5.", "",
             "| scene | size | CoC px | algorithm | threads | wall [s] | CPU [s] | ops | wall / bruteforce | "
             "CPU / bruteforce | ops / bruteforce |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = wall_table(hall_scale, threads, repeats, spp, quick)
    for r in rows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['coc']:g} | {r['algorithm']} | {r['threads']} | {r['wall']:.3f} | "
                     f"{r['cpu']:.3f} | {r['ops']:,.0f} | {r['wall_ratio']:.2f} | {r['cpu_ratio']:.2f} | {r['ops_ratio']:.3f} |")
    lines += ["", "`tile` against `tile+optimal` (the cost of the opt-in instrumentation):", "",
              "| scene | size | CoC px | threads | tile+optimal / tile |", "|---|---|---|---|---|"]
    by = {(r["scene"], r["size"], r["coc"], r["threads"], r["algorithm"]): r["wall"] for r in rows}
    for (s, size, coc, t, a), w in by.items():
        if a == "tile":
            lines.append(f"| {s} | {size} | {coc:g} | {t} | {by[(s, size, coc, t, 'tile+optimal')] / w:.2f} |")
    srows = sampling_table(max(threads), seeds, spp, quick)
    lines += ["", f"## Sampled simulation: speed against estimate error ({spp} spp, tile, bin_size 16, "
              f"{max(threads)} threads, {seeds} seeds per fraction)", "",
              "Speed-up: whole-frame wall time / sampled wall time (minimum over the seeds). |err|: median "
              "relative error of the estimated frame total against the whole-frame value; ±95%: median relative "
              "half-width; covered: share of seeds whose three intervals all contain the frame value. The "
              "fraction is of the bins that hold triangles (bins: all / with triangles). Triangle setup runs for "
              "every triangle at every fraction, which bounds the speed-up.", "",
              "| scene | size | bins | fraction | speed-up | |err| ops.total | ±95% ops.total | |err| samples_tested | "
              "±95% samples_tested | |err| samples_hit | ±95% samples_hit | covered |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in srows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['bins']} | {r['fraction']:g} | {r['speedup']:.1f} | "
                     + " | ".join(f"{r['err ' + k]:.2%} | {r['ci ' + k]:.2%}" for k in FIGURES)
                     + f" | {r['coverage']:.0%} |")
    vrows, kernels = simd_table(16, quick, max(2, repeats))
    lines += ["", f"## Explicit-SIMD sample tests (sampletest/simd_batch.h, {sim_isa()})", "",
              "Brute force, bunny, 16 spp, one thread; `pipeline.simd` off (the auto-vectorised scalar kernels) "
              "and on, interleaved, best of the repeats. Rates are samples tested per second of process CPU time "
              "(engine setup and Python included), so they are lower bounds of the sample-test rate.", "",
              "| class | CoC px | samples tested | simd off [M/s] | simd on [M/s] | on / off |", "|---|---|---|---|---|---|"]
    for r in vrows:
        lines.append(f"| {r['cls']} | {r['coc']:g} | {r['tested']:,} | {r['off']:.0f} | {r['on']:.0f} | {r['on'] / r['off']:.2f} |")
    lines += ["", "The kernels alone (1024-sample batches, minimum of 2000 interleaved passes, one thread):", "",
              "| class | scalar [M tests/s] | SIMD [M tests/s] | ratio |", "|---|---|---|---|"]
    for c, (a, b) in kernels.items():
        lines.append(f"| {c} | {a / 1e6:.0f} | {b / 1e6:.0f} | {b / a:.2f} |")
    grows = granularity_table(spp, quick)
    lines += ["", f"## Timing-model granularity ({spp} spp, tile, msaa, 1 texture, CoC 10 px, 1 core)", "",
              "`hardware.timing.granularity`: `bin` = one work record per (triangle, 64-px bin); `visit` = one per "
              "shading visit (per triangle and tile for tile). Error: bin cycles / visit cycles - 1 (visit is the "
              "detailed reference). Utilisation: busy / cycles per unit; the largest change between the two is shown. "
              "Time: render plus timing model, minimum of 2 interleaved runs.", "",
              "| scene | size | cycles (bin) | cycles (visit) | error | bottleneck bin / visit | largest utilisation change | "
              "records bin / visit | sim time visit / bin |", "|---|---|---|---|---|---|---|---|---|"]
    for r in grows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['cycles_bin']:,.0f} | {r['cycles_visit']:,.0f} | {r['err']:+.2%} | "
                     f"{r['bottleneck_bin']} / {r['bottleneck_visit']} | {r['util_unit']} {r['util_diff']:+.3f} | "
                     f"{r['records_bin']:,} / {r['records_visit']:,} | {r['time_visit'] / r['time_bin']:.2f} |")
    page = Path(out) / "bench_speed.md"
    page.parent.mkdir(parents=True, exist_ok=True)
    page.write_text("\n".join(lines) + "\n")
    print(f"\nwrote {page}")
    return {"page": page, "rows": rows, "sampling": srows, "granularity": grows}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--hall-scale", type=float, default=0.5, help="modern_hall at 1920x1080 times this")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(REPO / "reports" / "bench"))
    args = parser.parse_args(argv)
    run(args.hall_scale, args.threads, args.repeats, args.seeds, args.spp, args.quick, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

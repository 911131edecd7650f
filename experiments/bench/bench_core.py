"""`make bench`: engine throughput. Brute force on the bunny and on mixed_sizes at 512^2, 16 spp,
CoC 0 / 10 / 30 px, static and moving, for 1 and 2 threads: samples tested per second, ns per
sample test for each dimension class (2D static in focus, 3D moving in focus, 4D static defocused,
5D moving defocused), and the slowdown of exact operation counting. Ratios are measured in one run;
nothing is compared against a fixed time. Writes reports/bench/bench_core.md.

`make bench` runs it through pytest (tests/test_bench.py, marker ``bench``); `python -m
experiments.bench.bench_core` runs it directly."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from experiments.bench import machine, write_page

REPO = Path(__file__).resolve().parents[2]
from experiments.paths import bundled_configs, reports_dir, results_dir  # noqa: E402,F401


def scenes(quick: bool):
    import models

    bunny = models.named("bunny")
    mixed = models.named("mixed_sizes", n=5000 if quick else 20000)
    out = []
    for name, s in (("bunny", bunny), ("mixed_sizes", mixed)):
        out.append((name, False, s))
        out.append((name, True, s.with_motion(translation_t1=(0.15, 0.05, 0.0))))
    return out


def best_of(fn, repeats):
    best = None
    for _ in range(repeats):
        r = fn()
        if best is None or r.flat_stats["time.wall_s"] < best.flat_stats["time.wall_s"]:
            best = r
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="smaller mixed_sizes, one repeat")
    parser.add_argument("--out", default=str(reports_dir() / "bench"))
    args = parser.parse_args(argv)
    run(size=args.size, spp=args.spp, threads=args.threads, repeats=args.repeats, quick=args.quick, out=args.out)
    return 0


def run(size: int = 512, spp: int = 16, threads=(1, 2), repeats: int = 1, quick: bool = False,
        out=None) -> dict:
    """Run the benchmark and write ``out``/bench_core.md. Returns {"page": path of the page,
    "counts_equal": {algorithm: exact and documented operation counts agree}}."""
    out = reports_dir() / "bench" if out is None else out
    if quick:
        repeats = 1
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    lines = [f"# bench_core: brute-force throughput", "",
             f"`make bench` (`python -m experiments.bench.bench_core`), {machine()}, "
             f"{size}^2, {spp} spp, best of {repeats}.", "",
             "| scene | motion | CoC | threads | samples tested | Msamples/s | ns/test | class mix (2D/3D/4D/5D tests) |",
             "|---|---|---|---|---|---|---|---|"]
    per_class: dict[str, list[tuple[float, int]]] = {"2d": [], "3d": [], "4d": [], "5d": []}
    print(f"{'scene':12} {'motion':6} {'CoC':>4} {'thr':>3} {'tested':>13} {'Ms/s':>8} {'ns/test':>8}")
    for name, moving, scene in scenes(quick):
        hint = scene.camera_hint
        for coc in (0.0, 10.0, 30.0):
            cam = sim.Camera(width=size, height=size, fov_y_deg=hint["fov_y_deg"],
                             focus_distance=hint["focus_distance"], coc_px=coc)
            for n_threads in threads:
                cfg = sim.PipelineConfig(algorithm="bruteforce", threads=n_threads)
                r = best_of(lambda: sim.render(scene, cam, table, cfg), repeats)
                f = r.flat_stats
                tested, wall = f["raster.samples_tested"], f["time.wall_s"]
                mix = [f[f"raster.samples_tested_{c}"] for c in ("2d", "3d", "4d", "5d")]
                rate = tested / wall / 1e6
                print(f"{name:12} {str(moving):6} {coc:>4g} {n_threads:>3} {tested:>13,} {rate:>8.1f} {1e3 / rate:>8.2f}")
                lines.append(f"| {name} | {moving} | {coc:g} | {n_threads} | {tested:,} | {rate:.1f} | {1e3 / rate:.2f} | "
                             + "/".join(f"{m / max(tested, 1):.0%}" for m in mix) + " |")
                if n_threads == 1:
                    dominant = max(range(4), key=lambda i: mix[i])
                    if mix[dominant] > 0.95 * tested:
                        per_class[("2d", "3d", "4d", "5d")[dominant]].append((wall, tested))
    lines += ["", "## ns per sample test by dimension class (single thread, renders where one class is > 95% of tests)", "",
              "| class | what | ns/test | Msamples/s | documented ops/test |", "|---|---|---|---|---|"]
    costs = {k: v[0] for k, v in sim._core.measure_kernel_costs(1, 1).items()}
    what = {"2d": "static, in focus", "3d": "moving, in focus", "4d": "static, defocused", "5d": "moving, defocused"}
    print("\nns per sample test, single thread:")
    for c, runs in per_class.items():
        if not runs:
            continue
        wall = sum(w for w, _ in runs)
        tested = sum(t for _, t in runs)
        ns = wall / tested * 1e9
        print(f"  {c.upper()} ({what[c]}): {ns:.2f} ns/test = {1e3 / ns:.0f} M tests/s, {costs[f'sample.inside_{c}']} ops/test")
        lines.append(f"| {c.upper()} | {what[c]} | {ns:.2f} | {1e3 / ns:.0f} | {costs[f'sample.inside_{c}']} |")
    # Exact-count slowdown: the same render in both modes (smaller image: the counting type is slow).
    import models

    small = 128
    lines += ["", "## Exact operation counting", "",
              "| scene | algorithm | documented [s] | exact [s] | slowdown | counts equal |", "|---|---|---|---|---|---|"]
    print("\nexact-count mode slowdown (128^2, CoC 10, 1 thread):")
    bunny = models.named("bunny")
    cam = sim.Camera(width=small, height=small, fov_y_deg=45, focus_distance=bunny.camera_hint["focus_distance"], coc_px=10)
    counts_equal = {}
    for algo in ("bruteforce", "tile"):
        rd = best_of(lambda: sim.render(bunny, cam, table, sim.PipelineConfig(algorithm=algo, threads=1)), repeats)
        re = sim.render(bunny, cam, table, sim.PipelineConfig(algorithm=algo, threads=1, op_count="exact"))
        same = all(rd.flat_stats[k] == re.flat_stats[k] for k in rd.flat_stats if k.startswith(("ops.", "raster.")))
        counts_equal[algo] = same
        slow = re.flat_stats["time.wall_s"] / rd.flat_stats["time.wall_s"]
        print(f"  {algo}: documented {rd.flat_stats['time.wall_s']:.3f} s, exact {re.flat_stats['time.wall_s']:.3f} s, "
              f"slowdown {slow:.1f}x, counts equal: {same}")
        lines.append(f"| bunny | {algo} | {rd.flat_stats['time.wall_s']:.3f} | {re.flat_stats['time.wall_s']:.3f} | "
                     f"{slow:.1f}x | {same} |")
    page = write_page(out, "bench_core.md", lines)
    return {"page": page, "counts_equal": counts_equal}


if __name__ == "__main__":
    sys.exit(main())

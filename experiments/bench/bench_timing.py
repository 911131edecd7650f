"""What the timing and memory model costs: CPU time of a timed render over the same render untimed,
and the peak memory of a timed 1080p frame over the untimed one.

1. CPU, timed / untimed (process CPU time, the minimum of interleaved repeats), 64 spp, `tile`, one
   thread and two: the bunny at 512x512, CoC 10 and 50 px; modern_hall at 1920x1080, CoC 10; the dense
   interior (modern_hall with every triangle split into four: 123,644 triangles) at 1920x1080, CoC 10.
   Timed is the default hardware (memory system on, records per visit, none kept), and, for the
   record, the same with the memory system off and with records per (triangle, bin).
2. Peak memory: each render in a child process; the rise of its resident set over the render
   (VmHWM after resetting it), timed and untimed, at 1920x1080, 64 spp.
3. No refusals: the renders that used to exceed the 4 GiB memory guard with timing on, checked
   against sim.memory_estimate with timing on (and the first rendered).

Writes reports/bench/bench_timing.md. `python -m experiments.bench.bench_timing --help`."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time

from experiments.bench import machine, bench_parser, write_page
from experiments.paths import reports_dir

FLAT = {"depth_buffer": {"enabled": False, "compression": "none"}, "color_buffer": {"enabled": False}}
VARIANTS = (("untimed", False, {}), ("timed", True, {}), ("timed, memory system off", True, FLAT),
            ("timed, records per (triangle, bin)", True, {"timing": {"granularity": "bin"}}))


def _scene(name: str, subdivide: int = 0):
    import models

    return models.named(name, subdivide=subdivide) if subdivide else models.named(name)


CASES = (("bunny", 0, 512, 512, 10.0), ("bunny", 0, 512, 512, 50.0), ("modern_hall", 0, 1920, 1080, 10.0),
         ("modern_hall", 1, 1920, 1080, 10.0))


def cpu_table(threads_list=(1, 2), repeats: int = 2, quick: bool = False) -> list[dict]:
    import sim

    rows = []
    cases = CASES[:1] if quick else CASES
    for name, sub, w, h, coc in cases:
        scene = _scene(name, sub)
        if quick:
            w, h = w // 4, h // 4
        cam = sim.Camera.for_scene(scene, width=w, height=h, coc_px=coc)
        table = sim.SampleTable.stratified(spp=64, seed=1)
        for threads in threads_list:
            cfg = sim.PipelineConfig(algorithm="tile", threads=threads)
            sim.render(scene, cam, table, cfg, timing=False)  # warm: the table's index, page cache
            best: dict[str, float] = {}
            figures = {}
            for _ in range(repeats):
                for label, timing, hw in VARIANTS:
                    hwc = sim.HardwareConfig.from_dict(hw)
                    c0 = time.process_time()
                    r = sim.render(scene, cam, table, cfg, timing=timing, hardware=hwc)
                    cpu = time.process_time() - c0
                    best[label] = min(cpu, best.get(label, cpu))
                    figures[label] = r.flat_stats
            t = figures["timed"]
            row = dict(scene=name + (f" (x{4 ** sub} triangles)" if sub else ""), triangles=scene.n_triangles,
                       size=f"{w}x{h}", coc=coc, threads=threads, untimed=best["untimed"],
                       records=int(t["timing.records"]), cycles=t["timing.cycles"], bottleneck=t["timing.bottleneck"],
                       **{f"ratio {lab}": best[lab] / best["untimed"] for lab, _, _ in VARIANTS[1:]})
            rows.append(row)
            print(f"{row['scene']:24} {row['size']:>9} CoC {coc:g} threads {threads}: untimed {best['untimed']:.2f} s, "
                  + ", ".join(f"{lab} x{row['ratio ' + lab]:.2f}" for lab, _, _ in VARIANTS[1:]), flush=True)
    return rows


CHILD = r"""
import json, sys
import sim, models
name, sub, w, h, spp, timing, threads = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), sys.argv[6] == "1", int(sys.argv[7])
scene = models.named(name, subdivide=sub) if sub else models.named(name)
cam = sim.Camera.for_scene(scene, width=w, height=h, coc_px=10.0)
table = sim.SampleTable.stratified(spp=spp, seed=1)
cfg = sim.PipelineConfig(algorithm="tile", threads=threads)
table.engine_index(cam.lens, cfg.resolved_lens_grid(spp), cfg.time_strata)
def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024
before = status("VmRSS:")
open("/proc/self/clear_refs", "w").write("5")
r = sim.render(scene, cam, table, cfg, timing=timing)
print(json.dumps({"peak_increase": status("VmHWM:") - before, "records": r.flat_stats.get("timing.records")}))
"""


def peak_table(quick: bool = False) -> list[dict]:
    rows = []
    cases = [("modern_hall", 0, 480, 270)] if quick else [("modern_hall", 0, 1920, 1080), ("modern_hall", 1, 1920, 1080)]
    for name, sub, w, h in cases:
        out = {}
        for timing in (False, True):
            run = subprocess.run([sys.executable, "-c", CHILD, name, str(sub), str(w), str(h), "64", str(int(timing)), "2"],
                                 capture_output=True, text=True, check=True)
            out[timing] = json.loads(run.stdout.strip().splitlines()[-1])
        rows.append(dict(scene=name + (f" (x{4 ** sub} triangles)" if sub else ""), size=f"{w}x{h}",
                         untimed=out[False]["peak_increase"], timed=out[True]["peak_increase"],
                         records=out[True]["records"]))
        r = rows[-1]
        print(f"peak {r['scene']} {r['size']}: untimed {r['untimed'] / 2**20:.0f} MiB, timed {r['timed'] / 2**20:.0f} MiB "
              f"(x{r['timed'] / r['untimed']:.2f})", flush=True)
    return rows


# The renders the memory guard refused with timing on before the model was streamed (records: GiB
# estimated then): (scene, subdivide, width, height, spp, extra pipeline keys, what).
REFUSED = (("modern_hall", 1, 1920, 1080, 64, {}, "1920x1080, 64 spp, the dense interior (5.3 GiB of records)"),
           ("modern_hall", 1, 256, 144, 64, {"shading": "msaa", "texture_count": 1},
            "256x144, 64 spp, MSAA, the dense interior (4.2 GiB)"),
           ("bunny", 0, 256, 256, 64, {"tile_size": 1}, "the bunny at 256x256, CoC 50, tile_size 1 (6.9 GiB)"))


def refusal_table(render_first: bool = True) -> list[dict]:
    import sim
    from sim.render import visit_record_estimate

    rows = []
    for k, (name, sub, w, h, spp, extra, what) in enumerate(REFUSED):
        scene = _scene(name, sub)
        coc = 50.0 if name == "bunny" else 10.0
        cam = sim.Camera.for_scene(scene, width=w, height=h, coc_px=coc)
        cfg = sim.PipelineConfig(algorithm="tile", threads=2, **extra)
        v0, v1 = cam.engine_vertices(scene.positions, scene.positions_t1)
        est = sim.memory_estimate(cam, spp, scene.n_triangles, cfg, 2, timing=True,
                                  visit_records=visit_record_estimate(cam, v0, v1, cfg))
        rendered = ""
        if render_first and k == 0:
            r = sim.render(scene, cam, sim.SampleTable.stratified(spp=spp, seed=1), cfg)
            rendered = f"rendered: {r.flat_stats['timing.cycles']:,.0f} cycles"
        rows.append(dict(what=what, estimate=est, limit=cfg.memory_limit_bytes, rendered=rendered))
        print(f"{what}: estimate {est / 2**30:.2f} GiB {rendered}", flush=True)
    return rows


def run(quick: bool = False, out=None) -> dict:
    out = reports_dir() / "bench" if out is None else out
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    crows = cpu_table(repeats=1 if quick else 2, quick=quick)
    prows = peak_table(quick)
    rrows = refusal_table(render_first=not quick)
    labels = [lab for lab, _, _ in VARIANTS[1:]]
    lines = ["# bench_timing: what the timing and memory model costs", "",
             f"`python -m experiments.bench.bench_timing` (part of `make bench`), {machine()}, "
             f"load average {load:.1f} at the start. Compare the ratios (measured in one "
             "run), not the seconds.", "",
             "## CPU time, timed over untimed (64 spp, tile)", "",
             "Process CPU time (all threads, Python included), the minimum of interleaved repeats. Timed: the "
             "default hardware (depth and colour tile caches, compression, records per visit, none kept). "
             "Records: work records the timing model consumed.", "",
             "| scene | triangles | size | CoC | threads | untimed [s] | " + " | ".join(labels) + " | records | "
             "cycles | bottleneck |",
             "|---|---|---|---|---|---|" + "---|" * len(labels) + "---|---|---|"]
    for r in crows:
        lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['size']} | {r['coc']:g} | {r['threads']} | "
                     f"{r['untimed']:.2f} | " + " | ".join(f"{r['ratio ' + lab]:.2f}" for lab in labels)
                     + f" | {r['records']:,} | {r['cycles']:,.0f} | {r['bottleneck']} |")
    lines += ["", "## Peak memory of a frame, timed and untimed (64 spp, tile, 2 threads)", "",
              "The rise of the resident set over the render, measured in a child process (peak reset first).", "",
              "| scene | size | untimed [MiB] | timed [MiB] | timed / untimed | records |", "|---|---|---|---|---|---|"]
    for r in prows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['untimed'] / 2**20:.0f} | {r['timed'] / 2**20:.0f} | "
                     f"{r['timed'] / r['untimed']:.2f} | {r['records']:,} |")
    lines += ["", "## Renders the memory guard refused with timing on", "",
              "sim.memory_estimate with timing on, against the default limit (PipelineConfig.memory_limit_bytes).", "",
              "| render | estimate [GiB] | limit [GiB] | refused | |", "|---|---|---|---|---|"]
    for r in rrows:
        lines.append(f"| {r['what']} | {r['estimate'] / 2**30:.2f} | {r['limit'] / 2**30:.0f} | "
                     f"{'yes' if r['estimate'] > r['limit'] else 'no'} | {r['rendered']} |")
    page = write_page(out, "bench_timing.md", lines)
    return {"page": page, "cpu": crows, "peak": prows, "refusals": rrows}


def main(argv=None) -> int:
    ap = bench_parser(__doc__)
    ap.add_argument("--quick", action="store_true", help="small frames, one repeat (a smoke run)")
    a = ap.parse_args(argv)
    run(a.quick, a.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

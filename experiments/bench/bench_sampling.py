"""Sampled simulation and the timing model's granularity: what each costs against what it gets wrong.

1. Sampled simulation (PipelineConfig.sample_fraction, sim/sampling.py): for fractions 1 ... 0.01 on
   three scenes, the speed-up over the whole frame (wall and process CPU time, the minimum over the
   seeds against the minimum of the whole-frame renders interleaved with them) and the error of the estimated frame totals
   of ops.total, raster.samples_tested and raster.samples_hit (median over the seeds), with the median
   95% half-width.
2. The coverage of the 95% intervals over many draws: one render lists every bin (the engine returns
   each bin's own counters), then the engine's own draw (sim._core.stratify_bins) and the estimator
   are applied for each seed; covered = share of the draws whose interval contains the whole-frame
   value, per figure.
   Summary: the speed-up of 1. against the median error and coverage of 2. (200 draws rather than the
   few rendered seeds), and per scene the cheapest fraction whose median errors are under 1%.
   Units smaller than a bin (PipelineConfig.sample_split) on modern_hall: sampled renders of several
   fractions with the dense bins cut into units of their triangles, each row's speed-up, error and
   coverage from the same draws, beside the same fraction with whole bins.
3. The timing model's granularity (hardware.timing.granularity): cycles and the units' shares of the
   busy cycles with records per (triangle, bin) against records per shading visit, against the
   simulator time (render + timing model) and the records each costs.

Writes reports/bench/bench_sampling.md. `python -m experiments.bench.bench_sampling --help`."""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from experiments.bench import machine, scene_camera as _camera, write_page

REPO = Path(__file__).resolve().parents[2]
from experiments.paths import bundled_configs, reports_dir, results_dir  # noqa: E402,F401
FRACTIONS = (1.0, 0.5, 0.2, 0.1, 0.05, 0.04, 0.03, 0.025, 0.02, 0.01)
FIGURES = ("ops.total", "raster.samples_tested", "raster.samples_hit")
UNITS = ("setup", "tile_test", "sample_test", "depth", "shader", "texture", "dram")


def _cases(quick: bool):
    import models

    size = 256 if quick else 512
    return [("bunny", models.named("bunny"), size, size), ("spot", models.named("spot"), size, size),
            ("modern_hall", models.named("modern_hall"), 2 * size, size * 9 // 8)]


def _timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def sampling_table(threads: int, seeds: int, spp: int, quick: bool, bin_size: int, fractions=FRACTIONS):
    """Rows (scene, fraction, speed-up wall/CPU, median |error| and half-width per figure)."""
    import numpy as np

    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    rows = []
    for name, scene, w, h in _cases(quick):
        cam = _camera(scene, w, h, 10.0)
        base = sim.PipelineConfig(algorithm="tile", threads=threads, bin_size=bin_size)
        runs = [_timed(lambda: sim.render(scene, cam, table, base, timing=False)) for _ in range(2)]
        full = runs[-1][0].flat_stats
        n_bins = (-(-w // bin_size)) * (-(-h // bin_size))
        scene_rows = []
        for frac in fractions:
            if frac == 1.0:
                scene_rows.append(dict(scene=name, size=f"{w}x{h}", bins=f"{n_bins}", fraction=1.0, drawn=0,
                                       **{f"err {k}": 0.0 for k in FIGURES}, **{f"ci {k}": 0.0 for k in FIGURES}))
                continue
            # One whole frame before each fraction's seeds: the whole frame's minimum is taken over renders
            # spread through the scene's run, as the sampled renders' is (a machine whose load changes
            # during the run then moves both alike).
            runs.append(_timed(lambda: sim.render(scene, cam, table, base, timing=False)))
            walls, cpus, errs, cis = [], [], {k: [] for k in FIGURES}, {k: [] for k in FIGURES}
            r = None
            for seed in range(seeds):
                cfg = base.replace(sample_fraction=frac, sample_seed=seed)
                try:
                    r, wall, cpu = _timed(lambda: sim.render(scene, cam, table, cfg, timing=False))
                except sim.ConfigError as e:  # too few bins with triangles for an interval
                    print(f"{name:12} f={frac:<5g} not estimable: {str(e)[:90]}", flush=True)
                    break
                walls.append(wall), cpus.append(cpu)
                for k in FIGURES:
                    errs[k].append(abs(r.flat_stats[k] - full[k]) / full[k])
                    cis[k].append(r.ci95[k] / full[k])
            if not walls:
                continue
            scene_rows.append(dict(scene=name, size=f"{w}x{h}", bins=f"{n_bins} / {int(r.flat_stats['sample.candidates'])}",
                                   fraction=frac, drawn=int(r.flat_stats["sample.bins"]), wall=min(walls), cpu=min(cpus),
                                   **{f"err {k}": float(np.median(errs[k])) for k in FIGURES},
                                   **{f"ci {k}": float(np.median(cis[k])) for k in FIGURES}))
        t_full, c_full = min(r[1] for r in runs), min(r[2] for r in runs)
        for row in scene_rows:
            if row["fraction"] == 1.0:
                row.update(speedup=1.0, cpu_speedup=1.0, wall=t_full, cpu=c_full)
                continue
            row.update(speedup=t_full / row["wall"], cpu_speedup=c_full / row["cpu"])
            print(f"{name:12} f={row['fraction']:<5g} bins {row['drawn']:5d} speed-up wall x{row['speedup']:.1f} CPU "
                  f"x{row['cpu_speedup']:.1f}  median |err| " + ", ".join(f"{k} {row['err ' + k]:.2%}" for k in FIGURES),
                  flush=True)
        rows += scene_rows
    return rows


def coverage_table(spp: int, quick: bool, bin_size: int, draws: int, fractions=FRACTIONS[1:]):
    """Rows (scene, fraction, per figure: share of draws covered, median |error|) from one render that
    lists every bin, through the engine's draw and sim.sampling.estimate."""
    import numpy as np

    import sim
    from sim import sampling
    from sim.stats import DERIVED

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    rows = []
    for name, scene, w, h in _cases(quick):
        cam = _camera(scene, w, h, 10.0)
        n_bins = (-(-w // bin_size)) * (-(-h // bin_size))
        full = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile", bin_size=bin_size), timing=False,
                          _bins=np.arange(n_bins))  # every bin listed: each bin's own counters
        out = full.config["bins"]
        names = list(out["counters"])
        rows_all = np.asarray(out["bin_counters"])
        work, aux = np.asarray(out["bin_work"]), np.asarray(out["bin_aux"])
        setup = {n: int(out["counters"][n]) - int(rows_all[:, i].sum()) for i, n in enumerate(names)}
        for frac in fractions:
            hit = {k: 0 for k in FIGURES}
            errs = {k: [] for k in FIGURES}
            n = 0
            for seed in range(draws):
                try:
                    s = sampling.choose_bins(work, frac, seed, aux)
                except sim.ConfigError:
                    break
                sub = rows_all[s.bins]
                counters = {nm: setup[nm] + int(sub[:, i].sum()) for i, nm in enumerate(names)}
                flat, ci = sampling.estimate(s, counters, sub, DERIVED, names)
                for k in FIGURES:
                    truth = full.flat_stats[k]
                    hit[k] += abs(flat[k] - truth) <= ci[k]
                    errs[k].append(abs(flat[k] - truth) / truth)
                n += 1
            if not n:
                continue
            rows.append(dict(scene=name, fraction=frac, draws=n, strata=len(s.sizes),
                             **{f"cov {k}": hit[k] / n for k in FIGURES},
                             **{f"err {k}": float(np.median(errs[k])) for k in FIGURES}))
            print(f"{name:12} f={frac:<5g} {n} draws: covered " + ", ".join(f"{k} {hit[k] / n:.3f}" for k in FIGURES),
                  flush=True)
    return rows


def granularity_table(spp: int, quick: bool, threads: int = 1, repeats: int = 2):
    """Rows: the timing model with records per (triangle, bin) against records per shading visit
    (hardware.timing.granularity) on three scenes: cycles, the units' shares of the busy cycles,
    records, and the simulator time (render + timing model) each costs."""
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    cfg = sim.PipelineConfig(algorithm="tile", shading="msaa", texture_count=1, threads=threads)
    rows = []
    for name, scene, w, h in _cases(quick):
        cam = _camera(scene, w, h, 10.0)
        out = {}
        for gran in ("bin", "visit") * repeats:  # interleaved; minimum time kept
            hw = sim.HardwareConfig(timing={"granularity": gran})
            r, wall, cpu = _timed(lambda: sim.render(scene, cam, table, cfg, hardware=hw, keep_timing_records=True))
            prev = out.get(gran)
            out[gran] = (min(cpu, prev[0]) if prev else cpu, r.flat_stats, len(r.timing_records))
        (tb, fb, nb), (tv, fv, nv) = out["bin"], out["visit"]

        bot_b, bot_v = fb["timing.bottleneck"], fv["timing.bottleneck"]
        util = {u: fb[f"timing.{u}.utilization"] - fv[f"timing.{u}.utilization"] for u in UNITS}
        uworst = max(util, key=lambda u: abs(util[u]))
        row = dict(scene=name, size=f"{w}x{h}", cycles_bin=fb["timing.cycles"], cycles_visit=fv["timing.cycles"],
                   err=fb["timing.cycles"] / fv["timing.cycles"] - 1, bottleneck_bin=fb["timing.bottleneck"],
                   bottleneck_visit=fv["timing.bottleneck"], bot_util_bin=fb[f"timing.{bot_b}.utilization"],
                   bot_util_visit=fv[f"timing.{bot_v}.utilization"], util_unit=uworst, util_diff=util[uworst], records_bin=nb, records_visit=nv, time_bin=tb, time_visit=tv)
        rows.append(row)
        print(f"{name:12} cycles bin {row['cycles_bin']:,.0f} visit {row['cycles_visit']:,.0f} ({row['err']:+.2%}); "
              f"bottleneck {row['bottleneck_bin']} / {row['bottleneck_visit']}; records {nb:,} / {nv:,}; "
              f"CPU time x{tv / tb:.2f}", flush=True)
    return rows


def granularity_lines(grows, spp: int) -> list[str]:
    lines = ["", f"## Timing-model granularity ({spp} spp, tile, msaa, 1 texture, CoC 10 px, 1 thread)", "",
             "`hardware.timing.granularity`: `bin` = one work record per (triangle, screen bin; 64 px); `visit` "
             "(the default) = one per shading visit (per triangle and tile for tile). Error: bin cycles / visit "
             "cycles - 1 (visit is the detailed reference). Both carry the same work, so each unit's busy cycles are "
             "equal; what moves is how much the units overlap: the bottleneck unit's share of the frame's cycles "
             "(its utilisation, busy / cycles) and the unit whose utilisation moves most. Time: CPU time of render "
             "plus timing model, minimum of interleaved repeats.", "",
             "| scene | size | cycles (bin) | cycles (visit) | error | bottleneck bin / visit | bottleneck share bin / visit | "
             "largest utilisation change | records bin / visit | sim time visit / bin |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in grows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['cycles_bin']:,.0f} | {r['cycles_visit']:,.0f} | {r['err']:+.2%} | "
                     f"{r['bottleneck_bin']} / {r['bottleneck_visit']} | {r['bot_util_bin']:.3f} / {r['bot_util_visit']:.3f} | "
                     f"{r['util_unit']} {r['util_diff']:+.3f} | {r['records_bin']:,} / {r['records_visit']:,} | "
                     f"{r['time_visit'] / r['time_bin']:.2f} |")
    return lines


def summary_lines(srows, crows, draws: int) -> list[str]:
    """Speed-up (CPU, the rendered seeds) against the median error and coverage over the draws, and per
    scene the cheapest fraction whose median errors of ops.total and samples_tested are both under 1%."""
    cov = {(r["scene"], r["fraction"]): r for r in crows}
    lines = ["", f"## Summary: CPU speed-up against median error ({draws} draws) and coverage", "",
             "Speed-up: CPU time of the whole frame / of the sampled render (first table). Error and coverage: the "
             f"coverage table's {draws} draws of the same fraction (the first table's error is a median of a few "
             "seeds only). Aim: at least 10x at under 1% on ops.total and raster.samples_tested.", "",
             "| scene | fraction | speed-up CPU | median |err| ops.total | median |err| samples_tested | "
             "covered ops.total | covered samples_tested | aim met |",
             "|---|---|---|---|---|---|---|---|"]
    best = {}
    for r in srows:
        c = cov.get((r["scene"], r["fraction"]))
        if c is None:
            continue
        e1, e2 = c["err ops.total"], c["err raster.samples_tested"]
        met = r["cpu_speedup"] >= 10 and e1 < 0.01 and e2 < 0.01
        if met and r["scene"] not in best:
            best[r["scene"]] = r["fraction"]
        lines.append(f"| {r['scene']} | {r['fraction']:g} | {r['cpu_speedup']:.1f} | {e1:.2%} | {e2:.2%} | "
                     f"{c['cov ops.total']:.3f} | {c['cov raster.samples_tested']:.3f} | {'yes' if met else 'no'} |")
    lines += ["", "Aim met with whole bins: " + (", ".join(f"{k} at fraction {v:g}" for k, v in best.items()) or "nowhere")
              + "; not met: " + (", ".join(sorted({r['scene'] for r in srows} - set(best))) or "none")
              + " (units smaller than a bin: the table of units below)."]
    return lines


SPLIT = 0.25  # pipeline.sample_split of the units table
SPLIT_FRACTIONS = (0.1, 0.05, 0.03)


def split_table(threads: int, spp: int, quick: bool, bin_size: int, draws: int, fractions=SPLIT_FRACTIONS):
    """Units of the dense bins' triangles (PipelineConfig.sample_split) on modern_hall: per fraction,
    `draws` sampled renders (seeds 0, 1, ...) with units against the whole frame: speed-up (median
    whole-frame CPU over the median sampled CPU; a whole frame rendered before each fraction and every
    50 draws), median |error|, median relative half-width and coverage of ops.total and samples_tested;
    with the same fraction's bin-unit renders (sample_split 0) on the first seeds for the speed-up."""
    import numpy as np

    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    name, scene, w, h = _cases(quick)[-1]
    cam = _camera(scene, w, h, 10.0)
    base = sim.PipelineConfig(algorithm="tile", threads=threads, bin_size=bin_size)
    figs = FIGURES[:2]
    full_runs = [_timed(lambda: sim.render(scene, cam, table, base, timing=False)) for _ in range(2)]
    full = full_runs[-1][0].flat_stats
    rows = []
    for frac in fractions:
        for split, n in ((0.0, min(draws, 10)), (SPLIT, draws)):
            cpus, errs, cis, cov = [], {k: [] for k in figs}, {k: [] for k in figs}, {k: 0 for k in figs}
            r = None
            for seed in range(n):
                if seed % 50 == 0:
                    full_runs.append(_timed(lambda: sim.render(scene, cam, table, base, timing=False)))
                cfg = base.replace(sample_fraction=frac, sample_seed=seed, sample_split=split)
                r, _, cpu = _timed(lambda: sim.render(scene, cam, table, cfg, timing=False))
                cpus.append(cpu)
                for k in figs:
                    errs[k].append(abs(r.flat_stats[k] / full[k] - 1))
                    cis[k].append(r.ci95[k] / full[k])
                    cov[k] += abs(r.flat_stats[k] - full[k]) <= r.ci95[k]
            rows.append(dict(scene=name, size=f"{w}x{h}", fraction=frac, split=split, draws=n,
                             units=int(r.flat_stats["sample.candidates"]), drawn=int(r.flat_stats["sample.bins"]),
                             cpu=float(np.median(cpus)),
                             **{f"err {k}": float(np.median(errs[k])) for k in figs},
                             **{f"ci {k}": float(np.median(cis[k])) for k in figs},
                             **{f"cov {k}": cov[k] / n for k in figs}))
    full_cpu = float(np.median([c for _, _, c in full_runs]))
    for row in rows:
        row["cpu_speedup"] = full_cpu / row["cpu"]
    return rows


def split_lines(rows, spp: int, bin_size: int, threads: int) -> list[str]:
    figs = FIGURES[:2]
    lines = ["", f"## Units smaller than a bin for the dense bins ({spp} spp, tile, CoC 10 px, bin_size {bin_size}, "
             f"{threads} threads)", "",
             f"sample_split {SPLIT:g}: a bin heavier than {SPLIT:g} of a stratum's share of the brute-force work is cut "
             "into units of its triangles, drawn like bins (sim/sampling.py); 0 = the take-all stratum of whole bins. "
             "Every row's draws are sampled renders (seeds 0, 1, ...), so the speed-up, the error and the coverage "
             "come from the same renders. Speed-up: median CPU time of the whole frame (rendered before each row "
             "and every 50 draws) / median CPU time of the row's renders. units: the population drawn from (bins "
             "with triangles, a cut bin counted as its units); drawn: traversed units. covered: share of the draws "
             "whose 95% interval contains the whole-frame value. Under units the counters that depend on depth "
             "order are not estimated (NaN); the aim's figures are sums over visits.", "",
             "| scene | size | fraction | sample_split | draws | units | drawn | speed-up CPU | "
             + " | ".join(f"median |err| {k} | ±95% {k} | covered {k}" for k in figs) + " | aim met |",
             "|---|---|---|---|---|---|---|---|" + "---|---|---|" * len(figs) + "---|"]
    met_at = []
    for r in rows:
        met = r["cpu_speedup"] >= 10 and all(r[f"err {k}"] < 0.01 for k in figs) and \
            r["draws"] >= 200 and all(0.93 <= r[f"cov {k}"] <= 0.97 for k in figs)
        if met:
            met_at.append(f"{r['scene']} {r['size']} at fraction {r['fraction']:g}, sample_split {r['split']:g}")
        lines.append(f"| {r['scene']} | {r['size']} | {r['fraction']:g} | {r['split']:g} | {r['draws']} | {r['units']} | "
                     f"{r['drawn']} | {r['cpu_speedup']:.1f} | "
                     + " | ".join(f"{r['err ' + k]:.2%} | {r['ci ' + k]:.2%} | {r['cov ' + k]:.3f}" for k in figs)
                     + f" | {'yes' if met else 'no'} |")
    lines += ["", "Aim (at least 10x CPU at under 1% median error on both figures, coverage 0.93-0.97 over at least "
              "200 draws) met: " + ("; ".join(met_at) or "nowhere") + "."]
    return lines


def run(threads: int = 2, seeds: int = 5, draws: int = 200, spp: int = 64, bin_size: int = 8, quick: bool = False,
        out=None) -> dict:
    out = reports_dir() / "bench" if out is None else out
    if quick:
        seeds, draws, spp = 3, 50, 16
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    srows = sampling_table(threads, seeds, spp, quick, bin_size)
    crows = coverage_table(spp, quick, bin_size, draws)
    grows = granularity_table(spp, quick)
    xrows = split_table(threads, spp, quick, bin_size, draws)
    lines = ["# bench_sampling: sampled simulation and timing granularity, cost against error", "",
             f"`python -m experiments.bench.bench_sampling` (part of `make bench`), {machine()}, "
             f"load average {load:.1f} at the start. Compare the ratios (measured in "
             "one run), not the seconds; CPU is the process CPU time (all threads, Python included), which other "
             "processes' load disturbs less than wall time.", "",
             f"## Sampled simulation: speed against estimate error ({spp} spp, tile, CoC 10 px, bin_size {bin_size}, "
             f"{threads} threads, {seeds} seeds per fraction)", "",
             "Speed-up: whole-frame time / sampled time (minima over the whole-frame renders, two first and one "
             "before each fraction's seeds, and over the seeds). |err|: median "
             "relative error of the estimated frame total against the whole-frame value; ±95%: median relative "
             "half-width. The fraction is of the bins that hold triangles (bins: all / with triangles; drawn: "
             "traversed, including the take-all stratum). Per render, a bounds pre-pass runs over every triangle "
             "(setup's bounds and culls, nothing charged: each bin's work and the auxiliaries' totals); triangle "
             "setup, binning and the drawn bins' auxiliaries run only for the triangles that reach the drawn bins. "
             "The sample table's (lens cell, time stratum) index is built once per table (SampleTable.engine_index) "
             "and reused by every render here, the whole frame's included. What every fraction still pays: the "
             "projection of every vertex and the rest of sim.render in Python (the estimator's fit included), the "
             "pre-pass, and the take-all stratum's bins.", "",
             "| scene | size | bins | fraction | drawn | speed-up wall | speed-up CPU | |err| ops.total | ±95% ops.total | "
             "|err| samples_tested | ±95% samples_tested | |err| samples_hit | ±95% samples_hit |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in srows:
        lines.append(f"| {r['scene']} | {r['size']} | {r['bins']} | {r['fraction']:g} | {r['drawn']} | {r['speedup']:.1f} | "
                     f"{r['cpu_speedup']:.1f} | " + " | ".join(f"{r['err ' + k]:.2%} | {r['ci ' + k]:.2%}" for k in FIGURES)
                     + " |")
    lines += ["", f"## Coverage of the 95% intervals ({draws} draws per fraction, same frames)", "",
              "One render lists every bin; each draw is the engine's (sim._core.stratify_bins, seeds 0, 1, ...) and "
              "its estimate is sim.sampling.estimate on those bins' counters, so the draws cost no rendering. "
              "covered: share of the draws whose interval contains the whole-frame value (nominal 0.95).", "",
              "| scene | fraction | strata | " + " | ".join(f"covered {k} | median |err| {k}" for k in FIGURES) + " |",
              "|---|---|---|" + "---|---|" * len(FIGURES)]
    for r in crows:
        lines.append(f"| {r['scene']} | {r['fraction']:g} | {r['strata']} | "
                     + " | ".join(f"{r['cov ' + k]:.3f} | {r['err ' + k]:.2%}" for k in FIGURES) + " |")
    lines += summary_lines(srows, crows, draws)
    lines += split_lines(xrows, spp, bin_size, threads)
    lines += granularity_lines(grows, spp)
    page = write_page(out, "bench_sampling.md", lines)
    return {"page": page, "sampling": srows, "coverage": crows, "granularity": grows, "split": xrows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=5, help="sampled renders per fraction")
    ap.add_argument("--draws", type=int, default=200, help="draws per fraction for the coverage table")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--bin-size", type=int, default=8)
    ap.add_argument("--quick", action="store_true", help="small frames, 16 spp, few seeds (a smoke run)")
    ap.add_argument("--out", type=Path, default=reports_dir() / "bench")
    a = ap.parse_args(argv)
    run(a.threads, a.seeds, a.draws, a.spp, a.bin_size, a.quick, a.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

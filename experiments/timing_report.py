"""`python -m experiments.timing_report [CONFIG]`: render the sweep of configs/paper/cycles.yaml and
write reports/timing/cycles.{md,csv,png}: estimated cycles per frame (docs/timing.md) vs CoC and spp
for each algorithm, with the bottleneck unit.

The declarative report (`rast5d report --only cycles`) draws the sweep itself; this script adds
what a sweep cannot express cheaply. It loads the same config (experiments.config), renders every
sweep point once and, because the timing model runs on stored work records, re-times every render on
a few hardware variants (sim.timing.estimate on Result.timing_records) without rendering again; then
it checks the estimate's sensitivity to the record granularity (bin size) and the FIFO depth.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from sim.timing import UNITS

from .config import REPO, build, deep_merge, expand_sweep, load_config, load_dict

OUT = REPO / "reports" / "timing"
# Re-timed on the same records: what changes when one resource is scaled.
VARIANTS = {
    "default": {},
    "memory x4 (128 B/clk)": {"memory_bytes_per_clock": 128.0},
    "sample lanes x4 (256)": {"sample_test": {"throughput": 256.0}},
}


def _points(config_path: Path) -> list[tuple[dict, object]]:
    """[(point, RenderConfig)] for every sweep point of the config (experiments.config)."""
    return expand_sweep(load_config(config_path), str(config_path))


def run(config_path: Path) -> "pd.DataFrame":  # noqa: F821
    import pandas as pd

    import sim

    rows = []
    points = _points(config_path)
    t0 = time.perf_counter()
    for i, (point, cfg) in enumerate(points):
        scene, camera, table, pipeline = build(cfg)
        hw = cfg.hardware_config()
        hw_dict = hw.describe()
        res = sim.render(scene, camera, table, pipeline, hardware=hw)
        for variant, change in VARIANTS.items():
            vhw = sim.HardwareConfig.from_dict(deep_merge(hw_dict, change))
            timing = res.flat_stats if not change else sim.timing.estimate(res.timing_records, vhw)
            row = {"variant": variant, **point, "spp": table.spp, "coc_px": camera.coc_px,
                   "algorithm": pipeline.algorithm}
            row.update({k: v for k, v in res.flat_stats.items() if not k.startswith("timing.")})
            row.update({k: v for k, v in timing.items() if k.startswith("timing.")})
            rows.append(row)
        print(f"  [{i + 1}/{len(points)}] {point}: {res.flat_stats['timing.cycles'] / 1e6:.3f} Mcycles, "
              f"bottleneck {res.flat_stats['timing.bottleneck']}, wall {res.flat_stats['time.wall_s']:.2f} s",
              flush=True)
    print(f"{len(points)} renders in {time.perf_counter() - t0:.0f} s")
    return pd.DataFrame(rows)


def sensitivity(config_path: Path) -> list[str]:
    """Two checks of the model on one point (tile, CoC 10, 16 spp): record granularity (bin size,
    re-rendered) and FIFO depth (every FIFO set to one depth, re-timed on the same records)."""
    import sim

    cfg = load_config(config_path, ["sweep={}", "camera.coc_px=10", "samples.spp=16", "pipeline.algorithm=tile"])
    hw_dict = cfg.hardware_config().describe()
    lines = ["## Sensitivity (tile, CoC 10, 16 spp)", "",
             "Record granularity: records are (triangle, screen bin) visits, so the bin size sets how "
             "lumpy the work is (the engine's counters do not change with it).", "",
             "| bin size [px] | records | Mcycles | bottleneck | cycles / bound |", "|---|---|---|---|---|"]
    base = None
    scene, camera, table, pipeline = build(cfg)
    hardware = cfg.hardware_config()
    for bin_size in (8, 16, 32, 64, 128):
        res = sim.render(scene, camera, table, pipeline.replace(bin_size=bin_size), hardware=hardware)
        st = res.flat_stats
        lines.append(f"| {bin_size} | {st['timing.records']:,} | {st['timing.cycles'] / 1e6:.3f} | "
                     f"{st['timing.bottleneck']} | {st['timing.bound_ratio']:.3f} |")
        if bin_size == 64:
            base = res
    lines += ["", "FIFO depth (every unit's FIFO, re-timed on the 64-px records; default hardware otherwise, "
              "and with memory x4 so that the compute units limit):", "",
              "| FIFO entries | Mcycles | bottleneck | cycles / bound | Mcycles, memory x4 | bottleneck | cycles / bound |",
              "|---|---|---|---|---|---|---|"]
    for depth in (1, 2, 4, 8, 16, 64, 256):
        cells = []
        for extra in ({}, {"memory_bytes_per_clock": 128.0}):
            fifos = {u: {"fifo_entries": depth} for u in UNITS if u != "memory"}
            hw = deep_merge(hw_dict, {**extra, "memory_fifo_entries": depth, **fifos})
            t = sim.timing.estimate(base.timing_records, sim.HardwareConfig.from_dict(hw))
            cells += [f"{t['timing.cycles'] / 1e6:.3f}", t["timing.bottleneck"], f"{t['timing.bound_ratio']:.3f}"]
        lines.append(f"| {depth} | " + " | ".join(cells) + " |")
    return lines + [""]


def _table(df, variant: str, spp: int) -> list[str]:
    sub = df[(df["variant"] == variant) & (df["spp"] == spp)]
    algos = list(dict.fromkeys(sub["algorithm"]))
    cocs = sorted(set(sub["coc_px"]))
    lines = ["| algorithm | " + " | ".join(f"CoC {c:g}" for c in cocs) + " |", "|---|" + "---|" * len(cocs)]
    for a in algos:
        cells = []
        for c in cocs:
            r = sub[(sub["algorithm"] == a) & (sub["coc_px"] == c)].iloc[0]
            cells.append(f"{r['timing.cycles'] / 1e6:.3f} **{r['timing.bottleneck']}** ({r['timing.bound_ratio']:.2f})")
        lines.append(f"| {a} | " + " | ".join(cells) + " |")
    return lines


def write(df, config_path: Path, out: Path = OUT, extra: list[str] = ()) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "cycles.csv", index=False)
    spps = sorted(set(df["spp"]))
    d0 = df[df["variant"] == "default"]
    plotted = list(VARIANTS)[:2]  # default, and memory x4 where the compute units limit
    fig, axes = plt.subplots(len(plotted), len(spps), figsize=(5.5 * len(spps), 3.8 * len(plotted)), squeeze=False)
    markers = dict(zip(UNITS, "v^os*Dx"))
    for row, variant in zip(axes, plotted):
        dv = df[df["variant"] == variant]
        for ax, spp in zip(row, spps):
            for algo in dict.fromkeys(dv["algorithm"]):
                s = dv[(dv["spp"] == spp) & (dv["algorithm"] == algo)].sort_values("coc_px")
                line, = ax.plot(s["coc_px"], s["timing.cycles"] / 1e6, label=algo)
                for _, r in s.iterrows():
                    ax.plot(r["coc_px"], r["timing.cycles"] / 1e6, markers.get(r["timing.bottleneck"], "."),
                            color=line.get_color(), ms=7)
            ax.set_xlabel("CoC [px]")
            ax.set_ylabel("estimated Mcycles per frame")
            ax.set_title(f"{variant}, {spp} spp (marker = bottleneck: x memory, o sample_test, ^ tile_test)",
                         fontsize=8)
            ax.legend(fontsize=8)
            ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "cycles.png", dpi=110)
    plt.close(fig)
    rel = config_path.relative_to(REPO) if config_path.is_relative_to(REPO) else config_path
    lines = ["# Estimated cycles per frame vs CoC and spp (timing model)", "",
             f"Made by `python -m experiments.timing_report {rel}` (the declarative page of the same "
             "config is reports/paper/cycles.md; this one adds hardware variants and sensitivity checks).", "",
             load_dict(config_path)[0].get("outputs", {}).get("text", "").strip(), "",
             "Each cell: estimated **Mcycles** per frame, the **bottleneck** unit (most busy clocks) and, in "
             "parentheses, cycles / throughput bound (1.00 = the bottleneck unit is busy the whole frame).",
             "The hardware variants re-time the same work records (no re-render).", "",
             "![cycles](cycles.png)", ""]
    for variant in VARIANTS:
        for spp in spps:
            lines += [f"## {variant}, {spp} spp", ""] + _table(df, variant, spp) + [""]
    # Busy clocks per unit for the default hardware: where the time goes.
    lines += ["## Busy Mcycles per unit (default hardware)", "",
              "| spp | algorithm | CoC | samples tested | STE | setup | tile_test | sample_test | depth | memory | cycles |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in d0.sort_values(["spp", "algorithm", "coc_px"]).iterrows():
        lines.append(f"| {r['spp']} | {r['algorithm']} | {r['coc_px']:g} | {r['raster.samples_tested']:,} | "
                     f"{r['raster.ste']:.3f} | " + " | ".join(
                         f"{r[f'timing.{u}.busy_cycles'] / 1e6:.3f}" for u in
                         ("setup", "tile_test", "sample_test", "depth", "memory")) +
                     f" | {r['timing.cycles'] / 1e6:.3f} |")
    lines += ["", *extra]
    (out / "cycles.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {(out / 'cycles.md').relative_to(REPO)}, cycles.csv, cycles.png")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default=str(REPO / "configs" / "paper" / "cycles.yaml"))
    parser.add_argument("--out", default=str(OUT))
    args = parser.parse_args(argv)
    path = Path(args.config).resolve()
    df = run(path)
    write(df, path, Path(args.out), sensitivity(path))
    return 0


if __name__ == "__main__":
    sys.exit(main())

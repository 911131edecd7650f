"""`make bench`: CPU time of the report's most expensive kinds of point, against a second engine.

Each row is one point of a paper config (configs/paper/*.yaml; a reference image of an image metric
when marked so): the kinds that dominate `rast5d report`'s CPU time (reports/bench/bench_report.md):
the interleaved algorithms on 256 lens positions, `tile` with the exact optimum counted (Table 1),
the half-space variants and `interval` on large blur, brute force at high spp. Every point renders
in its own process, one thread, timing model off (the image and the counters only), and its CPU
time (``time.process_time``) is the minimum over the rounds.

With ``--base-core PATH`` (a built ``sim._core`` module of another engine with the same Python
binding, e.g. of an earlier commit: ``git worktree add /tmp/base <rev> && make -C /tmp/base install``;
the module is loaded under this checkout's ``sim`` package) the rounds alternate
processes of that engine and of this one (base, this, base, this, ...), so load from other
processes shifts both alike, and the page gives CPU this / base per point and whether the image and
every counter are the same (a hash of the image and of every counter but wall time).

Writes reports/bench/bench_report_points.md. `python -m experiments.bench.bench_report_points --help`."""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from experiments.bench import write_page

REPO = Path(__file__).resolve().parents[2]
from experiments.paths import bundled_configs, reports_dir, results_dir  # noqa: E402,F401

# (config, sweep point selected by these values, reference image of the point instead of the point)
POINTS = (
    ("fig16_interleaved", {"pipeline.algorithm": "interleave", "samples.spp": 64, "pipeline.cost_model": "robust"}, False),
    ("fig16_interleaved", {"pipeline.algorithm": "hinterleave", "samples.spp": 64, "pipeline.cost_model": "hardware"}, False),
    ("fig16_interleaved", {"pipeline.algorithm": "tile_interleaved", "samples.spp": 256, "pipeline.cost_model": "robust"}, False),
    ("fig15_interleaved", {"scene": "spot", "pipeline.algorithm": "interleave", "camera.coc_px": 20}, False),
    ("table1", {"scene": "mixed_sizes", "camera.coc_px": 10, "pipeline.cost_model": "robust"}, False),
    ("table1", {"scene": "modern_hall", "camera.coc_px": 50, "pipeline.cost_model": "robust"}, False),
    ("table2", {"scene": "mixed_sizes", "camera.coc_px": 50, "pipeline.algorithm": "tile",
                "pipeline.halfspace": {"h": True, "H": True}, "pipeline.cost_model": "robust"}, False),
    ("table2", {"scene": "modern_hall", "camera.coc_px": 50, "pipeline.algorithm": "interval", "pipeline.cost_model": "robust"}, False),
    ("fig16", {"pipeline.algorithm": "bruteforce", "samples.spp": 64, "pipeline.cost_model": "robust"}, False),
    ("motion5d", {"scene": "motion_field", "camera.coc_px": 30, "pipeline.algorithm": "tile",
                  "pipeline.time_splits": 4, "pipeline.halfspace": {"h": True, "H": True, "H5": True}}, False),
    ("methods", {"scene": "teapot", "camera.coc_px": 40, "pipeline.algorithm": "interleave", "samples.spp": 256}, False),
    ("methods", {"scene": "teapot", "camera.coc_px": 40, "pipeline.algorithm": "bruteforce", "samples.spp": 16}, True),
)


def _value(v):
    return v.get("name", v) if isinstance(v, dict) and "name" in v else v


def _matches(point: dict, want: dict) -> bool:
    for k, v in want.items():
        got = _value(point.get(k))
        if isinstance(v, dict):
            if not isinstance(got, dict) or any(got.get(kk) != vv for kk, vv in v.items()):
                return False
        elif got != v:
            return False
    return True


def label(config: str, want: dict, reference: bool) -> str:
    text = ", ".join(f"{k.split('.')[-1]} {_value(v) if not isinstance(v, dict) else json.dumps(v)}"
                     for k, v in want.items())
    return f"{config}: {'reference of ' if reference else ''}{text}"


def _point_config(config: str, want: dict, reference: bool):
    from experiments.config.load import load_config
    from experiments.config.sweep import expand_sweep
    from experiments.run.references import reference_config

    found = [pc for point, pc in expand_sweep(load_config(bundled_configs() / "paper" / f"{config}.yaml"))
             if _matches(point, want)]
    if not found:
        raise ValueError(f"{config}: no sweep point matches {want}")
    return reference_config(found[0]) if reference else found[0]


def measure_points(points=POINTS) -> dict:
    """{label: {cpu, hash, ops}}: each point rendered once in this process (one thread, no timing)."""
    import numpy as np

    import sim
    from experiments.config import build

    out = {}
    for config, want, reference in points:
        pc = _point_config(config, want, reference)
        scene, camera, table, pipeline = build(pc)
        pipeline = pipeline.replace(threads=1)
        c0 = time.process_time()
        r = sim.render(scene, camera, table, pipeline, hardware=pc.hardware_config(), timing=False)
        cpu = time.process_time() - c0
        stats = {k: v for k, v in r.flat_stats.items() if not k.startswith("time.")}
        digest = hashlib.sha1(np.ascontiguousarray(r.image).tobytes()
                              + json.dumps(stats, sort_keys=True, default=str).encode()).hexdigest()[:16]
        out[label(config, want, reference)] = {"cpu": cpu, "hash": digest, "ops": stats.get("ops.total")}
    return out


def _load_core(path: str) -> None:
    """Import ``sim._core`` from path instead of the installed module (before sim is imported)."""
    import importlib.util

    class _Finder:
        @staticmethod
        def find_spec(name, p=None, target=None):
            if name == "sim._core":
                return importlib.util.spec_from_file_location(name, path)
            return None

    sys.meta_path.insert(0, _Finder)


def _worker_run(core: str | None) -> dict:
    cmd = [sys.executable, "-m", "experiments.bench.bench_report_points", "--worker"]
    if core:
        cmd += ["--core", core]
    done = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    if done.returncode != 0:
        tail = "\n".join(done.stderr.strip().splitlines()[-3:])
        raise RuntimeError(f"the {'base engine ' + repr(core) if core else 'engine'}'s worker failed (a base "
                           f"engine must have this checkout's Python binding):\n{tail}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run(base_core: str | None = None, rounds: int = 2, out: Path | None = None, base_label: str = "") -> dict:
    """Alternate worker processes (base engine, this engine) for ``rounds`` rounds; write the page."""
    out = Path(out) if out is not None else reports_dir() / "bench"
    engines = (["base"] if base_core else []) + ["this"]
    best: dict[str, dict] = {e: {} for e in engines}
    loads = []
    t0 = time.time()
    for r in range(rounds):
        for e in engines:
            loads.append(os.getloadavg()[0])
            got = _worker_run(base_core if e == "base" else None)
            for k, v in got.items():
                prev = best[e].get(k)
                if prev is not None and prev["hash"] != v["hash"]:
                    raise RuntimeError(f"{k}: two renders of the same engine differ")
                if prev is None or v["cpu"] < prev["cpu"]:
                    best[e][k] = v
            print(f"round {r + 1} {e}: " + ", ".join(f"{v['cpu']:.2f}" for v in got.values()), flush=True)
    rows = []
    for config, want, reference in POINTS:
        k = label(config, want, reference)
        row = {"point": k, "cpu": best["this"][k]["cpu"], "ops": best["this"][k]["ops"]}
        if base_core:
            b = best["base"][k]
            row.update(base_cpu=b["cpu"], ratio=row["cpu"] / b["cpu"], same=b["hash"] == best["this"][k]["hash"])
        rows.append(row)
    lines = ["# The report's most expensive points: engine CPU time", "",
             "Generated by `python -m experiments.bench.bench_report_points"
             + (" --base-core PATH" if base_core else "") + f" --rounds {rounds}`. Machine: {platform.machine()}, "
             f"{os.cpu_count()} cores, load average {min(loads):.1f}-{max(loads):.1f} (1 min) during the run; "
             f"{time.time() - t0:.0f} s wall." + (f" Base engine: {base_label}." if base_core and base_label else ""), "",
             "Each row is one point of a paper config (or the reference image of its image metric): one engine "
             "thread, timing model off, CPU time of `sim.render` in its own process, minimum over the rounds"
             + (", the two engines' processes alternating (ratios measured in one run). *same*: the image and "
                "every counter (all but wall time) hash alike under both engines." if base_core else "."), ""]
    if base_core:
        lines += ["| point | ops [G] | CPU base [s] | CPU [s] | CPU / base | same |", "|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['point']} | {r['ops'] / 1e9:.2f} | {r['base_cpu']:.3f} | {r['cpu']:.3f} | "
                         f"{r['ratio']:.2f} | {'yes' if r['same'] else 'NO'} |")
        tb, tn = sum(r["base_cpu"] for r in rows), sum(r["cpu"] for r in rows)
        lines += ["", f"All rows: {tb:.1f} CPU-s base, {tn:.1f} CPU-s this engine ({tn / tb:.2f}x); "
                  f"images and counters the same in {sum(r['same'] for r in rows)} of {len(rows)} rows."]
    else:
        lines += ["| point | ops [G] | CPU [s] |", "|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['point']} | {r['ops'] / 1e9:.2f} | {r['cpu']:.3f} |")
    page = write_page(out, "bench_report_points.md", lines)
    return {"rows": rows, "page": page}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base-core", help="a built sim._core module to compare against (alternating processes)")
    ap.add_argument("--base-label", default="", help="what the base engine is (a line on the page)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out", default=None, help="folder of the page (default reports/bench)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--core", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        if a.core:
            _load_core(a.core)
        print(json.dumps(measure_points()))
        return 0
    run(a.base_core, a.rounds, a.out, a.base_label)
    return 0


if __name__ == "__main__":
    sys.exit(main())

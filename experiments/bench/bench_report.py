"""The whole `rast5d report`'s cost: run it into an empty temporary result store and record, per
config, the CPU seconds of the points it computed and its wall time, and for the whole run the CPU
seconds (RUSAGE_SELF + RUSAGE_CHILDREN), the wall time, the load average meanwhile and the ideal wall
time on N idle cores (max of total CPU / N and the longest single job). Writes
reports/bench/bench_report.md (or --out).

    python -m experiments.bench.bench_report [--workers 2] [--only CONFIG_OR_PAGE ...] [--out PAGE]

On a shared machine the wall time depends on the load; the CPU seconds and the ideal wall do not
(much). The pages are written into a temporary folder, never over reports/.
"""
from __future__ import annotations

from experiments.paths import bundled_configs, reports_dir, results_dir  # noqa: E402,F401

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path

_POINT_LOG = "RAST5D_BENCH_POINT_LOG"


def _cpu(kind) -> float:
    r = resource.getrusage(kind)
    return r.ru_utime + r.ru_stime


_RENDER_CPU = [0.0]  # CPU seconds inside sim.render in this process (_count_render)
_STARTED = [False]
_REFERENCE_CPU = [0.0]  # CPU seconds of reference images rendered in this process (counted as their jobs)


def _count_render():
    """Wrap sim.render (and the name the point kinds call) to add its CPU seconds to _RENDER_CPU."""
    import sim

    from experiments.run import points  # noqa: F401 - imports sim.render's callers

    if getattr(sim.render, "_bench_counted", False):
        return
    real = sim.render

    def render(*a, **k):
        c0 = time.process_time()
        try:
            return real(*a, **k)
        finally:
            _RENDER_CPU[0] += time.process_time() - c0

    render._bench_counted = True
    sim.render = render


def _timed_run_point(config_json, *args, **kwargs):
    """run_point in a worker, logging the point's CPU and wall seconds, the CPU inside sim.render, and
    for the first point of a worker the CPU it spent before (start-up, imports): one JSON line per point."""
    from experiments.run import points

    startup = None
    if not _STARTED[0]:
        _STARTED[0] = True
        # a forked worker's CPU clock starts at 0: its start-up, less the reference jobs it ran first
        startup = time.process_time() - _REFERENCE_CPU[0]
        _count_render()
    r0 = _RENDER_CPU[0]
    c0, t0 = time.process_time(), time.perf_counter()
    row = points.run_point(config_json, *args, **kwargs)
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    path = os.environ.get(_POINT_LOG)
    if path:
        rec = {"name": json.loads(config_json).get("name"), "hash": row.get("config_hash"), "cpu": cpu,
               "wall": wall, "status": row.get("status"), "kind": "point", "render_cpu": _RENDER_CPU[0] - r0,
               "pid": os.getpid(), **({"startup_cpu": startup} if startup is not None else {})}
        with open(path, "a") as f:
            f.write(json.dumps(rec) + "\n")
    return row


def _instrument(log: list, point_log: Path):
    """Wrap the report's sweep runner, the pool's point function and the reference renderer."""
    from experiments.report import pages
    from experiments.run import executors, references

    from experiments.bench import bench_report  # by its module name (not __main__), for the pool's pickling

    executors.run_point = bench_report._timed_run_point  # the forked workers inherit the wrapper
    try:
        from experiments.run import schedule

        schedule.run_point = bench_report._timed_run_point
    except ImportError:  # a tree without the one-pool pass
        pass
    orig_sweep, orig_ref = pages.run_sweep, references.reference_image

    def sweep(config, **kw):
        c0 = _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN)
        t0, th0 = time.perf_counter(), time.thread_time()
        df = orig_sweep(config, **kw)
        log.append({"config": config.name, "page": config.outputs.page or config.name, "points": len(df),
                    "summary": df.attrs.get("summary", {}), "wall": time.perf_counter() - t0,
                    "cpu_rusage": _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN) - c0,
                    "sweep_thread_cpu": time.thread_time() - th0, "load": os.getloadavg()[0]})
        return df

    def reference(config, threads=None):
        c0, t0 = time.process_time(), time.perf_counter()
        path = references._reference_path(references.reference_config(config))
        existed = path.exists()
        image = orig_ref(config, threads)
        if not existed:
            cpu = time.process_time() - c0
            bench_report._REFERENCE_CPU[0] += cpu
            with open(point_log, "a") as f:
                f.write(json.dumps({"name": config.name, "hash": path.name, "cpu": cpu,
                                    "wall": time.perf_counter() - t0, "kind": "reference",
                                    "spp": config.outputs.metrics.reference_spp,
                                    "threads": threads}) + "\n")
        return image

    orig_section = pages.section_markdown

    def section(config, *a, **kw):
        # page_cpu: the parent process (its engine threads re-rendering pictures included, and the
        # pool thread's store writes meanwhile); page_thread_cpu: the thread writing the section alone.
        c0, th0, r0 = _cpu(resource.RUSAGE_SELF), time.thread_time(), bench_report._RENDER_CPU[0]
        out = orig_section(config, *a, **kw)
        for c in log[::-1]:
            if c["config"] == config.name:
                c["page_cpu"] = _cpu(resource.RUSAGE_SELF) - c0
                c["page_thread_cpu"] = time.thread_time() - th0
                c["page_render_cpu"] = bench_report._RENDER_CPU[0] - r0
                break
        return out

    pages.run_sweep = sweep
    pages.section_markdown = section
    # the parent's renders (pictures drawn without a stored one); forked workers inherit the wrapper.
    # By the module's name: run as a script, this file is also __main__, whose counter no worker sees.
    bench_report._count_render()
    references.reference_image = reference


def _load_sampler(samples: list, stop: threading.Event, every: float = 10.0):
    while not stop.wait(every):
        samples.append(os.getloadavg()[0])


_PROBE = """
import time, models, sim
scene = models.named("bunny")
cam = sim.Camera.for_scene(scene, width=512, height=512, coc_px=10)
table = sim.SampleTable.create("stratified", spp=64, seed=1)
pipe = sim.PipelineConfig(algorithm="tile", threads=1)
best = []
for _ in range(5):
    c0 = time.process_time()
    sim.render(scene, cam, table, pipe, timing=False)
    best.append(time.process_time() - c0)
print(min(best))
"""


def machine_probe() -> float | None:
    """CPU seconds of one fixed render (the bunny, 512x512, CoC 10, 64 spp, `tile`, one thread, timing
    off; the least of five) in a fresh process: the machine's speed at the time, so that runs made
    at different times (a shared machine's speed varies) can be compared."""
    r = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True)
    try:
        return float(r.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only", nargs="*", default=None, help="configs or pages (default: the whole report)")
    ap.add_argument("--out", default=None, help="the page to write (default reports/bench/bench_report.md)")
    ap.add_argument("--json", default=None, help="also write the raw records here")
    ap.add_argument("--label", default="", help="a line saying what was measured (a state, not a revision: committed pages carry no revision)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary store and pages")
    ap.add_argument("--compare", default=None,
                    help="the --json of an earlier run (another code revision): a per-config table of both")
    args = ap.parse_args(argv)

    tmp = Path(tempfile.mkdtemp(prefix="rast5d_bench_report_"))
    os.environ["RAST5D_RESULTS"] = str(tmp / "results")
    point_log = tmp / "points.jsonl"
    os.environ[_POINT_LOG] = str(point_log)
    from experiments.config import REPO
    from experiments.report import pages

    log: list = []
    _instrument(log, point_log)
    loads: list = [os.getloadavg()[0]]
    stop = threading.Event()
    sampler = threading.Thread(target=_load_sampler, args=(loads, stop), daemon=True)
    sampler.start()
    probe = [machine_probe()]
    c0 = _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    started = time.strftime("%Y-%m-%d %H:%M:%S")
    rc = pages.main(only=args.only, workers=args.workers, reports_dir=tmp / "reports")
    wall = time.perf_counter() - t0
    cpu = _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN) - c0
    stop.set()
    probe.append(machine_probe())
    loads.append(os.getloadavg()[0])
    jobs = [json.loads(line) for line in point_log.read_text().splitlines()] if point_log.exists() else []
    if args.json:
        Path(args.json).write_text(json.dumps({"configs": log, "jobs": jobs, "cpu": cpu, "wall": wall,
                                               "loads": loads, "rc": rc, "probe": probe, "started": started,
                                               "label": args.label}, indent=1))
    lines = _page(log, jobs, cpu, wall, loads, args, started, rc, probe)
    if args.compare:
        lines += compare(json.loads(Path(args.compare).read_text()), {"configs": log, "jobs": jobs, "cpu": cpu})
    from experiments.bench import write_page

    out = Path(args.out) if args.out else reports_dir() / "bench" / "bench_report.md"
    write_page(out.parent, out.name, lines)
    if args.keep:
        print(f"kept {tmp}")
    else:
        shutil.rmtree(tmp, ignore_errors=True)
    return rc


def _page(log, jobs, cpu, wall, loads, args, started, rc, probe=(None, None)) -> list[str]:
    from experiments.report.tables import md_table

    n = args.workers
    empty = {"cpu": 0.0, "n": 0, "max": 0.0, "refs": 0.0, "n_refs": 0, "render": 0.0}
    by_cfg = defaultdict(lambda: dict(empty))
    for j in jobs:
        d = by_cfg[j["name"]]
        if j["kind"] == "reference":
            d["refs"] += j["cpu"]
            d["n_refs"] += 1
        else:
            d["cpu"] += j["cpu"]
            d["n"] += 1
            d["max"] = max(d["max"], j["cpu"])
            d["render"] += j.get("render_cpu", 0.0)
    rows = []
    pages = defaultdict(lambda: {"configs": 0, "jobs": 0, "cpu": 0.0, "section": 0.0, "thread": 0.0, "render": 0.0})
    seen = set()
    for c in log:
        d = by_cfg.get(c["config"], empty)
        seen.add(c["config"])
        pg = pages[c["page"]]
        pg["configs"] += 1
        pg["jobs"] += d["n"] + d["n_refs"]
        pg["cpu"] += d["cpu"] + d["refs"]
        pg["section"] += c.get("page_cpu", 0.0)
        pg["thread"] += c.get("page_thread_cpu", 0.0)
        pg["render"] += c.get("page_render_cpu", 0.0)
        rows.append([c["config"], c["page"], c["points"], d["n"], f"{d['cpu']:.1f}",
                     f"{d['refs']:.1f} ({d['n_refs']})" if d["n_refs"] else "", f"{d['max']:.1f}",
                     f"{c['cpu_rusage']:.1f}", f"{c.get('sweep_thread_cpu', 0.0):.1f}", f"{c['wall']:.1f}",
                     f"{c.get('page_cpu', 0.0):.1f}", f"{c.get('page_thread_cpu', 0.0):.1f}",
                     f"{c.get('page_render_cpu', 0.0):.1f}", f"{c['load']:.1f}"])
    for name, d in by_cfg.items():  # jobs of a config with no sweep of its own in this run
        if name not in seen:
            rows.append([name, "", "", d["n"], f"{d['cpu']:.1f}", f"{d['refs']:.1f} ({d['n_refs']})"
                         if d["n_refs"] else "", f"{d['max']:.1f}", "", "", "", "", "", "", ""])
            pg = pages[f"({name})"]
            pg["jobs"] += d["n"] + d["n_refs"]
            pg["cpu"] += d["cpu"] + d["refs"]
    job_cpu = sum(j["cpu"] for j in jobs)
    points = [j for j in jobs if j["kind"] == "point"]
    render_cpu = sum(j.get("render_cpu", 0.0) for j in points)
    startup = [j["startup_cpu"] for j in points if "startup_cpu" in j]
    page_cpu = sum(c.get("page_cpu", 0.0) for c in log)
    page_thread = sum(c.get("page_thread_cpu", 0.0) for c in log)
    page_render = sum(c.get("page_render_cpu", 0.0) for c in log)
    sweep_thread = sum(c.get("sweep_thread_cpu", 0.0) for c in log)
    longest = max(jobs, key=lambda j: j["cpu"]) if jobs else None
    ideal = max(cpu / n, longest["cpu"] if longest else 0.0)
    out = ["# The whole report's time", "",
           "Generated by `python -m experiments.bench.bench_report"
           + (f" --only {' '.join(args.only)}" if args.only else "") + f" --workers {n}`: "
           "`rast5d report` run into an empty temporary result store (pages into a temporary folder), "
           f"started {started}." + (f" {args.label}" if args.label else ""), "",
           f"- CPU, whole run (RUSAGE_SELF + RUSAGE_CHILDREN): **{cpu:.0f} s**; of it in computed points and "
           f"reference images (per job, in the process that ran it): {job_cpu:.0f} s over {len(jobs)} jobs",
           f"- per point job outside sim.render (config validation and hashing, the point's other computing, "
           f"metrics, records and pictures; the parent stores the row): {job_cpu - render_cpu - sum(j['cpu'] for j in jobs if j['kind'] == 'reference'):.1f} s "
           f"over {len(points)} points ({(sum(j['cpu'] - j.get('render_cpu', 0.0) for j in points)) / max(1, len(points)) * 1e3:.0f} ms each); "
           f"worker start-up before its first point (the reference images it rendered first not included): "
           f"{sum(startup):.1f} s over {len(startup)} workers",
           f"- the parent process, writing the page sections: {page_cpu:.0f} s (figures and tables in the "
           f"writing thread: {page_thread:.0f} s; pictures rendered there because the store had none: "
           f"{page_render:.0f} s); reading each sweep's rows from the store and waiting for them: "
           f"{sweep_thread:.0f} s; the rest (loading configs, hashing points, the pool's thread: storing rows, "
           f"starting workers): {cpu - job_cpu - page_cpu - sweep_thread:.0f} s",
           f"- ideal wall on {n} idle cores, max(CPU / {n}, longest job): **{ideal:.0f} s** "
           f"({ideal / 60:.1f} min)" + (f"; longest job: {longest['cpu']:.1f} CPU-s ({longest['kind']} of "
                                        f"`{longest['name']}`)" if longest else ""),
           f"- real wall: {wall:.0f} s ({wall / 60:.1f} min) at load average {min(loads):.1f}-{max(loads):.1f} "
           f"(mean {sum(loads) / len(loads):.1f}; 1-minute load sampled every 10 s, machine has "
           f"{os.cpu_count()} cores); exit code {rc}",
           "- the machine's speed (machine_probe: CPU of one fixed render, the bunny at 512x512, CoC 10, 64 spp, "
           "`tile`, one thread, timing off, the least of five): "
           + " before the run, ".join(f"{p:.3f} s" if p is not None else "not measured" for p in probe)
           + " after it", "",
           "Per config, in the order the report runs them. *points CPU*: CPU seconds of the points this "
           "config computed (a point shared with an earlier config is computed once, by the first); "
           "*references*: CPU seconds of the reference images rendered for its image metrics (count); "
           "*longest*: its most expensive point; *sweep CPU / thread / wall*: RUSAGE_SELF + CHILDREN, the "
           "parent thread's CPU and wall seconds around its sweep (with one pool over all configs most work "
           "happens in the pool; the sweep reads the store and waits); *section CPU*: writing its section "
           "in the parent (process CPU; *thread*: the writing thread alone; *renders*: pictures rendered "
           "there).", ""]
    out += md_table(["config", "page", "points", "computed", "points CPU [s]", "references CPU [s]",
                     "longest [s]", "sweep CPU [s]", "sweep thread [s]", "sweep wall [s]", "section CPU [s]",
                     "section thread [s]", "section renders [s]", "load"], rows)
    out += ["", "Per page: its configs' jobs (points and references) and the parent's CPU writing its sections.", ""]
    out += md_table(["page", "configs", "jobs", "jobs CPU [s]", "section CPU [s]", "section thread [s]",
                     "section renders [s]"],
                    [[p, v["configs"], v["jobs"], f"{v['cpu']:.1f}", f"{v['section']:.1f}", f"{v['thread']:.1f}",
                      f"{v['render']:.1f}"] for p, v in sorted(pages.items(), key=lambda t: -(t[1]["cpu"] + t[1]["section"]))])
    return out


def _job_cpu(run) -> dict:
    out = defaultdict(float)
    for j in run["jobs"]:
        out[j["name"]] += j["cpu"]
    return out


def compare(before: dict, after: dict) -> list[str]:
    """Per config: the CPU seconds of its points and references in an earlier run and in this one."""
    from experiments.report.tables import md_table

    b, a = _job_cpu(before), _job_cpu(after)
    pages = {c["config"]: c["page"] for c in after["configs"]}
    rows = []
    for name in sorted(set(a) | set(b), key=lambda n: -max(a.get(n, 0.0), b.get(n, 0.0))):
        rows.append([name, pages.get(name, ""), f"{b[name]:.1f}" if name in b else "not measured",
                     f"{a[name]:.1f}" if name in a else "", f"{a.get(name, 0.0) / b[name]:.2f}"
                     if b.get(name) else ""])
    both = [n for n in a if n in b]
    sb, sa = sum(b[n] for n in both), sum(a[n] for n in both)
    said = before.get("label") or "no label"
    when = f"started {before['started']}" if before.get("started") else "start time not recorded"
    return ["", "## Against an earlier run", "", f"The earlier run: {said} ({when}).", "",
            f"Configs measured in both: {len(both)}; their points and references: {sb:.0f} CPU-s before, "
            f"{sa:.0f} after ({sa / sb:.2f}x). Whole earlier run: {before.get('cpu', float('nan')):.0f} CPU-s "
            f"(RUSAGE) for {len(b)} configs, {before.get('cpu', 0.0) - sum(b.values()):.0f} of them outside "
            "the points (worker start-up per sweep, pages, configs).", ""] + md_table(
        ["config", "page", "before: points CPU [s]", "after [s]", "after / before"], rows)


if __name__ == "__main__":
    sys.exit(main())

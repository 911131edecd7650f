"""The `rast5d` command line: render one config (or one point of a sweep), run a sweep into the result
store, regenerate the report pages, list the registries, copy the shipped configs to edit.

Results go to ./results under the working directory (--results DIR or RAST5D_RESULTS moves them);
`rast5d report` writes its pages to ./reports (--reports DIR). Nothing is written inside the installed
package."""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path


LIST_KINDS = ("algorithms", "scenes", "counters", "configs")


def _missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def figure(row: dict, key: str, digits: int | None = None) -> str:
    """A figure of a result row as a user reads it: a counter as an integer (a sampled render's estimate
    rounded, with its 95% interval: '1,234,000 ± 5,600'), a ratio with ``digits`` decimals."""
    v, ci = row.get(key), row.get(f"{key}.ci95")
    if _missing(v):
        return "n/a"
    if digits is None:
        text = f"{round(float(v)):,}"
        return text + (f" ± {round(float(ci)):,}" if not _missing(ci) else "")
    text = f"{float(v):,.{digits}f}"
    return text + (f" ± {float(ci):,.{digits}f}" if not _missing(ci) else "")


def _sampled(row: dict) -> str:
    if _missing(row.get("sample.bins")) or _missing(row.get("sample.candidates")):
        return ""
    share = row.get("pipeline.sample_fraction")
    split = row.get("pipeline.sample_split")
    what = "screen bins with triangles" if _missing(split) or not split else \
        "units (screen bins with triangles, dense ones cut into units of their triangles)"
    return (f" (sampled: {round(row['sample.bins']):,} of {round(row['sample.candidates']):,} {what}"
            + (f", fraction {share:g}" if not _missing(share) else "") + "; ± is the 95% interval)")


def _summary(row: dict) -> str:
    if row.get("samples.kind") == "lines":  # line samples: lines per pixel and line tests
        n = row.get("samples.n_lines") or 16
        lod = (f", lod {row['lod.triangles_in']:,} -> {row['lod.triangles']:,} triangles"
               if "lod.triangles" in row else "")
        return (f"{row['scene.name'] or row['scene.path']}: {row['pipeline.algorithm']}, CoC {row['camera.coc_px']:g} px, "
                f"{int(n)} lines, {row['camera.width']}x{row['camera.height']} -> line tests {figure(row, 'lines.tests')}, "
                f"segments {figure(row, 'lines.segments')}, ops/pixel {figure(row, 'ops.per_pixel', 0)}{lod}, "
                f"wall {row['time.wall_s']:.2f} s{_sampled(row)}")
    return (f"{row['scene.name'] or row['scene.path']}: {row['pipeline.algorithm']}, CoC {row['camera.coc_px']:g} px, "
            f"{row['samples.spp']} spp ({row['samples.kind']}), {row['camera.width']}x{row['camera.height']} -> "
            f"samples tested {figure(row, 'raster.samples_tested')}, STE {figure(row, 'raster.ste', 3)}, "
            f"ops/pixel {figure(row, 'ops.per_pixel', 0)}, wall {row['time.wall_s']:.2f} s{_sampled(row)}")


def _json_safe(x):
    if isinstance(x, float) and (math.isnan(x) or math.isinf(x)):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    return x


def _sampling_overrides(args) -> list[str]:
    """--sample-fraction F and --no-timing as the --set overrides they stand for (validated by the
    schema)."""
    out = []
    if getattr(args, "sample_fraction", None) is not None:
        out.append(f"pipeline.sample_fraction={args.sample_fraction!r}")
    if getattr(args, "no_timing", False):
        out.append("hardware.timing.enabled=false")
    return out


def parse_point(text: str) -> dict:
    """--point 'camera.coc_px=10,pipeline.algorithm=tile' -> {key: value} (values parsed as YAML)."""
    import yaml

    from .config import ConfigError

    out = {}
    for part in [p for p in text.split(",") if p.strip()]:
        if "=" not in part:
            raise ConfigError(f"--point {text}: expected key=value[,key=value...], got {part!r}")
        key, raw = (x.strip() for x in part.split("=", 1))
        try:
            out[key] = yaml.safe_load(raw) if raw else None
        except yaml.YAMLError as e:
            raise ConfigError(f"--point {key}: cannot parse value {raw!r}: {e}") from None
    if not out:
        raise ConfigError(f"--point: expected key=value[,key=value...], got {text!r}")
    return out


def select_point(config, source: str, lines: dict | None, wanted: dict):
    """The one point of config's sweep whose swept values match ``wanted`` ({swept key: value}); a
    ConfigError names --point, the unknown key (did you mean) or value, or the keys still left open."""
    from .config import ConfigError, expand_sweep
    from .config.schema import _did_you_mean
    from .report.frames import same

    swept = [k for k in config.sweep if k != "zip"]
    for k, v in wanted.items():
        if k not in swept:
            raise ConfigError(f"--point {k}: not a swept key of {source}{_did_you_mean(k, swept)} "
                              f"(swept: {', '.join(swept)})")
        if not any(same(v, x) or v == x for x in config.sweep[k]):
            raise ConfigError(f"--point {k}={v!r}: not one of the sweep's values {config.sweep[k]!r}")
    points = [(p, c) for p, c in expand_sweep(config, source, lines)
              if all(same(p[k], v) or p[k] == v for k, v in wanted.items())]
    if len(points) != 1:
        open_keys = [k for k in swept if k not in wanted and len({json.dumps(p[k], default=str) for p, _ in points}) > 1]
        raise ConfigError(f"--point: {len(points)} points of {source} match {wanted}; also give "
                          + ", ".join(f"{k} (one of {config.sweep[k]!r})" for k in open_keys))
    return points[0]


def cmd_render(args) -> int:
    from .config import load_dict, validate
    from .run import render_point

    data, lines = load_dict(args.config, (args.set or []) + _sampling_overrides(args))
    config = validate(data, str(args.config), lines)
    if config.sweep and args.point is None:
        from .config import sweep_points

        first = sweep_points(config.sweep)[0]
        example = ",".join(f"{k}={json.dumps(v) if not isinstance(v, str) else v}" for k, v in first.items())
        print(f"error: {args.config}: has a sweep ({', '.join(k for k in config.sweep if k != 'zip')}); render one "
              f"point of it with --point, e.g. --point {example}, or run the sweep with `rast5d run`", file=sys.stderr)
        return 2
    if args.point is not None:
        if not config.sweep:
            print(f"error: --point: {args.config} has no sweep", file=sys.stderr)
            return 2
        point, config = select_point(config, str(args.config), lines, parse_point(args.point))
        print(f"point {', '.join(f'{k}={v}' for k, v in point.items())}")
    else:
        from .config import expand_sweep

        expand_sweep(config, str(args.config), lines)  # the point is checked before the render
    image = args.output or config.outputs.image
    stats_path = args.stats or config.outputs.stats
    if args.pixel:
        return _trace(config, args.pixel)
    from .run.progress import ProgressBar

    bar = ProgressBar(delay=args.progress_delay)
    options = {"progress": bar}
    if args.heatmaps:
        options["pixel_stats"] = True
    try:
        # every figure (the timing and memory model's too, unless switched off)
        row, result = render_point(config, image, options=options, timing=config.hardware_config().timing.enabled)
    finally:
        bar.close()
    print(_summary(row))
    if args.heatmaps:
        from .report.heatmaps import write_heatmaps

        files = write_heatmaps(result, args.heatmaps, tile=int(result.config["pipeline"]["tile_size"]))
        print(f"heatmaps -> {args.heatmaps}/ ({', '.join(f.name for f in files)})")
    if image:
        print(f"image -> {image}")
    if stats_path:
        Path(stats_path).parent.mkdir(parents=True, exist_ok=True)
        payload = {"config": config.model_dump(), "row": row, "stats": result.stats,
                   "counter_docs": {k: {"unit": u, "description": d}
                                    for k, (u, d) in __import__("sim").counter_docs().items()}}
        Path(stats_path).write_text(json.dumps(_json_safe(payload), indent=2, default=str))
        print(f"stats -> {stats_path}")
    return 0


def _pixel_arg(text: str) -> tuple[int, int]:
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y (two integers, column and row from the top), got {text!r}")
    return x, y


def _trace(config, pixel: tuple[int, int]) -> int:
    import sim

    from .config import build

    scene, camera, table, pipeline = build(config)
    print(sim.trace_pixel(scene, camera, table, pixel[0], pixel[1], pipeline, hardware=config.hardware_config()))
    return 0


def cmd_run(args) -> int:
    from .config import load_dict, validate
    from .run import run_sweep

    overrides = (args.set or []) + _sampling_overrides(args)
    data, lines = load_dict(args.config, overrides)
    config = validate(data, str(args.config), lines)
    # The rows, not a DataFrame: a cached run imports no pandas unless the config draws plots.
    rows = run_sweep(config, source=str(args.config), workers=args.workers, scheduler=args.scheduler,
                     force=args.force, lines=lines, retry_failed=args.retry_failed, progress=not args.quiet,
                     locks=not args.no_lock, frame=False)
    if not args.quiet and len(rows):
        print("\n".join(main_table(config, rows)))
    if config.outputs.plots and not args.no_report:
        from .report.pages import write_config_page
        from .run.store import to_frame

        df = to_frame(rows)
        df.attrs["summary"] = rows.summary
        page = write_config_page(config, args.config, df, overrides=overrides, echo=not args.quiet)
        if not args.quiet:
            from .paths import display

            print(f"report -> {display(page)}")
    return 0 if len(rows) and all(r.get("status") == "ok" for r in rows) else 1


# The figures of `rast5d run`'s table, when the rows have them: (column, heading, decimals or None).
MAIN_FIGURES = (("raster.samples_tested", "samples tested", None), ("raster.ste", "STE", 3),
                ("lines.tests", "line tests", None), ("ops.per_pixel", "ops/pixel", 0),
                ("metric.rmse", "RMSE", 4), ("timing.cycles", "cycles", None))


def main_table(config, table) -> list[str]:
    """`rast5d run`'s table on the terminal: one line per point, its swept values and main figures.
    ``table``: the sweep's rows (a list of dicts, as the store serves them) or its DataFrame."""
    from .run.store import table_columns

    records = table.to_dict("records") if hasattr(table, "to_dict") else table
    columns = table_columns(records)  # each column's values as the table file holds them

    def has(c):
        return any(not _missing(v) for v in columns.get(c, ()))

    keys = []
    for k in (k for k in config.sweep if k != "zip"):
        if k in columns:
            keys.append(k)
        else:  # a whole section swept (scene: [...]): its name or path
            keys += [c for c in (f"{k}.name", f"{k}.path") if has(c)][:1]
    figures = [(c, h, d) for c, h, d in MAIN_FIGURES  # the figures these points have (line tests: line samples)
               if has(c) and any(not _missing(v) and v != 0 for v in columns[c])]
    head = [k for k in keys] + [h for _, h, _ in figures] + ["status"]
    rows = []
    for n in range(len(records)):
        row = {c: vals[n] for c, vals in columns.items()}
        cells = [str(row.get(k)) if not isinstance(row.get(k), float) else f"{row[k]:g}" for k in keys]
        cells += [figure(row, c, d) if row.get("status") == "ok" else "" for c, _, d in figures]
        cells.append(row.get("status") if row.get("status") == "ok" else f"{row.get('status')}: {row.get('error')}")
        rows.append(cells)
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]
    right = set(range(len(keys), len(keys) + len(figures)))  # numbers align right, names left

    def line(cells):
        return "  ".join(c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(zip(cells, widths))).rstrip()

    return [line(head), line(["-" * w for w in widths])] + [line(r) for r in rows]


def list_items(what: str) -> list[tuple[str, str]]:
    """(name, description) rows of `rast5d list WHAT`: the registries the engine and models read."""
    import sim

    if what == "algorithms":
        inter = set(sim.interleaved_algorithms())
        return [(n, d + (" (needs an interleaved sample table)" if n in inter else ""))
                for n, d in sim.algorithm_docs().items()]
    if what == "scenes":
        from models.registry import scene_description, scene_names, scene_parameters

        return [(n, scene_description(n) + " [" + ", ".join(f"{k}={v!r}" for k, v in scene_parameters(n).items())
                 + "]") for n in scene_names()]
    if what == "counters":
        return [(n, f"[{u}] {d}") for n, (u, d) in sim.counter_docs().items()]
    if what == "configs":
        from .config import load_dict, sweep_points
        from .paths import configs_dir

        rows = []
        root = configs_dir()
        for path in sorted(root.rglob("*.yaml")):
            if "scenes" in path.relative_to(root).parts:
                continue
            data, _ = load_dict(path)
            about = (data.get("outputs") or {}).get("title") or data.get("description") or ""
            points = len(sweep_points(data["sweep"])) if isinstance(data.get("sweep"), dict) else 1
            rows.append((f"configs/{path.relative_to(root).as_posix()}",
                         f"{' '.join(str(about).split())} ({points} points)".strip()))
        return rows
    raise ValueError(f"list: unknown kind {what!r}")


def cmd_list(args) -> int:
    rows = list_items(args.what)
    if not rows:
        print(f"no {args.what} found (configs: ./configs, else the configs shipped with the package)")
        return 0
    width = max(len(n) for n, _ in rows)
    for name, description in rows:
        print(f"{name:<{width}}  {description}")
    return 0


def cmd_report(args) -> int:
    from .paths import configs_dir
    from .report.pages import main as report_main

    return report_main(only=args.only, workers=args.workers, scheduler=args.scheduler, force=args.force,
                       quick=args.quick, retry_failed=args.retry_failed, configs_dir=configs_dir(args.configs),
                       reports_dir=args.reports)


STARTER = "starter.yaml"  # the shipped starter config, copied by `rast5d init` as DIR/my_sweep.yaml


def init_dir(target: str | Path, force: bool = False) -> list[Path]:
    """`rast5d init DIR`: copy the shipped configs (configs/, with the paper configs and the scene files),
    a starter sweep (my_sweep.yaml) and the example notebooks (notebooks/) into DIR, for a user to edit;
    a non-empty DIR is refused unless ``force`` (then the copied files overwrite theirs, nothing else is
    touched)."""
    import shutil

    from .config import ConfigError
    from .paths import bundled_configs, check_output_dir

    target = Path(target)
    if target.exists() and not target.is_dir():
        raise ConfigError(f"init: {target} exists and is not a directory")
    if target.is_dir() and any(target.iterdir()) and not force:
        raise ConfigError(f"init: {target} is not empty; give an empty or new directory, or --force to copy over "
                          "the files there")
    target = check_output_dir(target, "init", "another DIR")
    src = bundled_configs()
    written = []
    for f in sorted(src.rglob("*.yaml")):
        rel = f.relative_to(src)
        dst = target / ("my_sweep.yaml" if rel.as_posix() == STARTER else Path("configs") / rel)
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(f, dst)
        written.append(dst)
    for f in sorted((Path(__file__).resolve().parent / "examples").glob("*.ipynb")):
        dst = target / "notebooks" / f.name
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(f, dst)
        written.append(dst)
    return written


def cmd_init(args) -> int:
    from .paths import display

    written = init_dir(args.dir, force=args.force)
    rel = [f.relative_to(Path(args.dir).resolve()) for f in written]
    configs = [f for f in rel if f.parts[0] == "configs"]
    n_paper = sum(1 for f in configs if f.parts[1] == "paper")
    notebooks = [f.name for f in written if f.suffix == ".ipynb"]
    print(f"wrote {display(Path(args.dir))}/: my_sweep.yaml (a starter sweep to edit), configs/ "
          f"({len(configs)} configs, {n_paper} of them the paper's report configs) and notebooks/ "
          f"({', '.join(notebooks)}: run them with Jupyter)")
    print(f"next: cd {args.dir} && rast5d run my_sweep.yaml   (results in ./results; pages of "
          "`rast5d report` in ./reports)")
    return 0


def _results_option(p) -> None:
    p.add_argument("--results", metavar="DIR",
                   help="the result store (default: $RAST5D_RESULTS, else ./results under the working directory)")


class _Version(argparse.Action):
    """--version: the package version, read only when asked for (the metadata lookup costs start-up)."""

    def __call__(self, parser, namespace, values, option_string=None):
        from . import __version__

        print(f"rast5d {__version__} (Python {sys.version.split()[0]})")
        parser.exit()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rast5d", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action=_Version, nargs=0, help="show the version and exit")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("render", help="render one configuration to an image and statistics")
    p.add_argument("config", help="YAML configuration (see docs/config.md)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a key, e.g. --set camera.coc_px=10 (repeatable)")
    p.add_argument("-o", "--output", help="PNG image path")
    p.add_argument("--stats", help="JSON statistics path")
    p.add_argument("--sample-fraction", type=float, metavar="F",
                   help="sampled simulation: render a stratified share F in (0, 1] of the screen bins and "
                        "estimate the frame with 95%% intervals (pipeline.sample_fraction)")
    p.add_argument("--heatmaps", metavar="DIR",
                   help="write the image and per-pixel maps of where the work goes (samples tested, hits, "
                        "operations, tile cull reason) as PNGs with colour bars into DIR")
    p.add_argument("--pixel", metavar="X,Y", type=_pixel_arg,
                   help="trace one pixel (column X, row Y from the top): the triangles that reached it, each "
                        "tile test's verdict, each sample tested and hit, the operations charged")
    p.add_argument("--progress-delay", type=float, default=2.0, metavar="S",
                   help="show a progress bar once the render has run S seconds (default 2)")
    p.add_argument("--no-timing", action="store_true",
                   help="do not run the timing and memory model (hardware.timing.enabled=false): no timing.*, "
                        "dram.*, depth.cache.* or color.* figures")
    p.add_argument("--point", metavar="KEY=VALUE,...",
                   help="render one point of a sweep config, e.g. --point camera.coc_px=10,pipeline.algorithm=tile "
                        "(every swept key that has more than one value)")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("run", help="run a sweep (config.sweep) into the result store (./results/<name>.parquet)")
    p.add_argument("config")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a key (repeatable)")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: executor.workers or the core count; 0 = in-process)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on a Dask distributed scheduler, e.g. tcp://host:8786")
    p.add_argument("--force", action="store_true", help="re-render points found in the result store")
    p.add_argument("--retry-failed", action="store_true",
                   help="re-render stored failed points (otherwise served from the store with their error)")
    p.add_argument("--no-report", action="store_true", help="do not write the config's report page")
    p.add_argument("--no-timing", action="store_true",
                   help="do not run the timing and memory model (hardware.timing.enabled=false): faster, and no "
                        "timing.*, dram.*, depth.cache.* or color.* figures")
    p.add_argument("--no-lock", action="store_true",
                   help="take and honour no point locks in the store (a file system where locks fail): a point "
                        "another run computes meanwhile may be computed twice; the row stored first is kept "
                        "(docs/store.md)")
    p.add_argument("-q", "--quiet", action="store_true", help="print no progress bar, table or page path")
    _results_option(p)
    p.add_argument("--sample-fraction", type=float, metavar="F",
                   help="sampled simulation for every point: a stratified share F in (0, 1] of the screen bins, "
                        "counters scaled to the frame with 95%% intervals in '<figure>.ci95' columns "
                        "(pipeline.sample_fraction)")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("report", help="run the report configs (cached) and write their pages into ./reports")
    p.add_argument("--only", action="append", metavar="NAME", help="only these configs or pages (repeatable)")
    p.add_argument("--quick", action="store_true",
                   help="small-resolution variant into reports/quick/ with its own result store (results/quick/)")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--scheduler", metavar="ADDRESS")
    p.add_argument("--force", action="store_true")
    p.add_argument("--retry-failed", action="store_true", help="re-render stored failed points")
    p.add_argument("--configs", metavar="DIR",
                   help="the configs folder to run (default: ./configs if there is one, else the configs shipped "
                        "with the package; `rast5d init` copies them)")
    p.add_argument("--reports", metavar="DIR", help="where the pages go (default: ./reports)")
    _results_option(p)
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("init", help="copy the shipped configs (paper, scenes), a starter sweep and the example "
                                    "notebooks into DIR to edit")
    p.add_argument("dir", metavar="DIR")
    p.add_argument("--force", action="store_true", help="copy into a non-empty DIR (overwriting the copied files)")
    p.set_defaults(func=cmd_init)

    p = sub.add_parser("list", help="list the algorithms, named scenes, counters or configs")
    p.add_argument("what", choices=LIST_KINDS)
    p.set_defaults(func=cmd_list)

    args = parser.parse_args(argv)
    if getattr(args, "results", None):
        import os

        os.environ["RAST5D_RESULTS"] = str(Path(args.results).expanduser().resolve())  # workers inherit it
    import warnings

    def show_warning(message, category, filename, lineno, file=None, line=None):
        print(f"warning: {message}", file=sys.stderr)  # a user's warning, not a source location

    warnings.showwarning = show_warning
    import sim

    from .run.store import RunStopped

    try:
        return args.func(args)
    except sim.Error as e:  # every refused input (rast5d.Error)
        print(f"error: {e}", file=sys.stderr)
        return 2
    except ValueError as e:  # other input errors
        print(f"error: {e}", file=sys.stderr)
        return 2
    except RunStopped as e:  # a full or read-only store, a lost or silent Dask scheduler (docs/store.md)
        print(f"error: {e}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""The `rast5d` command line: render one config, run a sweep, regenerate the paper reports."""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path


LIST_KINDS = ("algorithms", "scenes", "counters", "configs")


def _summary(row: dict) -> str:
    if row.get("samples.kind") == "lines":  # line samples: lines per pixel and line tests
        n = row.get("samples.n_lines") or 16
        lod = (f", lod {row['lod.triangles_in']:,} -> {row['lod.triangles']:,} triangles"
               if "lod.triangles" in row else "")
        return (f"{row['scene.name'] or row['scene.path']}: {row['pipeline.algorithm']}, CoC {row['camera.coc_px']:g} px, "
                f"{int(n)} lines, {row['camera.width']}x{row['camera.height']} -> line tests {row['lines.tests']:,}, "
                f"segments {row['lines.segments']:,}, ops/pixel {row['ops.per_pixel']:,.0f}{lod}, "
                f"wall {row['time.wall_s']:.2f} s")
    return (f"{row['scene.name'] or row['scene.path']}: {row['pipeline.algorithm']}, CoC {row['camera.coc_px']:g} px, "
            f"{row['samples.spp']} spp ({row['samples.kind']}), {row['camera.width']}x{row['camera.height']} -> "
            f"samples tested {row['raster.samples_tested']:,}, STE {row['raster.ste']:.3f}, "
            f"ops/pixel {row['ops.per_pixel']:,.0f}, wall {row['time.wall_s']:.2f} s")


def _json_safe(x):
    if isinstance(x, float) and (math.isnan(x) or math.isinf(x)):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    return x


def _sampling_overrides(args) -> list[str]:
    """--sample-fraction F as the --set override it stands for (validated by the pipeline schema)."""
    if getattr(args, "sample_fraction", None) is None:
        return []
    return [f"pipeline.sample_fraction={args.sample_fraction!r}"]


def cmd_render(args) -> int:
    from .config import load_config
    from .run import render_point

    config = load_config(args.config, (args.set or []) + _sampling_overrides(args))
    if config.sweep:
        print(f"{args.config}: has a sweep ({', '.join(k for k in config.sweep if k != 'zip')}); use `rast5d run` "
              "for sweeps", file=sys.stderr)
        return 2
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
        row, result = render_point(config, image, options=options, timing=True)  # every figure
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
    from .report.pages import write_config_page
    from .run import run_sweep

    overrides = (args.set or []) + _sampling_overrides(args)
    data, lines = load_dict(args.config, overrides)
    config = validate(data, str(args.config), lines)
    df = run_sweep(config, source=str(args.config), workers=args.workers, scheduler=args.scheduler,
                   force=args.force, lines=lines, retry_failed=args.retry_failed)
    if config.outputs.plots and not args.no_report:
        page = write_config_page(config, args.config, df, overrides=overrides)
        print(f"report -> {page}")
    return 0 if len(df) and (df["status"] == "ok").all() else 1


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
        from .config import REPO, load_dict, sweep_points

        rows = []
        root = next((r for r in (Path.cwd(), REPO) if (r / "configs").is_dir()), REPO)
        for path in sorted((root / "configs").rglob("*.yaml")):
            if "scenes" in path.relative_to(root / "configs").parts:
                continue
            data, _ = load_dict(path)
            about = (data.get("outputs") or {}).get("title") or data.get("description") or ""
            points = len(sweep_points(data["sweep"])) if isinstance(data.get("sweep"), dict) else 1
            rows.append((str(path.relative_to(root)), f"{' '.join(str(about).split())} ({points} points)".strip()))
        return rows
    raise ValueError(f"list: unknown kind {what!r}")


def cmd_list(args) -> int:
    rows = list_items(args.what)
    if not rows:
        print(f"no {args.what} found (configs: a configs/ folder in the working directory or the checkout)")
        return 0
    width = max(len(n) for n, _ in rows)
    for name, description in rows:
        print(f"{name:<{width}}  {description}")
    return 0


def cmd_report(args) -> int:
    from .report.pages import main as report_main

    return report_main(only=args.only, workers=args.workers, scheduler=args.scheduler, force=args.force,
                       quick=args.quick, retry_failed=args.retry_failed)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rast5d", description=__doc__)
    from . import __version__

    parser.add_argument("--version", action="version",
                        version=f"rast5d {__version__} (Python {sys.version.split()[0]})")
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
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("run", help="run a sweep (config.sweep) into the result store (results/<name>.parquet)")
    p.add_argument("config")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a key (repeatable)")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: executor.workers or the core count; 0 = in-process)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on a Dask distributed scheduler, e.g. tcp://host:8786")
    p.add_argument("--force", action="store_true", help="re-render points found in the result store")
    p.add_argument("--retry-failed", action="store_true",
                   help="re-render stored failed points (otherwise served from the store with their error)")
    p.add_argument("--no-report", action="store_true", help="do not write the config's report page")
    p.add_argument("--sample-fraction", type=float, metavar="F",
                   help="sampled simulation for every point: a stratified share F in (0, 1] of the screen bins, "
                        "counters scaled to the frame with 95%% intervals in '<figure>.ci95' columns "
                        "(pipeline.sample_fraction)")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("report", help="run the report configs of configs/ (cached) and regenerate reports/")
    p.add_argument("--only", action="append", metavar="NAME", help="only these configs or pages (repeatable)")
    p.add_argument("--quick", action="store_true",
                   help="small-resolution variant into reports/quick/ with its own result store (results/quick/)")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--scheduler", metavar="ADDRESS")
    p.add_argument("--force", action="store_true")
    p.add_argument("--retry-failed", action="store_true", help="re-render stored failed points")
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("list", help="list the algorithms, named scenes, counters or configs")
    p.add_argument("what", choices=LIST_KINDS)
    p.set_defaults(func=cmd_list)

    args = parser.parse_args(argv)
    import warnings

    def show_warning(message, category, filename, lineno, file=None, line=None):
        print(f"warning: {message}", file=sys.stderr)  # a user's warning, not a source location

    warnings.showwarning = show_warning
    from .config import ConfigError
    import sim

    try:
        return args.func(args)
    except (ConfigError, sim.ConfigError, sim.SceneInputError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except ValueError as e:  # models.SceneError and other input errors
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

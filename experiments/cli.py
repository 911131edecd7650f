"""The `rast5d` command line: render one config, run a sweep, regenerate the paper reports."""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path


def _summary(row: dict) -> str:
    return (f"{row['scene']}: {row['algorithm']}, CoC {row['coc_px']:g} px, {row['spp']} spp, "
            f"{row['width']}x{row['height']} -> samples tested {row['raster.samples_tested']:,}, "
            f"STE {row['raster.ste']:.3f}, ops/pixel {row['ops.per_pixel']:,.0f}, "
            f"wall {row['time.wall_s']:.2f} s")


def _json_safe(x):
    if isinstance(x, float) and (math.isnan(x) or math.isinf(x)):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    return x


def cmd_render(args) -> int:
    from .config import load_config
    from .runner import render_point

    config = load_config(args.config, args.set or [])
    if config.sweep:
        print(f"{args.config}: has a sweep ({', '.join(config.sweep)}); use `rast5d run` for sweeps",
              file=sys.stderr)
        return 2
    image = args.output or config.output.image
    stats_path = args.stats or config.output.stats
    row, result = render_point(config, image)
    print(_summary(row))
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


def cmd_run(args) -> int:
    from .config import load_config
    from .runner import run_sweep

    if args.scheduler:
        print("--scheduler: distributed (Dask) execution is not implemented yet; use --workers N "
              "for a local process pool", file=sys.stderr)
        return 2
    config = load_config(args.config, args.set or [])
    out = Path(args.out or Path("results") / (config.name or Path(args.config).stem))
    df = run_sweep(config, out, source=str(args.config), workers=args.workers, use_cache=not args.no_cache,
                   images=args.images)
    return 0 if (df["status"] == "ok").all() else 1


def cmd_report(args) -> int:
    from . import paper

    return paper.main(only=args.only, workers=args.workers, use_cache=not args.no_cache)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rast5d", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("render", help="render one configuration to an image and statistics")
    p.add_argument("config", help="YAML configuration (see docs/config.md)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a key, e.g. --set camera.coc_px=10 (repeatable)")
    p.add_argument("-o", "--output", help="PNG image path")
    p.add_argument("--stats", help="JSON statistics path")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("run", help="run a sweep (config.sweep) into a results table")
    p.add_argument("config")
    p.add_argument("--set", action="append", metavar="KEY=VALUE")
    p.add_argument("--out", help="output directory (default results/<name>)")
    p.add_argument("--workers", type=int, default=1, help="local worker processes")
    p.add_argument("--scheduler", help="Dask scheduler address (not implemented yet)")
    p.add_argument("--no-cache", action="store_true", help="re-render points found in results/cache")
    p.add_argument("--images", action="store_true", help="also write each point's image")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("report", help="regenerate reports/ from configs/paper/")
    p.add_argument("--only", action="append", metavar="NAME", help="only these reports (repeatable)")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--no-cache", action="store_true")
    p.set_defaults(func=cmd_report)

    args = parser.parse_args(argv)
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

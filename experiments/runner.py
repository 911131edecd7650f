"""Render one point or a whole sweep: result rows, a per-point cache, error isolation, progress.

Each finished point is appended to ``<out>/results.jsonl`` as soon as it finishes and cached
under ``results/cache/<config hash>.json`` (neither is committed), so a sweep that fails or is
interrupted keeps every finished point; a failing point becomes a row with ``status = "error"``
and its message, and the sweep goes on.
"""
from __future__ import annotations

import json
import math
import time
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from .config import REPO, RenderConfig, build, config_hash, expand_sweep

CACHE_DIR = REPO / "results" / "cache"
_ENGINE_ID = None


def engine_id() -> str:
    """Fingerprint of the compiled engine and the Python that drives it: cached results are only
    reused by the same engine (an engine change invalidates the cache)."""
    global _ENGINE_ID
    if _ENGINE_ID is None:
        import hashlib

        import sim

        h = hashlib.sha256(Path(sim._core.__file__).read_bytes())
        for folder in ("sim", "models"):
            for f in sorted((REPO / folder).glob("*.py")):
                h.update(f.read_bytes())
        _ENGINE_ID = h.hexdigest()[:12]
    return _ENGINE_ID


def meta_columns(config: RenderConfig, camera=None) -> dict:
    """Identifying columns of a result row."""
    spec = config.scene
    row = {
        "scene": spec.name or Path(spec.path).stem,
        "algorithm": config.pipeline.algorithm,
        "generator": config.sample_table.generator,
        "spp": config.sample_table.spp,
        "tile_size": config.pipeline.tile_size,
        "halfspace_h": config.pipeline.halfspace.get("h", True),
        "halfspace_H": config.pipeline.halfspace.get("H", True),
        "selective_H": config.pipeline.selective_H,
        "config_hash": config_hash(config),
    }
    if camera is not None:
        row.update(width=camera.width, height=camera.height, coc_px=camera.coc_px, lens=camera.lens)
    else:
        row.update(coc_px=config.camera.coc_px)
    return row


def render_point(config: RenderConfig, image_path: str | Path | None = None) -> tuple[dict, object]:
    """Render one (non-swept) config: (row, sim.Result)."""
    import sim

    scene, camera, table, pipeline = build(config)
    result = sim.render(scene, camera, table, pipeline)
    row = meta_columns(config, camera)
    row["lens_grid"] = result.config["lens_grid"]
    row["triangles"] = scene.n_triangles
    row.update(result.flat_stats)
    row["status"] = "ok"
    row["error"] = ""
    row["engine_id"] = engine_id()
    if image_path is not None:
        result.save_png(image_path)
    return row, result


def _run_one(args) -> dict:
    config_json, point, image_path = args
    config = RenderConfig.model_validate_json(config_json)
    try:
        row, _ = render_point(config, image_path)
    except Exception as e:  # noqa: BLE001 - a failing point must not stop the sweep
        row = meta_columns(config)
        row.update(status="error", error=f"{type(e).__name__}: {e}",
                   traceback=traceback.format_exc(limit=3))
    row.update({f"point.{k}": v for k, v in point.items()})
    return row


def _clean(row: dict) -> dict:
    return {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}


def run_sweep(config: RenderConfig, out_dir: str | Path, *, source: str = "config", workers: int = 1,
              use_cache: bool = True, images: bool = False, progress: bool = True):
    """Run every point of config's sweep. Returns a pandas DataFrame (one row per point)."""
    import pandas as pd

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    points = expand_sweep(config, source)
    rows: list[dict] = []
    todo = []
    for point, cfg in points:
        h = config_hash(cfg)
        cached = CACHE_DIR / f"{h}-{engine_id()}.json"
        if use_cache and cached.exists():
            row = json.loads(cached.read_text())
            row.update({f"point.{k}": v for k, v in point.items()})
            rows.append(row)
            continue
        image = str(out / "images" / f"{h}.png") if images else None
        if image:
            Path(image).parent.mkdir(parents=True, exist_ok=True)
        todo.append((cfg.model_dump_json(), point, image))
    log = out / "results.jsonl"
    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc=config.name or source, unit="point")

    def finished(row: dict):
        row = _clean(row)
        rows.append(row)
        with log.open("a") as f:
            f.write(json.dumps(row, default=str) + "\n")
        if row["status"] == "ok":
            CACHE_DIR.mkdir(parents=True, exist_ok=True)
            keep = {k: v for k, v in row.items() if not k.startswith("point.")}
            (CACHE_DIR / f"{row['config_hash']}-{engine_id()}.json").write_text(json.dumps(keep, default=str))
        if bar:
            bar.update(1)
            if row["status"] != "ok":
                bar.write(f"point failed: {row.get('error')}")

    t0 = time.perf_counter()
    if workers <= 1:
        for args in todo:
            finished(_run_one(args))
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            for fut in as_completed([pool.submit(_run_one, a) for a in todo]):
                finished(fut.result())
    if bar:
        bar.close()
    df = pd.DataFrame(rows)
    df.to_csv(out / "results.csv", index=False)
    if progress:
        n_err = int((df["status"] != "ok").sum()) if "status" in df else 0
        print(f"{len(df)} points ({len(todo)} rendered, {len(df) - len(todo)} cached, {n_err} failed) "
              f"in {time.perf_counter() - t0:.1f} s -> {out / 'results.csv'}")
    return df

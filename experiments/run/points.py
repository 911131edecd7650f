"""Point kinds: what one point of a sweep computes (config key `point:`, docs/reports.md §Point kinds),
and the row it leaves in the result store.

- render (default): sim.render of the point; its counters, derived figures and timing estimate.
- occlusion_query: sim.occlusion_query of `point.query` behind the point's scene; the query's own
  work (the render with the query minus the occluders alone) and `query.visible`,
  `query.samples_passed`.
- conservative: sim.conservative_raster of the scene (1 x 1 tiles, per-pixel t-z boxes); its
  counters and `conservative.pixels_covered`.
- transparency, sampler, soft_shadows, caustics, glossy: the uses of the rasterizer (sim.uses, run by
  experiments/run/uses.py with `point.options`): the image and counters of the use's main pass and its
  figures (sim.uses.FIGURES).
- precision: one row of the numerical-precision study (experiments/run/precision.py, `point.options`):
  the engine's kernels in an arithmetic against float64 and the ray caster, or the point's render in its
  pipeline.precision against the default precision; its figures are numerics.* (sim/figures.py).
- retime: sim.timing.estimate on the stored work records of the point's render (store.records_path;
  rendered once on first use) with `point.hardware` merged over the hardware section; the render's
  counters and the re-timed `timing.*` figures.
"""
from __future__ import annotations

import json
import time
import traceback
from pathlib import Path

from ..config.schema import deep_merge
from ..config import RESULT_EXCLUDE, RenderConfig, build, build_scene, config_hash, flatten, point_columns, timing_needed
from ..config.inputs import input_digests, tracking_reads
from .store import cached_records, disk_fault, engine_id, git_rev, store_pictures, store_records
from .precision import precision_point
from .uses import USE_KINDS


def config_columns(config: RenderConfig, h: str | None = None) -> dict:
    """The flattened resolved config of a point (hardware fully resolved; camera from the built camera);
    h: its config_hash when already known."""
    row = flatten(config.model_dump(exclude=RESULT_EXCLUDE | {"hardware"}))
    row.update(point_columns(config))
    try:
        row.update(flatten({"hardware": config.hardware_config().describe()}))
    except Exception:  # noqa: BLE001 - validated on load; keep the row even if not
        pass
    row["config_hash"] = config_hash(config) if h is None else h
    return row


def camera_columns(camera) -> dict:
    """The resolved camera of a point (fields the scene's hint filled in included)."""
    out = {}
    for k in ("width", "height", "fov_y_deg", "focus_distance", "coc_px", "aperture_radius", "lens", "near"):
        if hasattr(camera, k):
            v = getattr(camera, k)
            out[f"camera.{k}"] = v if isinstance(v, (int, float, str)) else json.dumps(v)
    return out


def _build(config: RenderConfig, row: dict, threads: int | None):
    """(scene, camera, table, pipeline) of a point; adds the resolved camera and the scene size to row."""
    scene, camera, table, pipeline = build(config)
    if threads is not None and config.pipeline.threads == 0:
        pipeline = pipeline.replace(threads=threads)
    row.update(camera_columns(camera))
    row["scene.triangles"] = scene.n_triangles
    return scene, camera, table, pipeline


def _rendered(config, row: dict, threads, options: dict | None = None, timing: bool | None = None):
    """sim.render of a point; adds its resolved lens grid and every counter and figure to row.
    options: extra sim.render keywords that observe the render (pixel_stats, progress); timing: run the
    timing model (None: as the point's config asks, timing_needed)."""
    import sim

    scene, camera, table, pipeline = _build(config, row, threads)
    # Sweep points of pages that never read timing skip the model (timing_needed); a render from the
    # command line (`rast5d render`) asks for every figure with timing=True.
    timing = timing_needed(config) if timing is None else timing
    opts = dict(options or {})
    if opts.get("keep_timing_records") and not timing:
        opts.pop("keep_timing_records")
    result = sim.render(scene, camera, table, pipeline, hardware=config.hardware_config(), timing=timing, **opts)
    row["resolved.lens_grid"] = result.config.get("lens_grid")
    row.update(result.flat_stats)
    if result.ci95 is not None:  # sampled simulation: 95% half-widths beside the estimates
        row.update({f"{k}.ci95": v for k, v in result.ci95.items()})
    return result


def _render(config, row, image_path, threads, options=None, timing=None):
    result = _rendered(config, row, threads, options, timing)
    if config.outputs.metrics is not None and result.ci95 is not None:
        raise ValueError(f"outputs.metrics: image metrics need the whole frame; pipeline.sample_fraction="
                         f"{config.pipeline.sample_fraction!r} renders only sampled bins (not estimable)")
    if config.outputs.metrics is not None:
        from .references import point_metrics

        row.update(point_metrics(config, result.image))
    if image_path is not None:
        Path(image_path).parent.mkdir(parents=True, exist_ok=True)
        result.save_png(image_path)
    return result


def _occlusion_query(config, row, image_path, threads):
    import sim

    scene, camera, table, pipeline = _build(config, row, threads)
    t0 = time.perf_counter()
    r = sim.occlusion_query(scene, build_scene(config.point.query), camera, table, pipeline, mode=config.point.mode)
    row.update(r.work)
    row.update({"query.visible": bool(r.visible), "query.samples_passed": int(r.samples_passed),
                "time.wall_s": time.perf_counter() - t0})
    return r


def _conservative(config, row, image_path, threads):
    import sim

    if config.pipeline.sample_fraction < 1:
        raise ValueError(f"pipeline.sample_fraction: {config.pipeline.sample_fraction!r}: conservative "
                         "rasterization is not sampled; use sample_fraction=1")

    scene, camera, _, pipeline = _build(config, row, threads)
    t0 = time.perf_counter()
    r = sim.conservative_raster(scene, camera, pipeline, reduce="tz_box")
    row.update(r.flat_stats)
    row.update({"conservative.pixels_covered": int((r.count > 0).sum()), "time.wall_s": time.perf_counter() - t0})
    return r


def render_config(config: RenderConfig) -> RenderConfig:
    """The render whose work records a retime point re-times (the same config without the point section)."""
    return config.model_copy(update={"point": type(config.point)()})


def stored_render(config: RenderConfig, threads: int | None = None):
    """(timing records, flat counters with the resolved camera and scene size) of ``config``'s render, from
    the store or rendered and stored."""
    base = render_config(config)
    h = config_hash(base)
    cached = cached_records(h)
    if cached is not None:
        return cached
    stats: dict = {}
    with tracking_reads() as reads:
        result = _rendered(base, stats, threads, {"keep_timing_records": True}, timing=True)
    stats["inputs.files"] = json.dumps(input_digests(reads))
    store_records(h, result.timing_records, stats)
    return result.timing_records, stats


def _retime(config, row, image_path, threads):
    import sim

    if config.pipeline.sample_fraction < 1:
        raise ValueError(f"pipeline.sample_fraction: {config.pipeline.sample_fraction!r}: re-timing needs the whole "
                         "frame's work records (the timing model is not estimable from sampled bins)")
    records, stats = stored_render(config, threads)
    t0 = time.perf_counter()
    timing = sim.timing.estimate(records, config.retime_hardware())
    row.update({k: v for k, v in stats.items() if not k.startswith("timing.")})
    row.update(timing)
    row["time.wall_s"] = time.perf_counter() - t0
    return timing


def _timing_reference(config, row, image_path, threads):
    """The timing model against its reference (docs/timing.md, "The model's own error"): the render with
    visit records kept; the model's figures on them (the render's own), the cycle-stepped reference on the
    same records (reference.*), and the model on (triangle, bin) records of the same render (bin.*);
    CPU time of the model alone and of the reference on the visit records (time.model_s,
    time.reference_s)."""
    import sim

    if config.pipeline.sample_fraction < 1:
        raise ValueError(f"pipeline.sample_fraction: {config.pipeline.sample_fraction!r}: the reference needs the "
                         "whole frame's work records")
    hw = config.hardware_config()
    visit_hw = sim.HardwareConfig.from_dict(deep_merge(hw.describe(), {"timing": {"granularity": "visit"}}))
    bin_hw = sim.HardwareConfig.from_dict(deep_merge(hw.describe(), {"timing": {"granularity": "bin"}}))
    scene, camera, table, pipeline = _build(config, row, threads)
    result = sim.render(scene, camera, table, pipeline, hardware=visit_hw, timing=True, keep_timing_records=True)
    row["resolved.lens_grid"] = result.config.get("lens_grid")
    row.update(result.flat_stats)
    records = result.timing_records
    c0 = time.process_time()
    model = sim.timing.estimate(records, visit_hw)
    row["time.model_s"] = time.process_time() - c0
    c0 = time.process_time()
    ref = sim.timing.reference(records, visit_hw)
    row["time.reference_s"] = time.process_time() - c0
    row.update({f"reference.{k[len('timing.'):]}": v for k, v in ref.items()})
    assert model["timing.cycles"] == row["timing.cycles"]  # the streamed figures are the model's
    coarse = sim.render(scene, camera, table, pipeline, hardware=bin_hw, timing=True).flat_stats
    row.update({f"bin.{k[len('timing.'):]}": v for k, v in coarse.items() if k.startswith("timing.")})
    return result


POINT_KINDS = {"render": _render, "occlusion_query": _occlusion_query, "conservative": _conservative,
               "retime": _retime, "timing_reference": _timing_reference}
POINT_KINDS.update(USE_KINDS)  # the uses of the rasterizer (experiments/run/uses.py)
POINT_KINDS["precision"] = precision_point  # the numerical-precision study (experiments/run/precision.py)


def render_point(config: RenderConfig, image_path: str | Path | None = None, threads: int | None = None,
                 options: dict | None = None, timing: bool | None = None, h: str | None = None) -> tuple[dict, object]:
    """Compute one (non-swept) point: (row, the sim result of its kind). options: sim.render keywords
    that observe a render point (pixel_stats, progress); timing: run the timing model of a render point
    (None: as its config asks, timing_needed); h: the point's config_hash when already known."""
    kind = config.point.kind
    if image_path is not None and kind not in ("render", *USE_KINDS):
        raise ValueError(f"outputs.images: only render and use points have images, got point kind {kind!r}")
    if (options or timing is not None) and kind != "render":
        raise ValueError(f"point.kind: per-pixel statistics, progress and timing need a render point, got {kind!r}")
    row = config_columns(config, h)
    extra = {"options": options} if options else {}
    if timing is not None:
        extra["timing"] = timing
    result = POINT_KINDS[kind](config, row, image_path, threads, **extra)
    row.update(status="ok", error="", **{"engine.version": engine_id(), "engine.git_rev": git_rev()})
    return row, result


def picture_options(pictures) -> dict | None:
    """The sim.render keywords that the pictures of a point need: the pixel-statistics maps they draw
    (the tile verdict maps for 'tile.cull_reason'), only maps of pixel_stats=True (a page asking for
    another name renders the point itself and reports it)."""
    from sim.pixel_stats import DEFAULT, DERIVED, TILE_VERDICTS

    maps: list[str] = []
    for name in pictures or ():
        wanted = TILE_VERDICTS if name == "tile.cull_reason" else (name,) if name in DEFAULT or name in DERIVED else ()
        maps += [n for n in wanted if n not in maps]
    return {"pixel_stats": maps} if maps else None


def run_point(config_json: str, image_path: str | None = None, threads: int | None = None,
              records_hash: str | None = None, pictures: tuple[str, ...] = ()) -> dict:
    """One point, isolated: any exception becomes a row with status 'error', its message and its
    traceback (never raised). ``inputs.files`` lists the files read meanwhile ({path: sha256}, JSON):
    the store serves the row only while they are unchanged. ``records_hash``: a render point stores its
    timing records and counters under it, as stored_render would, for the retime points that re-time it.
    ``pictures``: what a report page pictures of this point ('image', pixel-statistics map names,
    'tile.cull_reason'; experiments/report/heatmaps.py): kept in the store (store_pictures) from this
    render, so the page does not render the point again."""
    config = RenderConfig.model_validate_json(config_json)
    h = config_hash(config)
    t0 = time.perf_counter()
    result = None
    options = picture_options(pictures) if config.point.kind == "render" else None
    if records_hash is not None and config.point.kind == "render":  # the retime points re-time its records
        options = {**(options or {}), "keep_timing_records": True}
    with tracking_reads() as reads:
        try:
            try:
                row, result = render_point(config, image_path, threads, options=options, h=h)
            except Exception:  # noqa: BLE001 - the pictures' statistics must not fail the point
                if options is None:
                    raise
                options = None
                row, result = render_point(config, image_path, threads, h=h)
        except Exception as e:  # noqa: BLE001 - a failing point must not stop the sweep
            fault = disk_fault(e)
            if fault is not None:  # a full or read-only disk (its image): the run stops, the point is not failed
                raise fault from e
            row = config_columns(config, h)
            row.update(status="error", error=f"{type(e).__name__}: {e}", traceback=traceback.format_exc(),
                       **{"engine.version": engine_id(), "engine.git_rev": git_rev(),
                          "time.wall_s": time.perf_counter() - t0})
    row["inputs.files"] = json.dumps(input_digests(reads))
    records = getattr(result, "timing_records", None)
    if records_hash is not None and row.get("status") == "ok" and records is not None and result.ci95 is None:
        stats = {"resolved.lens_grid": row.get("resolved.lens_grid"), **result.flat_stats,
                 "inputs.files": row["inputs.files"]}
        store_records(records_hash, records, stats)
    if pictures and row.get("status") == "ok" and getattr(result, "ci95", None) is None:
        keep_pictures(h, result, pictures, row["inputs.files"])
    return row


def keep_pictures(h: str, result, pictures, inputs_files: str) -> None:
    """Store the arrays the pictures of point ``h`` draw: its image and the pixel-statistics maps
    named (all tile verdict maps for 'tile.cull_reason'); maps the render did not make are left out
    (the page then renders the point and reports the missing map)."""
    from sim.pixel_stats import TILE_VERDICTS

    arrays = {}
    stats = getattr(result, "pixel_stats", None) or {}
    for name in pictures:
        if name == "image" and getattr(result, "image", None) is not None:
            arrays["image"] = result.image
        elif name == "tile.cull_reason":
            arrays.update({f"map:{n}": stats[n] for n in TILE_VERDICTS if n in stats})
        elif name in stats:
            arrays[f"map:{name}"] = stats[name]
    if arrays:
        store_pictures(h, arrays, inputs_files)


def error_row(config_json: str, message: str, transient: bool = False) -> dict:
    """The row of a point that did not return one; ``transient`` (a lost cluster worker) rows are not
    stored, so the next run computes the point again."""
    config = RenderConfig.model_validate_json(config_json)
    row = config_columns(config)
    row.update(status="error", error=message, **{"engine.version": engine_id(), "engine.git_rev": git_rev()})
    if transient:
        row["_transient"] = True
    return row

"""Pictures of where the work of one frame goes: `rast5d render --heatmaps DIR` and the `heatmap` /
`image` plot kinds with `map:` (docs/reports.md). Each map of `Result.pixel_stats` (sim.pixel_stats)
becomes a PNG with a colour bar labelled from `sim.counter_docs()`; tile-level counters are summed
per screen tile; the tile cull reason is a categorical map with a titled legend."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .frames import apply_derived

# Maps written by default (those present in the result), with the rendered image and the cull reason.
DEFAULT_MAPS = ("raster.samples_tested", "raster.samples_hit", "ops.total", "tile.culled")
TILE_LEVEL = ("tile.", "interval.culled_")
REASON_LABELS = {
    "tile.culled_2d": "2D edge test", "tile.culled_h": "h_i lines (uv-boxes empty)",
    "interval.culled_clip": "clip box", "tile.culled_lens": "outside the lens shape",
    "tile.culled_H": "H_j lines", "interval.culled_t": "time interval t̂", "tile.accepted": "accepted (none culled)",
}
REASON_COLOURS = {
    "tile.culled_2d": "#0072B2", "tile.culled_h": "#E69F00", "interval.culled_clip": "#999999",
    "tile.culled_lens": "#CC79A7", "tile.culled_H": "#D55E00", "interval.culled_t": "#009E73",
    "tile.accepted": "#F0E442",
}


def map_label(name: str, per_tile: bool = False) -> str:
    """'<description> (<unit> per pixel)' from sim.counter_docs()."""
    import sim

    unit, desc = sim.counter_docs().get(name, ("", name))
    where = "per tile" if per_tile else "per pixel"
    return f"{name}: {unit} {where}" if unit else f"{name} ({where})"


def map_values(stats: dict, name: str, tile: int) -> tuple[np.ndarray, bool]:
    """The (H, W) float map to draw and whether it was summed per tile (then upsampled to pixels)."""
    import sim

    a = stats[name]
    if tile > 1 and name.startswith(TILE_LEVEL):
        h, w = a.shape
        blocks = sim.pixel_stats.tile_blocks(a, tile)
        return np.kron(blocks, np.ones((tile, tile)))[:h, :w].astype(float), True
    return a.astype(float), False


def map_norm(values_list):
    """One colour scale for maps drawn side by side: log when the non-zero values span two decades."""
    from matplotlib.colors import LogNorm, Normalize

    nz = np.concatenate([v[v > 0].ravel() for v in values_list]) if values_list else np.zeros(0)
    if nz.size and nz.max() / nz.min() >= 100:
        return LogNorm(vmin=nz.min(), vmax=nz.max()), True
    hi = max((float(v.max()) for v in values_list), default=1.0)
    return Normalize(vmin=0.0, vmax=hi if hi > 0 else 1.0), False


def draw_map(ax, values: np.ndarray, label: str, fig, title: str | None = None, norm=None, colorbar=True):
    """One map (with a colour bar unless colorbar=False); a log colour scale when the non-zero values
    span two decades (norm: a shared scale from map_norm)."""
    if norm is None:
        norm, log = map_norm([values])
    else:
        log = norm.__class__.__name__ == "LogNorm"
    data = np.ma.masked_where(values <= 0, values) if log else values
    im = ax.imshow(data, cmap="magma", interpolation="nearest", norm=norm)
    ax.set_facecolor("black")
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)
    if colorbar:
        cb = fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
        cb.set_label(label + (" (log scale; black = 0)" if log else ""), fontsize=8)
        cb.ax.tick_params(labelsize=7)
    return im


def draw_reason(ax, stats: dict, tile: int, title: str | None = None):
    """The tile cull reason map (sim.pixel_stats.cull_reason) with a titled legend."""
    import sim
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    reason, names = sim.pixel_stats.cull_reason(stats, tile)
    h, w = next(iter(stats.values())).shape
    img = np.kron(reason, np.ones((tile, tile), dtype=reason.dtype))[:h, :w]
    present = [i for i in range(len(names)) if (reason == i).any()]
    colours = ["#000000"] + [REASON_COLOURS.get(n, "#777777") for n in names]
    ax.imshow(img + 1, cmap=ListedColormap(colours), vmin=0, vmax=len(names), interpolation="nearest")
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)
    handles = [Patch(color=REASON_COLOURS.get(names[i], "#777777"), label=REASON_LABELS.get(names[i], names[i]))
               for i in present] + [Patch(color="#000000", label="no triangle tested")]
    ax.legend(handles=handles, title="most frequent cull per tile", fontsize=7, title_fontsize=7,
              loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)


def map_title(result, name: str) -> str:
    """A map's title: its counter and the frame's total; under sampling (Result.ci95) the map holds
    the sampled bins only, so the title gives the frame estimate with its 95% interval and says so."""
    from .figures import value_label

    what = value_label(name)
    total = int(result.pixel_stats[name].sum())
    ci = (result.ci95 or {}).get(name)
    if ci is None:
        return f"{what} (frame total {total:,})"
    estimate = result.flat_stats.get(name, float("nan"))
    return (f"{what}: frame estimate {round(estimate):,} ± {round(ci):,}\n"
            f"(map: the sampled bins only, {total:,})")


def write_heatmaps(result, out_dir, tile: int = 1, names=None) -> list[Path]:
    """Write the rendered image and one PNG per map of result.pixel_stats into out_dir; returns
    the files. tile: the screen tile size (tile-level counters are summed per tile)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .figures import STYLE

    plt.rcParams.update(STYLE)
    stats = result.pixel_stats or {}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = [out / "image.png"]
    result.save_png(files[0])
    wanted = [n for n in (names or DEFAULT_MAPS) if n in stats]
    if names is None:
        wanted = [n for n in wanted if n != "tile.culled" or stats[n].any()]
    h, w = result.image.shape[:2]
    size = (min(8.0, 2.5 + 5.0 * w / max(h, w)), min(6.0, 1.0 + 4.5 * h / max(h, w)))
    for name in wanted:
        values, per_tile = map_values(stats, name, tile)
        fig, ax = plt.subplots(figsize=size)
        draw_map(ax, values, map_label(name, per_tile), fig, title=map_title(result, name))
        path = out / f"{name}.png"
        fig.savefig(path, dpi=150, bbox_inches="tight")
        plt.close(fig)
        files.append(path)
    if (names is None or "tile.cull_reason" in names) and "tile.accepted" in stats and stats["tile.visited"].any():
        fig, ax = plt.subplots(figsize=(size[0] + 2.0, size[1]))
        draw_reason(ax, stats, tile, title=f"tile cull reason ({tile}x{tile} tiles)")
        path = out / "tile.cull_reason.png"
        fig.savefig(path, dpi=150, bbox_inches="tight")
        plt.close(fig)
        files.append(path)
    return files


# ---- plot kinds `image` and `heatmap` with `map:` (report pages) -----------------------------------

MAX_PANELS = 6


def picture_name(spec) -> str | None:
    """What a plot pictures of its points: 'image' (`kind: image`), a map name (`kind: heatmap` with
    `map:`), or None (a plot of the rows)."""
    if spec.kind == "image":
        return "image"
    return spec.map


def pictured_points(config, points) -> dict[str, set[str]]:
    """{config_hash: picture names} of the points that ``config``'s page pictures (point_pictures),
    chosen before they are rendered, from their config columns: the sweep renders them with what the
    pictures need and keeps it in the store. A `where:` on a column that only the results have picks
    nothing here; point_pictures then renders those points itself. points: [(hash, config)]."""
    from ..run.points import config_columns
    from ..run.store import to_frame
    from .frames import PlotError, apply_where, same

    specs = [sp for sp in config.outputs.plots if picture_name(sp) is not None]
    if not specs or not points:
        return {}
    df = to_frame([config_columns(cfg, h) for h, cfg in points])
    for name, expr in config.outputs.derived.items():  # the derived columns that need no result
        try:
            df = apply_derived(df, {name: expr})
        except PlotError:
            continue
    out: dict[str, set[str]] = {}
    for spec in specs:
        dd = df
        for col, names in spec.labels.items():  # display names first, as section_markdown does
            if col in dd.columns:
                dd = dd.assign(**{col: [next((n for k, n in names.items() if same(v, k)), v) for v in dd[col]]})
        try:
            hashes = list(apply_where(dd, spec.where)["config_hash"])
        except PlotError:
            continue
        if len(hashes) > MAX_PANELS:
            continue
        for h in hashes:
            out.setdefault(h, set()).add(picture_name(spec))
    return out


class _Stored:
    """A point's stored pictures in the shape point_pictures reads from a render's result."""

    def __init__(self, arrays: dict):
        self.image = arrays.get("image")
        self.pixel_stats = {k[4:]: v for k, v in arrays.items() if k.startswith("map:")}


def _stored(h: str, name: str):
    """The stored pictures of point h if they hold what picture ``name`` draws, else None."""
    from sim.pixel_stats import TILE_VERDICTS

    from ..run.store import cached_pictures

    arrays = cached_pictures(h)
    if arrays is None:
        return None
    need = ["image"] if name == "image" else [f"map:{n}" for n in TILE_VERDICTS] if name == "tile.cull_reason" \
        else [f"map:{name}"]
    return _Stored(arrays) if all(k in arrays for k in need) else None


def point_pictures(spec, config, d, out_base: Path | None) -> dict:
    """`kind: image` (the rendered image) or `kind: heatmap` with `map:` (a Result.pixel_stats map,
    or 'tile.cull_reason') of the sweep points left by `where:`, one panel per `facet` value (one
    panel without facet). The image and maps come from the result store, where the sweep's render of
    the point kept them (pictured_points); a point without them is rendered here and they are kept."""
    import matplotlib

    from ..config.inputs import input_digests, tracking_reads
    from ..run.runner import hashed_sweep
    from ..run import render_point
    from ..run.points import keep_pictures
    from .figures import STYLE, _plt, _save, facet_title, grid_shape, value_label
    from .frames import PlotError, label, same, unique

    what = f"plot {spec.title or spec.kind!r}"
    if "config_hash" not in d.columns:
        raise PlotError(f"{what}: needs the points' config_hash column")
    facets = unique(d[spec.facet]) if spec.facet else [None]
    if len(facets) > MAX_PANELS:
        raise PlotError(f"{what}: {len(facets)} panels (at most {MAX_PANELS}); narrow it with where:")
    by_hash = {h: pc for _, pc, h in hashed_sweep(config)}
    picks = []
    for f in facets:
        sub = d if f is None else d[[same(v, f) for v in d[spec.facet]]]
        hashes = unique(sub["config_hash"])
        if len(hashes) != 1:
            raise PlotError(f"{what}: where: leaves {len(hashes)} points" + (f" for {spec.facet} = {label(f)}" if f is not None else "")
                            + "; pick one with where:")
        if hashes[0] not in by_hash:
            raise PlotError(f"{what}: point {hashes[0]} is not in the config's sweep")
        picks.append((f, by_hash[hashes[0]], sub.iloc[0]))
    name = spec.map or "image"
    results = []
    for _, pc, row in picks:
        h = str(row["config_hash"])
        res = _stored(h, name)
        if res is None:
            with tracking_reads() as reads:
                _, res = render_point(pc, options={"pixel_stats": True} if spec.kind == "heatmap" else None, h=h)
            if pc.point.kind == "render" and getattr(res, "ci95", None) is None:
                keep_pictures(h, res, [name], json.dumps(input_digests(reads)))
        results.append(res)
    plt = _plt()
    rows_md = []
    with matplotlib.rc_context(STYLE):
        nr, nc = grid_shape(len(picks))
        fig, axes = plt.subplots(nr, nc, figsize=(3.0 * nc + (1.6 if name == "tile.cull_reason" else 0.6), 2.8 * nr),
                                 squeeze=False)
        flat = [a for r in axes for a in r]
        norm = last = None
        if spec.kind == "heatmap" and name != "tile.cull_reason":
            for res in results:
                if name not in res.pixel_stats:
                    raise PlotError(f"{what}: map {name!r} is not a per-pixel map; known: "
                                    f"{', '.join(sorted(res.pixel_stats))}, tile.cull_reason")
            norm, log = map_norm([map_values(r.pixel_stats, name, int(pc.pipeline.tile_size))[0]
                                  for r, (_, pc, _) in zip(results, picks)])
        for ax, (f, pc, row), res in zip(flat, picks, results):
            title = facet_title(spec.facet, f) if f is not None else None
            tile = int(pc.pipeline.tile_size)
            if spec.kind == "image":
                from sim.png import linear_to_srgb8

                ax.imshow(linear_to_srgb8(res.image), interpolation="nearest")
                ax.set_xticks([])
                ax.set_yticks([])
                ax.grid(False)
                if title:
                    ax.set_title(title)
                rows_md.append(([label(f)] if f is not None else []) + [f"{res.image.shape[1]}x{res.image.shape[0]}"])
            elif name == "tile.cull_reason":
                draw_reason(ax, res.pixel_stats, tile, title=title)
                ax.grid(False)
                import sim

                reason, names = sim.pixel_stats.cull_reason(res.pixel_stats, tile)
                counts = [int((reason == i).sum()) for i in range(len(names))]
                rows_md.append(([label(f)] if f is not None else [])
                               + [", ".join(f"{REASON_LABELS.get(n, n)} {c}" for n, c in zip(names, counts) if c)])
            else:
                values, per_tile = map_values(res.pixel_stats, name, tile)
                last = draw_map(ax, values, map_label(name, per_tile), fig, title=title, norm=norm, colorbar=False)
                ax.grid(False)
                rows_md.append(([label(f)] if f is not None else [])
                               + [f"{int(res.pixel_stats[name].sum()):,}", f"{float(values.max()):,.0f}"])
        for a in flat[len(picks):]:
            a.set_visible(False)
        if last is not None:  # one colour bar, one scale for every panel
            cb = fig.colorbar(last, ax=flat[:len(picks)], fraction=0.046 / max(1, nc) * 2, pad=0.02)
            cb.set_label(map_label(name, name.startswith(TILE_LEVEL)) + (" (log scale; black = 0)" if log else ""),
                         fontsize=8)
            cb.ax.tick_params(labelsize=7)
        if spec.title:
            fig.suptitle(spec.title, fontsize=9)
        files = _save(fig, out_base, dpi=150)
        plt.close(fig)
    from .tables import md_table

    head = [value_label(spec.facet)] if spec.facet else []
    if spec.kind == "image":
        head += ["image size"]
    elif name == "tile.cull_reason":
        head += ["tiles by most frequent verdict"]
    else:
        head += [f"{name} frame total", "largest " + ("per tile" if name.startswith(TILE_LEVEL) else "per pixel")]
    return {"files": files, "markdown": md_table(head, rows_md), "fits": []}

"""Pictures of where the work of one frame goes: `rast5d render --heatmaps DIR` and the `heatmap` /
`image` plot kinds with `map:` (docs/reports.md). Each map of `Result.pixel_stats` (sim.pixel_stats)
becomes a PNG with a colour bar labelled from `sim.counter_docs()`; tile-level counters are summed
per screen tile; the tile cull reason is a categorical map with a titled legend."""
from __future__ import annotations

from pathlib import Path

import numpy as np

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


def draw_map(ax, values: np.ndarray, label: str, fig, title: str | None = None):
    """One map with a colour bar; a log colour scale when the non-zero values span two decades."""
    from matplotlib.colors import LogNorm

    nz = values[values > 0]
    log = nz.size > 0 and nz.max() / nz.min() >= 100
    data = np.ma.masked_where(values <= 0, values) if log else values
    im = ax.imshow(data, cmap="magma", interpolation="nearest",
                   norm=LogNorm(vmin=nz.min(), vmax=nz.max()) if log else None)
    ax.set_facecolor("black")
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)
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
        draw_map(ax, values, map_label(name, per_tile), fig,
                 title=f"{name} (frame total {int(stats[name].sum()):,})")
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

"""Shading and texture-cache results of issue 6 (part A), written to reports/paper/shading_study.md.

    .venv/bin/python -m experiments.shading_study [--only table3 thrash texcache hakura multiview]

Each study is a small, explicit sweep over sim.render (the declarative configs in configs/paper/
describe the same sweeps for the report machinery); the Markdown page states the settings, the
paper's numbers where there are any, and the departures. About 3-4 minutes on 2 cores.
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import models
import sim

from .plots import md_table

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "reports" / "paper"

_scenes: dict = {}


def scene(name):
    if name not in _scenes:
        _scenes[name] = models.named(name)
    return _scenes[name]


def camera(name, width, height, coc, **kw):
    hint = dict(scene(name).camera_hint or {})
    hint.update(width=width, height=height, coc_px=coc, **kw)
    hint.pop("aperture_radius", None)
    return sim.Camera(**hint)


def run(scene_obj, cam, table, hardware=None, **pipeline):
    r = sim.render(scene_obj, cam, table, sim.PipelineConfig(**pipeline), hardware=hardware)
    return r.flat_stats


# ---- 001 Table 3 ---------------------------------------------------------------------------------

TABLE3_PAPER = {"OUR": [1, 2, 4, 6, 9], "INTERVAL": [10, 12, 14, 16, 19]}
COCS = [0, 10, 20, 30, 50]


def study_table3():
    name, W, H, spp = "modern_hall", 256, 144, 64
    table = sim.SampleTable.stratified(spp=spp, seed=1)
    rows, raw = [], []
    for coc in COCS:
        cam = camera(name, W, H, coc)
        ss = run(scene(name), cam, table, algorithm="tile", tile_size=2, shading="per_sample")
        our = run(scene(name), cam, table, algorithm="tile", tile_size=2, shading="msaa")
        itv = run(scene(name), cam, table, algorithm="interval", shading="msaa")
        denom = ss["shade.lanes_live"]  # supersampling shades every sample that passes early-z
        raw.append((coc, our, itv, ss))
        rows.append([coc, f"{100 * our['shade.quad_requests'] / denom:.1f}%", f"{TABLE3_PAPER['OUR'][COCS.index(coc)]}%",
                     f"{100 * itv['shade.quad_requests'] / denom:.1f}%",
                     f"{TABLE3_PAPER['INTERVAL'][COCS.index(coc)]}%",
                     f"{our['shade.quad_requests'] / ss['shade.quad_requests']:.3f}",
                     f"{itv['shade.quad_requests'] / ss['shade.quad_requests']:.3f}",
                     f"{our['shade.lanes_helper'] / (4 * our['shade.quad_requests']):.2f}"])
    text = [
        "## 001 Table 3: quad shading requests relative to supersampling",
        "",
        f"`{name}` (the paper's Museum is not available; modern_hall is an interior of similar triangle sizes), "
        f"{W}x{H}, {spp} spp stratified, 2x2 tiles, lens grid 4x4. OUR = `tile` with `shading: msaa` (one shade "
        "per pixel per tile visit); INTERVAL = `interval` with `shading: msaa` (a visit is a lens-cell pass, so at "
        "best one shade per pixel per cell). Ratio = `shade.quad_requests` / samples shaded by supersampling "
        "(`shade.lanes_live` with `shading: per_sample`, early-z), which is the paper's normalisation "
        "(256 samples per 2x2 block at 64 spp). Also given: the ratio to supersampling's own quad requests "
        "(quads of one sample index over 2x2 pixels), and the helper-lane fraction of OUR's quads.",
        "",
    ]
    text += md_table(["CoC [px]", "OUR", "paper OUR", "INTERVAL", "paper INTERVAL", "OUR / SS quads",
                      "INTERVAL / SS quads", "OUR helper lanes"], rows)
    return text, raw


# ---- texture thrashing vs triangle size (001 §3) ---------------------------------------------------

def textured_square(edge_px, cam, depth):
    """A fronto-parallel square of edge_px pixels at `depth`, uvs 0..edge_px/512 so that a
    512-texel procedural texture maps about one texel per pixel (lambda ~ 0)."""
    s_y = 1.0 / math.tan(math.radians(cam.fov_y_deg) / 2)
    half = edge_px / (s_y * cam.height / depth)
    q = models.procedural.quad_triangles((0.0, 0.0, -depth), 2 * half, 2 * half)
    k = edge_px / 512
    uvs = np.array([[[0, 0], [k, 0], [k, k]], [[0, 0], [k, k], [0, k]]], np.float32)
    return models.Scene.from_arrays(q, uvs=uvs, texture=sim.texturing.procedural_texture(512, 7))


def study_thrash():
    W = H = 320
    spp, n_lens, coc = 64, 256, 10
    table = sim.SampleTable.interleaved(spp=spp, n_lens=n_lens, seed=1)
    rows = []
    for edge in (16, 32, 64, 128, 256):
        cam = sim.Camera(width=W, height=H, fov_y_deg=45.0, focus_distance=5.0, coc_px=coc)
        sc = textured_square(edge, cam, depth=10.0)
        line = [edge]
        for ways in (0, 4):
            hw = sim.HardwareConfig(tex_cache={"size_bytes": 16384, "ways": ways})
            res = {}
            for algo, shading in (("interleave", "per_sample"), ("tile", "per_sample"), ("tile", "msaa")):
                st = run(sc, cam, table, hardware=hw, algorithm=algo, shading=shading, texture_count=1,
                         texture_filter="bilinear", bin_size=320)
                res[algo, shading] = st
            il, tl, tm = res["interleave", "per_sample"], res["tile", "per_sample"], res["tile", "msaa"]
            bpx = [st["tex.cache.bytes_fetched"] / (edge * edge) for st in (il, tl, tm)]
            line += [f"{il['tex.cache.hits'] / il['tex.cache.accesses']:.4f}", *(f"{b:.1f}" for b in bpx),
                     f"{bpx[0] / bpx[1]:.1f}x",
                     f"{il['tex.cache.misses_cold']}/{il['tex.cache.misses_capacity']}/{il['tex.cache.misses_conflict']}"]
        rows.append(line)
    text = [
        "## Texture thrashing of INTERLEAVE vs triangle size (001 §3)",
        "",
        f"One fronto-parallel textured square (two triangles) of the given edge, defocused (CoC {coc} px at "
        f"infinity, at depth 10 with focus 5: {coc / 2:.0f} px blur), {W}x{W}, {spp} spp, interleaved table with "
        f"{n_lens} lens coordinates (001 §3's setting), one 512^2 procedural texture at about one texel per pixel, "
        "bilinear, blocked 4x4 layout, one 16 KB cache with 64-byte lines, fully associative (FA) and 4-way, "
        "one screen bin (so that binning does not bound the pass footprint). IL = INTERLEAVE, shading per "
        "sample (it supersamples); TILE per sample (SS) and with MSAA. B/px = `tex.cache.bytes_fetched` per "
        "covered pixel; the last column splits IL's misses into cold/capacity/conflict.",
        "",
    ]
    text += md_table(["edge [px]", "FA: hit IL", "B/px IL", "B/px TILE SS", "B/px TILE MSAA", "IL / TILE SS",
                      "IL misses c/cap/conf", "4-way: hit IL", "B/px IL", "B/px TILE SS", "B/px TILE MSAA",
                      "IL / TILE SS", "IL misses c/cap/conf"], rows)
    return text, rows


# ---- texture cache vs CoC and traversal order on textured scenes -------------------------------------

def study_texcache():
    W, H, spp, n_lens = 256, 144, 64, 256
    table = sim.SampleTable.interleaved(spp=spp, n_lens=n_lens, seed=1)
    rows = []
    for name in ("spot_wall", "modern_hall"):
        for coc in (0, 10, 30):
            cam = camera(name, W, H, coc)
            for kb in (16, 64):
                hw = sim.HardwareConfig(tex_cache={"size_bytes": kb * 1024})
                line = [name, coc, kb]
                for algo, shading in (("interleave", "per_sample"), ("tile", "per_sample"), ("tile", "msaa")):
                    st = run(scene(name), cam, table, hardware=hw, algorithm=algo, shading=shading, texture_count=1,
                             bin_size=256)
                    line += [f"{st['tex.cache.hits'] / max(1, st['tex.cache.accesses']):.4f}",
                             f"{st['tex.cache.bytes_fetched'] / st['frame.pixels']:.1f}"]
                rows.append(line)
    text = [
        "## Texture cache vs CoC and traversal order",
        "",
        f"{W}x{H}, {spp} spp, interleaved table with {n_lens} lens coordinates (INTERLEAVE needs one; `tile` uses "
        "the same table), one texture per shader (the scene's texture, procedural where a triangle has none), "
        "trilinear, blocked 4x4 layout, one 4-way cache with 64-byte lines, one screen bin. Hit rate = "
        "`tex.cache.hits / tex.cache.accesses`; B/px = `tex.cache.bytes_fetched / frame.pixels`.",
        "",
    ]
    text += md_table(["scene", "CoC", "cache KB", "hit IL", "B/px IL", "hit TILE SS", "B/px TILE SS",
                      "hit TILE MSAA", "B/px TILE MSAA"], rows)
    return text, rows


# ---- Hakura & Gupta 1997 ------------------------------------------------------------------------------

def study_hakura():
    name, W, H = "modern_hall", 256, 144
    rows = []
    for blur, coc, spp in (("pinhole", 0, 4), ("blur", 20, 16)):
        table = sim.SampleTable.stratified(spp=spp, seed=1)
        cam = camera(name, W, H, coc)
        for layout in ("blocked", "linear"):
            for kb in (4, 8, 16, 32, 64, 128):
                hw = sim.HardwareConfig(tex_cache={"size_bytes": kb * 1024})
                st = run(scene(name), cam, table, hardware=hw, algorithm="tile", shading="msaa", texture_count=1,
                         texture_layout=layout, texture_filter="trilinear", bin_size=256)
                miss = st["tex.cache.misses"] / max(1, st["tex.cache.accesses"])
                no_cache = 4 * st["tex.fetches"]  # every texel from memory
                rows.append([blur, layout, kb, f"{100 * miss:.2f}%", st["tex.cache.misses_cold"],
                             st["tex.cache.misses_capacity"], st["tex.cache.misses_conflict"],
                             f"{st['tex.cache.bytes_fetched'] / st['frame.pixels']:.1f}",
                             f"{no_cache / max(1, st['tex.cache.bytes_fetched']):.1f}x"])
    text = [
        "## Hakura & Gupta (1997) baseline: miss rate vs cache size, blocked vs linear",
        "",
        f"`{name}`, {W}x{H}, `tile` traversal (2x2 tiles) with MSAA shading (one shade per pixel per tile visit, "
        "as a conventional rasterizer), one texture, trilinear, one 4-way cache with 64-byte lines (blocked = 4x4 "
        "texels per line). Pinhole: CoC 0, 4 spp; blur: CoC 20, 16 spp. Miss rate per access (an access = the "
        "distinct lines of one bilinear footprint); saving = bytes without a cache (4 bytes per texel fetched) / "
        "bytes fetched with the cache. HG97: working sets of at most about 16 KB, 3-15x less bandwidth with a cache.",
        "",
    ]
    text += md_table(["view", "layout", "cache KB", "miss rate", "cold", "capacity", "conflict", "B/px",
                      "saving vs no cache"], rows)
    return text, rows


# ---- stereo and multi-view with the shading cache (002 §8) -------------------------------------------

class MultiViewCamera(sim.Camera):
    """V views on a camera line: the lens is V times wider in u than one view's (an oblong lens,
    002 §8 / Fig. 16); each view's samples use their own sub-interval of u."""

    def __init__(self, views, **kw):
        super().__init__(**kw)
        self.views = views

    def engine_params(self):
        p = super().engine_params()
        p["coc_x_px"] *= self.views
        return p


def multiview_table(views, spp_per_view, seed):
    parts = []
    for k in range(views):
        s = np.array(sim.SampleTable.stratified(spp=spp_per_view, seed=seed + k).samples("square"))
        s[..., 2] = -1 + (2 * k + (s[..., 2] + 1)) / views
        parts.append(s)
    return sim.SampleTable.from_array(np.concatenate(parts, axis=2), lens="square")


def study_multiview():
    name, W, H, spp_v = "spot_wall", 256, 256, 8
    rows, base = [], {}
    for coc, views in ((10, 1), (10, 2), (10, 7), (3, 1), (3, 2), (3, 7)):
        cam = MultiViewCamera(views, **{**scene(name).camera_hint, "width": W, "height": H, "coc_px": coc,
                                        "lens": "square"})
        table = multiview_table(views, spp_v, seed=11)
        cache = run(scene(name), cam, table, algorithm="tile", shading="cache", shading_cache_entries=1024)
        ss = run(scene(name), cam, table, algorithm="tile", shading="per_sample")
        inv, lanes = cache["shade.lanes_live"], cache["shade.invocations"]
        if views == 1:
            base = dict(inv=inv, lanes=lanes, ss=ss["shade.lanes_live"])
        rows.append([coc, views, views * spp_v, inv, f"{100 * (inv / base['inv'] - 1):+.1f}%", lanes,
                     f"{100 * (lanes / base['lanes'] - 1):+.1f}%", f"{cache['shade.cache_hits'] / max(1, cache['shade.cache_hits'] + cache['shade.cache_misses']):.3f}",
                     ss["shade.lanes_live"], f"{100 * (ss['shade.lanes_live'] / base['ss'] - 1):+.0f}%"])
    text = [
        "## Stereo and multi-view with the shading cache (002 §8)",
        "",
        f"`{name}` (moving cow, defocused wall), {W}x{H}, square lens; V views side by side on a camera line: the "
        f"lens is V times wider in u (CoC 10 or 3 px per view), view k's {spp_v} samples per pixel use the k-th "
        "u-interval (002 Fig. 16), so the table has 8V spp. `tile` (2x2), `shading: cache` with 1024 entries, "
        "key (triangle, pixel of the lens-centre view at shutter open), one cache per 64x64 bin. Invocations = "
        "shading-cache misses (`shade.lanes_live`); with helper lanes = `shade.invocations`. Supersampled "
        "shading is given for contrast. Paper: +10% for 2 views, +15% for 7 views vs 1 view.",
        "",
    ]
    text += md_table(["CoC per view", "views", "spp", "invocations", "vs 1 view", "lanes incl. helpers", "vs 1 view",
                      "cache hit rate", "supersampled shades", "vs 1 view"], rows)
    return text, rows


STUDIES = {"table3": study_table3, "thrash": study_thrash, "texcache": study_texcache, "hakura": study_hakura,
           "multiview": study_multiview}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", choices=list(STUDIES), default=list(STUDIES))
    args = ap.parse_args(argv)
    page = ["# Shading, texturing and the texture cache (issue 6)", "",
            "Generated by `.venv/bin/python -m experiments.shading_study` (model: docs/shading.md). "
            "Configs describing the same sweeps: `configs/paper/table3.yaml`, `texcache.yaml`, `hakura.yaml`, "
            "`multiview.yaml`.", ""]
    for key in args.only:
        t0 = time.time()
        text, _ = STUDIES[key]()
        page += text + ["", f"_({key}: {time.time() - t0:.0f} s)_", ""]
        print("\n".join(text), flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / ("shading_study.md" if len(args.only) == len(STUDIES) else f"shading_study_{'_'.join(args.only)}.md")
    path.write_text("\n".join(page) + "\n")
    print(f"wrote {path.relative_to(REPO)}")


if __name__ == "__main__":
    main()

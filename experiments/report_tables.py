"""Registered page tables that no plot spec can express (docs/reports.md §Escape hatch): each needs a
baseline row from elsewhere in the sweep. Placed with {{table:NAME}} in a config's outputs.text."""
from __future__ import annotations

import math

from .plots import md_table
from .report import derived_table

SCENE_ORDER = ["bunny", "spot", "modern_hall", "mixed_sizes"]

# 001 Table 2, StoneGiant: culled share and Gops for none / h_i / H_j / both / INTERVAL.
PAPER_T2 = {10: (["0%", "30%", "62%", "65%", "27%"], ["23", "19", "10", "10", "17"]),
            50: (["0%", "79%", "72%", "86%", "66%"], ["83", "24", "26", "18", "29"])}


def _ok(df):
    return df[df["status"] == "ok"] if "status" in df.columns else df


def _scenes(df) -> list:
    present = list(dict.fromkeys(df["scene.name"]))
    return [s for s in SCENE_ORDER if s in present] + [s for s in present if s not in SCENE_ORDER]


@derived_table("table2_culling")
def table2_culling(df, config) -> list[str]:
    """Culled share = 1 - tested / tested(no half-space test), per scene and R, beside the paper's."""
    df = _ok(df)
    modes = [("none", "tile", False, False), ("h_i", "tile", True, False), ("H_j", "tile", False, True),
             ("h_i+H_j", "tile", True, True), ("INTERVAL", "interval", True, True)]
    rows = []
    for s in _scenes(df):
        for coc in sorted(df["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            tested, gops = {}, {}
            for name, algo, h, H in modes:
                r = sub[(sub["pipeline.algorithm"] == algo) & (sub["pipeline.halfspace.h"] == h)
                        & (sub["pipeline.halfspace.H"] == H)]
                tested[name] = float(r["raster.samples_tested"].iloc[0]) if len(r) else math.nan
                gops[name] = float(r["ops.total"].iloc[0]) / 1e9 if len(r) else math.nan
            base = tested["none"]
            rows.append([s, f"{coc:g}", "culled"] + [f"{100 * (1 - tested[m[0]] / base):.0f}%" for m in modes])
            rows.append([s, f"{coc:g}", "Gops"] + [f"{gops[m[0]]:.2f}" for m in modes])
    for coc, (cull, g) in PAPER_T2.items():
        rows.append(["**paper: StoneGiant**", str(coc), "culled"] + cull)
        rows.append(["**paper: StoneGiant**", str(coc), "Gops"] + g)
    return md_table(["scene", "R", "row"] + [m[0] for m in modes], rows)


@derived_table("fig15_trends")
def fig15_trends(df, config) -> list[str]:
    """Is tile (2x2, and 1x1) the cheapest of the arbitrary-pattern algorithms at every CoC?"""
    df = _ok(df)
    lines = ["Trend checks (001 §6.2: OUR is the cheapest at every CoC):", ""]
    for s in _scenes(df):
        sub = df[df["scene.name"] == s]
        others = sub[sub["pipeline.algorithm"].isin(["bruteforce", "interval"])]

        def cheapest(tile_size):
            fails = []
            for c in sorted(sub["camera.coc_px"].unique()):
                mine = sub[(sub["camera.coc_px"] == c) & (sub["pipeline.algorithm"] == "tile")
                           & (sub["pipeline.tile_size"] == tile_size)]["ops.total"]
                best = others[others["camera.coc_px"] == c]["ops.total"].min()
                if len(mine) and not mine.iloc[0] <= best:
                    fails.append(f"CoC {c:g}: {mine.iloc[0] / best:.2f}x the best other")
            return "yes" if not fails else "no (" + "; ".join(fails) + ")"

        bf = sub[sub["pipeline.algorithm"] == "bruteforce"].sort_values("camera.coc_px")["ops.total"]
        growth = bf.iloc[-1] / bf.iloc[0] if len(bf) > 1 else math.nan
        lines.append(f"- {s}: `tile` 2x2 cheaper than bruteforce and interval at every CoC: **{cheapest(2)}**; "
                     f"`tile` 1x1: **{cheapest(1)}**; bruteforce ops grow {growth:.1f}x from the smallest to "
                     "the largest CoC.")
    lines += ["", "Where `tile` with 2x2 tiles loses to `interval` (micro-triangle workloads such as the bunny, "
              "close to the focus plane), the 2x2 tile is coarser than the triangles: the exact active region of a "
              "2x2 tile holds more samples than INTERVAL's per-pixel bounds for a lens cell. With 1x1 tiles `tile` "
              "competes again; the best tile size depends on the triangle-size distribution."]
    return lines


@derived_table("pareto_members")
def pareto_members(df, config) -> list[str]:
    """Which (sample-table kind, algorithm) pairs make up the RMSE Pareto front against each cost."""
    from .plots import pareto_front

    df = _ok(df)
    costs = [c for c in ("ops.total", "raster.samples_tested", "time.wall_s", "timing.cycles") if c in df.columns]
    rows = []
    for s in _scenes(df):
        sub = df[df["scene.name"] == s].dropna(subset=["metric.rmse"])
        for c in costs:
            sub_c = sub.dropna(subset=[c])
            idx = pareto_front(sub_c[c].to_numpy(float), sub_c["metric.rmse"].to_numpy(float))
            front = sub_c.iloc[idx]
            kinds = [f"{k}{'' if n != n or n is None else f' {int(n)}'}" for k, n in
                     zip(front["samples.kind"], front["samples.n_lens"])]
            members = {}
            for k, a, spp in zip(kinds, front["pipeline.algorithm"], front["samples.spp"]):
                members.setdefault(f"{k} / {a}", []).append(int(spp))
            text = "; ".join(f"{m} (spp {', '.join(map(str, v))})"
                             for m, v in sorted(members.items(), key=lambda kv: -len(kv[1])))
            rows.append([s, c, str(len(front)), text])
    return (["Pareto-front members (sample-table kind / algorithm, with the spp of each front point):", ""]
            + md_table(["scene", "cost", "front points", "members"], rows))


# 002 §8: shader-invocation increase with a 1024-entry shading cache, against one view.
PAPER_MULTIVIEW = {2: "+10%", 7: "+15%"}


@derived_table("multiview_increase")
def multiview_increase(df, config) -> list[str]:
    """Shader invocations (shading-cache misses) for V views relative to one view, per CoC."""
    df = _ok(df)
    rows = []
    for coc in sorted(df["camera.coc_px"].unique()):
        sub = df[df["camera.coc_px"] == coc]
        base = sub[sub["samples.views"] == 1]
        if not len(base):
            continue
        b = float(base["shade.lanes_live"].iloc[0])
        for views in sorted(sub["samples.views"].unique()):
            r = sub[sub["samples.views"] == views]
            inv = float(r["shade.lanes_live"].iloc[0])
            hit = float(r["shade.cache_hit_rate"].iloc[0]) if "shade.cache_hit_rate" in r else math.nan
            rows.append([f"{coc:g}", str(int(views)), str(int(r["samples.spp"].iloc[0])), f"{inv:.0f}",
                         f"{100 * (inv / b - 1):+.1f}%", f"{hit:.3f}", PAPER_MULTIVIEW.get(int(views), "")])
    return md_table(["CoC [px] (whole lens)", "views", "spp (all views)", "shader invocations", "vs 1 view",
                     "cache hit rate", "paper"], rows)

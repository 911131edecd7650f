"""Tables of a report page: the data table of a plot spec (our numbers, the paper's beside them),
the power-law fit table, and the named tables that no plot spec can express because each needs a
baseline row from elsewhere in the sweep (docs/reports.md §Named tables), placed with {{table:NAME}}
in a config's outputs.text. TABLES is a plain registry filled here; nothing imports back."""
from __future__ import annotations

import math

import numpy as np

from .frames import PROSE_DATA, cell, fmt, ok_rows, label, missing, pareto_front, paper_value, same, sorted_x, unique


def md_table(header: list, rows: list[list]) -> list[str]:
    """A Markdown table; cells are formatted with str()."""
    return (["| " + " | ".join(map(str, header)) + " |", "|" + "---|" * len(header)]
            + ["| " + " | ".join(map(str, r)) + " |" for r in rows])


def data_table(spec, d, hues) -> list[str]:
    """Our numbers, one row per (facet, x) and one column per (y, hue), paper columns beside them."""
    facets = unique(d[spec.facet]) if spec.facet else [None]
    if spec.kind == "scatter":
        cols = list(dict.fromkeys(c for c in (spec.facet, spec.hue, spec.style, *spec.columns, spec.x, spec.ys[0]) if c))
        rows = [[fmt(r[c], spec.format) for c in cols] for _, r in d[cols].iterrows()]
        return md_table(cols, rows)
    if spec.x is None:  # plain listing of the y columns
        cols = list(dict.fromkeys([c for c in (spec.facet, spec.hue) if c] + spec.columns + spec.ys))
        rows = [[fmt(r[c], spec.format) for c in cols] for _, r in d[cols].iterrows()]
        return md_table(cols, rows)
    groups = []  # (hue, y, header)
    for h in hues:
        for y in spec.ys:
            if h is None:
                header = y
            else:
                header = label(h) if len(spec.ys) == 1 else f"{y} {label(h)}"
            groups.append((h, y, header))
    header = ([spec.facet] if spec.facet else []) + [spec.x]
    paper_groups = []
    for h, y, head in groups:
        header.append(head)
        g = h if h is not None else y
        if any(same(g, k) for k in spec.paper):
            header.append(f"{head} (paper)")
            paper_groups.append(g)
    extra = [k for k in spec.paper if not any(same(k, (h if h is not None else y)) for h, y, _ in groups)]
    header += [f"{label(k)} (paper)" for k in extra]
    rows = []
    for f in facets:
        df_f = d if f is None else d[[same(v, f) for v in d[spec.facet]]]
        xs = sorted_x(list(df_f[spec.x]) + [x for k in spec.paper for x in spec.paper[k]]) if f is facets[0] \
            else sorted_x(df_f[spec.x])
        for x in xs:
            r = ([label(f)] if spec.facet else []) + [label(x)]
            for h, y, _ in groups:
                keys = {spec.x: x}
                if h is not None:
                    keys[spec.hue] = h
                v, n = cell(df_f, keys, y)
                r.append(fmt(v, spec.format) + (f" (mean of {n})" if n > 1 else ""))
                g = h if h is not None else y
                if g in paper_groups:
                    p = paper_value(spec, g, x)
                    r.append("" if p is None else fmt(p, spec.format))
            for k in extra:
                p = paper_value(spec, k, x)
                r.append("" if p is None else fmt(p, spec.format))
            rows.append(r)
    return md_table(header, rows)


def powerlaw_table(spec, d, hues) -> tuple[list[str], list[dict]]:
    """Fit y = c x^-alpha per (facet, hue) in log-log (least squares over the mean y at each x)."""
    facets = unique(d[spec.facet]) if spec.facet else [None]
    y = spec.ys[0]
    rows, fits = [], []
    for f in facets:
        df_f = d if f is None else d[[same(v, f) for v in d[spec.facet]]]
        for h in hues:
            sub = df_f if h is None else df_f[[same(v, h) for v in df_f[spec.hue]]]
            xs = [x for x in sorted_x(sub[spec.x])]
            pts = [(float(x), cell(sub, {spec.x: x}, y)[0]) for x in xs]
            pts = [(a, b) for a, b in pts if a > 0 and b > 0 and np.isfinite(b)]
            if len(pts) < 2:
                continue
            lx, ly = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            slope, icpt = np.polyfit(lx, ly, 1)
            pred = slope * lx + icpt
            ss = float(np.sum((ly - ly.mean()) ** 2))
            r2 = 1.0 - float(np.sum((ly - pred) ** 2)) / ss if ss > 0 else 1.0
            fit = {"facet": f, "hue": h, "alpha": -float(slope), "r2": r2, "n": len(pts),
                   "x_min": pts[0][0], "x_max": pts[-1][0]}
            fits.append(fit)
            paper = paper_value(spec, h if h is not None else y, "alpha") if spec.paper else None
            rows.append(([label(f)] if spec.facet else []) + ([label(h)] if spec.hue else [])
                        + [f"{fit['alpha']:.3f}", f"{r2:.3f}", str(len(pts)), f"{pts[0][0]:g}-{pts[-1][0]:g}"]
                        + ([fmt(paper)] if spec.paper else []))
    header = ([spec.facet] if spec.facet else []) + ([spec.hue] if spec.hue else []) + [
        f"alpha ({y} ∝ {spec.x}^-alpha)", "R²", "points", f"{spec.x} range"] + (["paper alpha"] if spec.paper else [])
    return md_table(header, rows), fits


# ---- named tables --------------------------------------------------------------------------------

TABLES: dict = {}
# name -> the result columns (prefixes ending in ".") a named table reads besides the rows' config; a page
# that places the table must read them (tests/test_prose.py: timing figures need a page that reads timing)
READS: dict = {}
# name -> fn(df, config) -> DataFrame: a named table's values, tidy (one row per cell, df.attrs["keys"] the
# key columns), for the page prose: {NAME.column[key=value]} (experiments/report/prose.py)
VALUES: dict = {}


def named_table(name: str, reads: tuple[str, ...] = ()):
    """Register a page table fn(df, config) -> Markdown lines under ``name`` (for {{table:NAME}}); ``reads``:
    the result columns it needs beyond those any render row has (e.g. "timing."). The escape hatch: prefer
    `derived:` columns and `table` plots."""
    def deco(fn):
        TABLES[name] = fn
        READS[name] = tuple(reads)
        return fn

    return deco


def named_values(name: str):
    """Register fn(df, config) -> DataFrame (tidy, ``attrs["keys"]`` its key columns) as the values the
    prose may quote as {NAME.column[key=value]}; a named table of the same name prints the same values."""
    def deco(fn):
        def tidy(df, config):
            out = fn(df, config)
            out.attrs["keys"] = list(out.attrs.get("keys", []))
            return out

        VALUES[name] = tidy
        return fn

    return deco


SCENE_ORDER = ["bunny", "spot", "modern_hall", "mixed_sizes"]

# [Akenine-Möller 2012] Table 2, StoneGiant: culled share and Gops for none / h_i / H_j / both / INTERVAL.
PAPER_T2 = {10: (["0%", "30%", "62%", "65%", "27%"], ["23", "19", "10", "10", "17"]),
            50: (["0%", "79%", "72%", "86%", "66%"], ["83", "24", "26", "18", "29"])}


def page_rows(name: str):
    """The rows (derived columns included) of the section of config ``name`` on the page being written, for
    a named table or value table that joins several sections of its page (the hardware page joins error
    curves, costs and re-timed variants); outside `rast5d report` (a config's own page) the stored result
    table of ``name`` (experiments.load). KeyError naming the config when neither has it."""
    if name in PROSE_DATA:
        return ok_rows(PROSE_DATA[name][2])
    from ..run.store import load

    try:
        return ok_rows(load(name))
    except (FileNotFoundError, OSError, KeyError, ValueError):
        raise KeyError(f"page_rows: no rows of config {name!r} on this page or in the result store") from None


def algorithm_fact(algorithm, name: str):
    """A traversal-registry fact (sim.algorithm_info) of an algorithm name, or None for an unknown one."""
    import sim

    try:
        return getattr(sim.algorithm_info(str(algorithm)), name)
    except sim.ConfigError:
        return None


def is_lines(algorithm) -> bool:
    """The algorithm tests line samples (sim.algorithm_info(name).samples)."""
    return algorithm_fact(algorithm, "samples") == "lines"


def is_gpu(algorithm) -> bool:
    """The algorithm runs the conventional-GPU pipeline (sim.algorithm_info(name).pipeline)."""
    return algorithm_fact(algorithm, "pipeline") == "gpu"


def _lines_mask(df) -> np.ndarray:
    return np.array([is_lines(a) for a in df["pipeline.algorithm"]], dtype=bool)


def _first(df, keys: dict):
    """The first row whose columns equal keys, or None."""
    for k, v in keys.items():
        df = df[df[k] == v]
    return df.iloc[0] if len(df) else None


def _scenes(df) -> list:
    present = list(dict.fromkeys(df["scene.name"]))
    return [s for s in SCENE_ORDER if s in present] + [s for s in present if s not in SCENE_ORDER]


T2_MODES = [("none", "tile", False, False), ("h_i", "tile", True, False), ("H_j", "tile", False, True),
            ("h_i+H_j", "tile", True, True), ("INTERVAL", "interval", True, True)]


@named_values("table2_culling")
def table2_values(df, config):
    """Per scene, R, mode (none, h_i, H_j, h_i+H_j, INTERVAL) and cost model: the culled share
    1 - tested / tested(no half-space test) and Gops."""
    import pandas as pd

    df = ok_rows(df)
    rows = []
    for s in _scenes(df):
        for coc in sorted(df["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            models = list(dict.fromkeys(sub["pipeline.cost_model"])) if "pipeline.cost_model" in sub.columns else [None]
            tested = {}
            for name, algo, h, H in T2_MODES:
                r = sub[(sub["pipeline.algorithm"] == algo) & (sub["pipeline.halfspace.h"] == h)
                        & (sub["pipeline.halfspace.H"] == H)]
                tested[name] = float(r["raster.samples_tested"].iloc[0]) if len(r) else math.nan
                for model in models:  # the samples tested do not depend on the cost model (oracle off)
                    rm = r if model is None else r[r["pipeline.cost_model"] == model]
                    rows.append({"scene": s, "R": float(coc), "mode": name, "cost_model": model,
                                 "tested": tested[name], "gops": float(rm["ops.total"].iloc[0]) / 1e9 if len(rm) else math.nan})
    out = pd.DataFrame(rows)
    base = out[out["mode"] == "none"].set_index(["scene", "R", "cost_model"])["tested"]
    out["culled"] = [1 - t / base.get((s, r, m), math.nan) for s, r, m, t in
                     zip(out["scene"], out["R"], out["cost_model"], out["tested"])]
    out.attrs["keys"] = ["scene", "R", "mode", "cost_model"]
    return out


@named_table("table2_culling")
def table2_culling(df, config) -> list[str]:
    """Culled share = 1 - tested / tested(no half-space test), per scene and R, beside the paper's."""
    v = table2_values(df, config)
    rows = []
    for (s, coc), g in v.groupby(["scene", "R"], sort=False):
        first = g[g["cost_model"] == g["cost_model"].iloc[0]]
        culled = dict(zip(first["mode"], first["culled"]))
        rows.append([s, f"{coc:g}", "culled"] + [f"{100 * culled[m[0]]:.0f}%" for m in T2_MODES])
        for model, gm in g.groupby("cost_model", sort=False):
            gops = dict(zip(gm["mode"], gm["gops"]))
            rows.append([s, f"{coc:g}", "Gops" if model is None else f"Gops ({model})"]
                        + [f"{gops[m[0]]:.2f}" for m in T2_MODES])
    for coc, (cull, g) in PAPER_T2.items():
        rows.append(["**paper: StoneGiant**", str(coc), "culled"] + cull)
        rows.append(["**paper: StoneGiant**", str(coc), "Gops"] + g)
    return md_table(["scene", "R", "row"] + [m[0] for m in T2_MODES], rows)


@named_table("fig15_trends")
def fig15_trends(df, config) -> list[str]:
    """Is tile (2x2, and 1x1) the cheapest of the arbitrary-pattern algorithms at every CoC?"""
    df = ok_rows(df)
    lines = ["Trend checks ([Akenine-Möller 2012] §6.2: OUR is the cheapest at every CoC):", ""]
    models = list(dict.fromkeys(df["pipeline.cost_model"])) if "pipeline.cost_model" in df.columns else [None]
    losing = []
    for s, model in [(s, m) for s in _scenes(df) for m in models]:
        sub = df[df["scene.name"] == s]
        if model is not None:
            sub = sub[sub["pipeline.cost_model"] == model]
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

        two, one = cheapest(2), cheapest(1)
        if two != "yes":
            losing.append((s, one == "yes"))
        bf = sub[sub["pipeline.algorithm"] == "bruteforce"].sort_values("camera.coc_px")["ops.total"]
        growth = bf.iloc[-1] / bf.iloc[0] if len(bf) > 1 else math.nan
        where = s if model is None else f"{s} ({model})"
        lines.append(f"- {where}: `tile` 2x2 cheaper than bruteforce and interval at every CoC: **{two}**; "
                     f"`tile` 1x1: **{one}**; bruteforce ops grow {growth:.1f}x from the smallest to "
                     "the largest CoC.")
    if losing:  # where the paper's claim does not hold here, and what 1x1 tiles do there
        names = ", ".join(s for s, _ in losing)
        rescued = [s for s, ok in losing if ok]
        lines += ["", f"Where `tile` with 2x2 tiles loses ({names}), the 2x2 tile is coarser than the triangles: the "
                  "exact active region of a 2x2 tile holds more samples than INTERVAL's per-pixel bounds for a lens "
                  "cell." + (f" With 1x1 tiles `tile` is the cheapest at every CoC on {', '.join(rescued)}." if rescued
                             else "")]
    return lines


@named_table("pareto_members", reads=("timing.",))
def pareto_members(df, config) -> list[str]:
    """Which (sample-table kind, algorithm) pairs make up the RMSE Pareto front against each cost."""
    df = ok_rows(df)
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


# [Nilsson 2012] §8: shader-invocation increase with a 1024-entry shading cache, against one view.
PAPER_MULTIVIEW = {2: "+10%", 7: "+15%"}


@named_table("multiview_increase")
def multiview_increase(df, config) -> list[str]:
    """Shader invocations (shading-cache misses) for V views relative to one view, per CoC."""
    df = ok_rows(df)
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


# [Akenine-Möller 2012] Table 3: quad shading requests / supersampled shades for OUR and INTERVAL.
PAPER_T3 = {"tile": {0: 1, 10: 2, 20: 4, 30: 6, 50: 9}, "interval": {0: 10, 10: 12, 20: 14, 30: 16, 50: 19}}


@named_table("table3_supersampling")
def table3_supersampling(df, config) -> list[str]:
    """Per CoC: quad requests of tile+msaa (OUR) and interval+msaa relative to the samples supersampling
    shades (shade.lanes_live of the per_sample row) and to supersampling's own quad requests; OUR's
    helper-lane share of its quads."""
    df = ok_rows(df)
    rows = []
    for coc in sorted(df["camera.coc_px"].unique()):
        sub = df[df["camera.coc_px"] == coc]

        ss, our, itv = (_first(sub, {"pipeline.algorithm": a, "pipeline.shading": sh})
                        for a, sh in (("tile", "per_sample"), ("tile", "msaa"), ("interval", "msaa")))
        if ss is None or our is None or itv is None:
            continue
        shades = float(ss["shade.lanes_live"])
        rows.append([f"{coc:g}", f"{100 * our['shade.quad_requests'] / shades:.1f}%",
                     f"{PAPER_T3['tile'].get(int(coc), '')}%", f"{100 * itv['shade.quad_requests'] / shades:.1f}%",
                     f"{PAPER_T3['interval'].get(int(coc), '')}%",
                     f"{our['shade.quad_requests'] / ss['shade.quad_requests']:.3f}",
                     f"{itv['shade.quad_requests'] / ss['shade.quad_requests']:.3f}",
                     f"{our['shade.lanes_helper'] / (4 * our['shade.quad_requests']):.2f}"])
    return md_table(["CoC [px]", "OUR", "paper OUR", "INTERVAL", "paper INTERVAL", "OUR / SS quads",
                     "INTERVAL / SS quads", "OUR helper lanes"], rows)


@named_table("thrash_traffic")
def thrash_traffic(df, config) -> list[str]:
    """Per square edge and cache associativity: INTERLEAVE's hit rate, texture bytes per covered pixel of
    INTERLEAVE and of tile (per sample and MSAA), their ratio, and INTERLEAVE's cold/capacity/conflict misses."""
    df = ok_rows(df)
    rows = []
    for edge in sorted(df["scene.params.edge_px"].unique()):
        line = [f"{edge:g}"]
        for ways in sorted(df["hardware.tex_cache.ways"].unique()):
            sub = df[(df["scene.params.edge_px"] == edge) & (df["hardware.tex_cache.ways"] == ways)]

            il, tl, tm = (_first(sub, {"pipeline.algorithm": a, "pipeline.shading": sh})
                          for a, sh in (("interleave", "per_sample"), ("tile", "per_sample"), ("tile", "msaa")))
            bpx = [st["tex.cache.bytes_fetched"] / (edge * edge) for st in (il, tl, tm)]
            line += [f"{il['tex.cache.hits'] / il['tex.cache.accesses']:.4f}", *(f"{b:.1f}" for b in bpx),
                     f"{bpx[0] / bpx[1]:.1f}x",
                     f"{int(il['tex.cache.misses_cold'])}/{int(il['tex.cache.misses_capacity'])}/"
                     f"{int(il['tex.cache.misses_conflict'])}"]
        rows.append(line)
    ways = [("FA" if w == 0 else f"{int(w)}-way") for w in sorted(df["hardware.tex_cache.ways"].unique())]
    header = ["edge [px]"]
    for w in ways:
        header += [f"{w}: hit IL", "B/px IL", "B/px TILE SS", "B/px TILE MSAA", "IL / TILE SS", "IL misses c/cap/conf"]
    return md_table(header, rows)


@named_table("zcull_savings")
def zcull_savings(df, config) -> list[str]:
    """Per scene and CoC: HiZ off against on (pipeline.hiz.enabled), pairs culled by zmax and zmin, depth
    bytes saved, HiZ traffic, and the sample tests saved."""
    df = ok_rows(df)
    keys = [c for c in ("scene.params.order", "scene.params.layers", "camera.coc_px", "scene.params.motion_px")
            if c in df.columns]
    rows = []
    for _, on in df[df["pipeline.hiz.enabled"] == True].iterrows():  # noqa: E712 - a pandas column
        match = df["pipeline.hiz.enabled"] == False  # noqa: E712
        for k in keys:
            match &= df[k].isna() if missing(on[k]) else df[k] == on[k]
        off = df[match]
        if not len(off):
            continue
        off = off.iloc[0]
        order = on.get("scene.params.order")
        name = "front_to_back" if missing(order) else str(order)
        motion = on.get("scene.params.motion_px")
        if on["camera.coc_px"] or not missing(motion):
            name += f", CoC {on['camera.coc_px']:g}, motion {0 if missing(motion) else motion:g} px"
        bytes_off = off["depth.bytes_read"] + off["depth.bytes_written"]
        bytes_on = on["depth.bytes_read"] + on["depth.bytes_written"]
        hiz = on["hiz.bytes_read"] + on["hiz.bytes_written"]
        pairs = on["zcull.pairs"]
        rows.append([name, f"{on['scene.params.layers']:g}", f"{int(pairs):,}",
                     f"{100 * on['zcull.pairs_culled'] / pairs:.1f}", f"{100 * on['zcull.pairs_zmin'] / pairs:.1f}",
                     f"{int(bytes_off):,}", f"{int(bytes_on):,}", f"{100 * (1 - bytes_on / bytes_off):.1f}",
                     f"{int(hiz):,}", f"{100 * (1 - (bytes_on + hiz) / bytes_off):.1f}",
                     f"{100 * (1 - on['raster.samples_tested'] / off['raster.samples_tested']):.1f}"])
    return md_table(["order", "layers", "pairs", "zmax-culled %", "zmin (no reads) %", "depth bytes off",
                     "depth bytes on", "depth bytes saved %", "HiZ bytes", "saved incl. HiZ %",
                     "sample tests saved %"], rows)


@named_table("multiview_wide")
def multiview_wide(df, config) -> list[str]:
    """Per CoC and number of views: shading-cache misses and lanes (with helpers) of `shading: cache`, its
    hit rate, and the supersampled shades (`shading: per_sample`), each relative to one view."""
    df = ok_rows(df)
    rows = []
    for coc in sorted(df["camera.coc_px"].unique(), reverse=True):
        sub = df[df["camera.coc_px"] == coc]

        def one(views, shading):
            return _first(sub, {"samples.views": views, "pipeline.shading": shading})

        base, base_ss = one(1, "cache"), one(1, "per_sample")
        if base is None or base_ss is None:
            continue
        for views in sorted(sub["samples.views"].unique()):
            c, ss = one(views, "cache"), one(views, "per_sample")
            if c is None or ss is None:
                continue
            inv, lanes, shades = (float(c["shade.lanes_live"]), float(c["shade.invocations"]),
                                  float(ss["shade.lanes_live"]))
            hits, misses = float(c["shade.cache_hits"]), float(c["shade.cache_misses"])
            rows.append([f"{coc:g}", str(int(views)), str(int(c["samples.spp"])), f"{inv:,.0f}",
                         f"{100 * (inv / base['shade.lanes_live'] - 1):+.1f}%", f"{lanes:,.0f}",
                         f"{100 * (lanes / base['shade.invocations'] - 1):+.1f}%",
                         f"{hits / max(1.0, hits + misses):.3f}",
                         f"{shades:,.0f}", f"{100 * (shades / base_ss['shade.lanes_live'] - 1):+.0f}%",
                         PAPER_MULTIVIEW.get(int(views), "")])
    return md_table(["CoC per view", "views", "spp", "invocations", "vs 1 view", "lanes incl. helpers", "vs 1 view",
                     "cache hit rate", "supersampled shades", "vs 1 view", "paper"], rows)


# ---- line samples, level of detail and the methods page (configs/paper/methods.yaml) -------------

def _col(df, name, default=math.nan):
    return df[name] if name in df.columns else [default] * len(df)


def _on(df, name) -> np.ndarray:
    """Boolean mask: the switch column `name` is true (a sweep that leaves it unset stores nan)."""
    return np.array([str(v) == "True" for v in _col(df, name, False)], dtype=bool)


def method_label(row) -> str:
    """'stratified 64 / tile', 'lines 16', 'lines 16 clip', with ' +LoD' when level of detail is on."""
    get = row.get if hasattr(row, "get") else (lambda k, d=None: d)
    if is_lines(get("pipeline.algorithm")):
        n = get("samples.n_lines")
        s = f"lines {int(n) if n == n and n is not None else '?'}"
        if str(get("pipeline.lines.tile_clip")) == "True":
            s += " clip"
    else:
        s = f"{get('samples.kind')} {int(get('samples.spp'))} / {get('pipeline.algorithm')}"
    if str(get("pipeline.lod.enabled")) == "True":
        s += " +LoD"
    return s


def _work(r) -> float:
    """Every counted operation: ops.total + ops.interp + ops.segments (the line samples' buffers and
    composite, and every method's depth and colour interpolation)."""
    seg = r.get("ops.segments", 0.0)
    return float(r["ops.total"]) + float(r.get("ops.interp", 0.0)) + (0.0 if seg != seg else float(seg))


_T95 = {1: 12.71, 2: 4.30, 3: 3.18, 4: 2.78, 5: 2.57, 6: 2.45, 7: 2.36, 8: 2.31, 9: 2.26, 10: 2.23}


def _fit_alpha(x, y):
    """Least squares log y = c - alpha log x: (alpha, 95% half-width, n); half-width nan with n < 3."""
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    n = len(x)
    if n < 2:
        return math.nan, math.nan, n
    slope, icpt = np.polyfit(x, y, 1)
    if n < 3:
        return -float(slope), math.nan, n
    resid = y - (slope * x + icpt)
    se = math.sqrt(float(np.sum(resid ** 2)) / (n - 2) / float(np.sum((x - x.mean()) ** 2)))
    return -float(slope), _T95.get(n - 2, 2.0) * se, n


def _families(sub):
    """(family name, rows) of the methods whose error falls with work: points per (kind, algorithm),
    lines, lines with the tile clip, each with level of detail off and (where swept) on."""
    out = []
    for lod in (False, True):
        part = sub[_on(sub, "pipeline.lod.enabled") == lod]
        tag = " +LoD" if lod else ""
        pts = part[~_lines_mask(part)]
        for (kind, algo), g in pts.groupby(["samples.kind", "pipeline.algorithm"]):
            if g["samples.spp"].nunique() >= 2:
                out.append((f"points {kind} / {algo}{tag}", g))
        is_line = _lines_mask(part)
        for clip in (False, True):
            ln = part[is_line & (_on(part, "pipeline.lines.tile_clip") == clip)]
            if len(ln) >= 2:
                out.append((f"lines{' clip' if clip else ''}{tag}", ln))
    return out


@named_table("methods_table", reads=("timing.",))
def methods_table(df, config) -> list[str]:
    """Scene x CoC x method: work, estimated cycles, wall time, RMSE and FLIP."""
    df = ok_rows(df)
    rows = []
    for s in _scenes(df):
        for coc in sorted(df[df["scene.name"] == s]["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            recs = sorted((r for _, r in sub.iterrows()), key=lambda r: (is_lines(r["pipeline.algorithm"]), _work(r)))
            for r in recs:
                rows.append([s, f"{coc:g}", method_label(r), f"{_work(r):.3g}", f"{float(r['ops.total']):.3g}",
                             fmt(r.get("timing.cycles", math.nan), "{:.3g}"), f"{float(r['time.wall_s']):.2f}",
                             f"{float(r['metric.rmse']):.4f}", fmt(r.get("metric.flip", math.nan), "{:.4f}")])
    return md_table(["scene", "CoC", "method", "ops (all)", "ops.total", "est. cycles", "wall [s]", "RMSE", "FLIP"], rows)


@named_values("methods_alpha")
def methods_alpha_values(df, config):
    """alpha in RMSE ∝ work^-alpha per (scene, CoC, method family), its 95% half-width and points; an
    interleaved family also before its lens floor (`before_floor` true)."""
    import pandas as pd

    df = ok_rows(df).dropna(subset=["metric.rmse"])
    rows = []
    for s in _scenes(df):
        for coc in sorted(df[df["scene.name"] == s]["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            for fam, g in _families(sub):
                parts = [(fam, g, False, math.nan)]
                pre = _before_lens_floor(g)
                if pre is not None:
                    parts.append((fam, pre[0], True, pre[1]))
                for name, part, before, n_lens in parts:
                    work = [_work(r) for _, r in part.iterrows()]
                    a, hw, n = _fit_alpha(work, part["metric.rmse"].to_numpy(float))
                    rows.append({"scene": s, "coc": float(coc), "family": name, "before_floor": before, "n_lens": n_lens,
                                 "alpha": a, "halfwidth": hw, "points": n})
    out = pd.DataFrame(rows)
    out.attrs["keys"] = ["scene", "coc", "family", "before_floor"]
    return out


@named_table("methods_alpha")
def methods_alpha(df, config) -> list[str]:
    """alpha in RMSE ∝ work^-alpha per method family, with a 95% confidence interval (t, n - 2 dof)."""
    rows = []
    for r in methods_alpha_values(df, config).itertuples():
        name = r.family + (f" (spp ≤ {int(r.n_lens)}, before the floor)" if r.before_floor else "")
        ci = "" if r.halfwidth != r.halfwidth else f"[{r.alpha - r.halfwidth:.2f}, {r.alpha + r.halfwidth:.2f}]"
        rows.append([r.scene, f"{r.coc:g}", name, f"{r.alpha:.2f}", ci, str(r.points)])
    return md_table(["scene", "CoC", "method family", "alpha (RMSE ∝ ops^-alpha)", "95% CI", "points"], rows)


def _before_lens_floor(g):
    """An interleaved family (N discrete lens positions) converges to the N-point lens average, not to
    the disk's integral: past spp = N its error flattens onto that bias. (the points with spp <= N,
    N) when the family also has points beyond N and at least three up to it, else None."""
    n_lens = np.asarray(_col(g, "samples.n_lens"), float)
    if not np.isfinite(n_lens).any():
        return None
    n = float(np.nanmax(n_lens))
    spp = g["samples.spp"].to_numpy(float)
    if (spp <= n).sum() < 3 or not (spp > n).any():
        return None
    return g[spp <= n], n


def _interp_work(g, target, cost=None):
    """Work (or another cost, `cost(row)`, e.g. wall time) a point-sample family needs to reach RMSE
    `target` (log-log interpolation between the two bracketing points, ordered by work; extrapolated
    along the last segment), or nan."""
    cost = cost or _work
    pts = sorted(((_work(r), float(r["metric.rmse"]), float(cost(r))) for _, r in g.iterrows()), key=lambda p: p[0])
    pts = [(c, e) for _w, e, c in pts]
    if len(pts) < 2:
        return math.nan
    for (w0, e0), (w1, e1) in zip(pts, pts[1:]):
        if min(e0, e1) <= target <= max(e0, e1) or (w1, e1) == pts[-1]:
            if e0 == e1:
                return w0
            t = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(w0) + t * (math.log(w1) - math.log(w0)))
    return math.nan


def _wall(r) -> float:
    return float(r["time.wall_s"])


def _cycles(r) -> float:
    return float(r.get("timing.cycles", math.nan))


# [Tzeng 2012] Table 1: frames per second of its point sampler (256 point samples per pixel) and of its line
# sampler (16 lines per pixel) in the same tiled GPU renderer (GTX 580, 800 x 800), per mesh.
PAPER_TZENG_T1 = {"Dragon": (0.64, 2.86), "Cessna": (2.12, 9.01), "Hand": (1.12, 4.47), "Geckcheck": (11.54, 49.31),
                  "SDCC": (0.49, 2.04), "Teapot": (1.93, 5.11)}


@named_values("methods_claim")
def methods_claim_values(df, config):
    """Per scene and CoC, 16 lines against 256 points: both RMSEs and FLIPs, the operations of 256 points
    (tile, bruteforce) over the lines', and at equal RMSE (the point family's cost interpolated to the 16
    lines' RMSE along its spp sweep) the work, cycles and wall time of tile and bruteforce over the lines'."""
    import pandas as pd

    df = ok_rows(df)
    rows = []
    for s in _scenes(df):
        for coc in sorted(df[df["scene.name"] == s]["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)
                     & ~_on(df, "pipeline.lod.enabled")]
            is16 = _lines_mask(sub) & (np.asarray(_col(sub, "samples.n_lines"), float) == 16)
            ln = sub[is16 & ~_on(sub, "pipeline.lines.tile_clip")]
            lc = sub[is16 & _on(sub, "pipeline.lines.tile_clip")]
            tile = sub[(sub["pipeline.algorithm"] == "tile") & (sub["samples.kind"] == "stratified")]
            bf = sub[(sub["pipeline.algorithm"] == "bruteforce") & (sub["samples.kind"] == "stratified")]
            p256 = tile[tile["samples.spp"] == 256]
            b256 = bf[bf["samples.spp"] == 256]
            if not len(ln) or not len(p256):
                continue
            l, p = ln.iloc[0], p256.iloc[0]
            c = lc.iloc[0] if len(lc) else None
            lw, target = _work(l), float(l["metric.rmse"])

            def ratio(g, cost, of=l):
                return _interp_work(g, target, cost) / cost(of) if len(g) >= 2 else math.nan

            rows.append({"scene": s, "coc": float(coc), "rmse_lines": target, "rmse_points": float(p["metric.rmse"]),
                         "tile256_ops": _work(p) / lw, "bf256_ops": _work(b256.iloc[0]) / lw if len(b256) else math.nan,
                         "eq_tile_ops": ratio(tile, _work), "eq_tile_clip_ops": ratio(tile, _work, c) if c is not None else math.nan,
                         "eq_tile_cycles": ratio(tile, _cycles), "eq_tile_wall": ratio(tile, _wall),
                         "eq_bf_ops": ratio(bf, _work), "eq_bf_wall": ratio(bf, _wall),
                         "flip_lines": float(l.get("metric.flip", math.nan)), "flip_points": float(p.get("metric.flip", math.nan))})
    out = pd.DataFrame(rows)
    out["lines_better"] = out["rmse_lines"] < out["rmse_points"]
    out.attrs["keys"] = ["scene", "coc"]
    return out


@named_table("methods_claim", reads=("timing.",))
def methods_claim(df, config) -> list[str]:
    """[Tzeng 2012]'s claim, 16 lines against 256 points (4-5x faster at better quality), on our scenes: the
    ratios at 256 points, and at equal RMSE (the work, cycles and wall time the point family needs to reach
    the 16 lines' RMSE, interpolated along its spp sweep) against `tile` and `bruteforce`; then [Tzeng 2012]'s
    own Table 1 and what it measured against."""
    f = lambda v, spec="{:.2f}": "" if v != v else spec.format(v)  # noqa: E731
    rows = [[r.scene, f"{r.coc:g}", f"{r.rmse_lines:.4f}", f"{r.rmse_points:.4f}", f(r.tile256_ops), f(r.bf256_ops),
             f(r.eq_tile_ops), f(r.eq_tile_clip_ops), f(r.eq_tile_cycles), f(r.eq_tile_wall), f(r.eq_bf_ops),
             f(r.eq_bf_wall), f(r.flip_lines, "{:.4f}"), f(r.flip_points, "{:.4f}")]
            for r in methods_claim_values(df, config).itertuples()]
    fps = [line / point for point, line in PAPER_TZENG_T1.values()]
    rows.append([f"**[Tzeng 2012] Table 1** ({len(PAPER_TZENG_T1)} meshes, GTX 580, 800 x 800)", "", "lower noise (its Fig. 9)",
                 "", "", f"frame rate, lines / points: {min(fps):.2f}–{max(fps):.2f} (per mesh "
                 + ", ".join(f"{m} {line / point:.2f}" for m, (point, line) in PAPER_TZENG_T1.items())
                 + "; its own tiled GPU point sampler at 256 spp, not a tile-test rasterizer)", "", "", "", "", "", "", "", ""])
    return md_table(["scene", "CoC", "RMSE 16 lines", "RMSE 256 pts", "ops 256 pts (tile) / 16 lines",
                     "ops 256 pts (bruteforce) / 16 lines", "equal RMSE: ops tile / lines",
                     "equal RMSE: ops tile / lines clip", "equal RMSE: est. cycles tile / lines",
                     "equal RMSE: wall tile / lines", "equal RMSE: ops bruteforce / lines",
                     "equal RMSE: wall bruteforce / lines", "FLIP 16 lines", "FLIP 256 pts"], rows)


def _pareto(points):
    """The Pareto front of (cost, error, label) triples: no other point is both cheaper and better."""
    front, best = [], math.inf
    for c, e, lab in sorted(points, key=lambda p: (p[0], p[1])):
        if e < best:
            front.append((c, e, lab))
            best = e
    return front


@named_values("methods_pareto")
def methods_pareto_values(df, config):
    """Per scene, CoC and cost axis (ops (all), wall): the Pareto front's size, the line methods on it, and
    its lowest RMSE and the method there."""
    import pandas as pd

    df = ok_rows(df).dropna(subset=["metric.rmse"])
    rows = []
    for s in _scenes(df):
        for coc in sorted(df[df["scene.name"] == s]["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            for axis, cost in (("ops (all)", _work), ("wall", _wall)):
                front = _pareto([(cost(r), float(r["metric.rmse"]), method_label(r)) for _, r in sub.iterrows()])
                line_labels = {method_label(r) for _, r in sub.iterrows() if is_lines(r["pipeline.algorithm"])}
                n_lines = sum(lab in line_labels for _c, _e, lab in front)
                rows.append({"scene": s, "coc": float(coc), "axis": axis, "front": len(front), "lines": n_lines,
                             "members": "; ".join(f"{lab} ({e:.4f})" for _c, e, lab in front),
                             "best_rmse": front[-1][1], "best_method": front[-1][2],
                             "lines_on_front": f"{s} CoC {coc:g}: {n_lines} of {len(front)}",
                             "best_on_front": f"{s} CoC {coc:g}: {front[-1][2]}"})
    out = pd.DataFrame(rows)
    out.attrs["keys"] = ["scene", "coc", "axis"]
    return out


@named_table("methods_pareto", reads=("timing.",))
def methods_pareto(df, config) -> list[str]:
    """The Pareto fronts (RMSE against all counted operations and against wall time) per scene and
    CoC: the methods on the front, cheapest first, with their RMSE."""
    rows = [[r.scene, f"{r.coc:g}", r.axis, f"{r.lines} / {r.front}", r.members]
            for r in methods_pareto_values(df, config).itertuples()]
    return md_table(["scene", "CoC", "cost", "lines on the front", "front, cheapest first (RMSE)"], rows)


@named_table("methods_lod")
def methods_lod(df, config) -> list[str]:
    """Level of detail: work saved and the FLIP increase, per scene, CoC and method."""
    df = ok_rows(df)
    on = df[_on(df, "pipeline.lod.enabled")]
    rows = []
    for _, r in on.iterrows():
        keys = {"scene.name": r["scene.name"], "camera.coc_px": r["camera.coc_px"],
                "pipeline.algorithm": r["pipeline.algorithm"], "samples.kind": r["samples.kind"],
                "samples.spp": r["samples.spp"]}
        base = df[~_on(df, "pipeline.lod.enabled")]
        for k, v in keys.items():
            base = base[base[k] == v]
        if is_lines(r["pipeline.algorithm"]):
            base = base[np.asarray(base["samples.n_lines"], float) == float(r["samples.n_lines"])]
        if "pipeline.lines.tile_clip" in df.columns:
            base = base[_on(base, "pipeline.lines.tile_clip") == (str(r["pipeline.lines.tile_clip"]) == "True")]
        if not len(base):
            continue
        b = base.iloc[0]
        saved = 1.0 - _work(r) / _work(b)
        df_ = float(r.get("metric.flip", math.nan)) - float(b.get("metric.flip", math.nan))
        rows.append([r["scene.name"], f"{r['camera.coc_px']:g}", method_label(b),
                     f"{int(r.get('lod.triangles_in', 0)):,} → {int(r.get('lod.triangles', 0)):,}",
                     f"{100 * saved:.0f}%", fmt(b.get("metric.flip", math.nan), "{:.4f}"),
                     fmt(r.get("metric.flip", math.nan), "{:.4f}"), f"{df_:+.4f}"])
    return md_table(["scene", "CoC", "method", "triangles", "ops saved", "FLIP without", "FLIP with LoD",
                     "FLIP increase"], rows)


@named_table("methods_segments")
def methods_segments(df, config) -> list[str]:
    """Segment-buffer statistics by CoC, and what the tile clip saved."""
    df = ok_rows(df)
    ln = df[_lines_mask(df) & ~_on(df, "pipeline.lod.enabled")]
    rows = []
    for s in _scenes(ln):
        for coc in sorted(ln[ln["scene.name"] == s]["camera.coc_px"].unique()):
            sub = ln[(ln["scene.name"] == s) & (ln["camera.coc_px"] == coc)]
            for n in sorted(sub["samples.n_lines"].dropna().unique()):
                g = sub[sub["samples.n_lines"] == n]
                off = g[~_on(g, "pipeline.lines.tile_clip")]
                on = g[_on(g, "pipeline.lines.tile_clip")]
                if not len(off):
                    continue
                r = off.iloc[0]
                seg = max(float(r["lines.segments"]), 1.0)
                clip = ""
                if len(on):
                    c = on.iloc[0]
                    culled = float(c["lines.culled_tile"]) / max(float(c["lines.tests"]) + float(c["lines.culled_tile"]), 1)
                    clip = f"{100 * culled:.0f}% tests skipped, ops {_work(c) / _work(r):.2f}x"
                rows.append([s, f"{coc:g}", str(int(n)), f"{float(r['lines.tests']):.3g}", f"{seg:.3g}",
                             f"{100 * float(r['lines.overflows']) / seg:.1f}%",
                             f"{100 * float(r['lines.segments_merged']) / seg:.1f}%",
                             f"{100 * float(r['lines.rejected_occluded']) / seg:.1f}%",
                             f"{100 * float(r['lines.rejected_small']) / seg:.1f}%", clip])
    return md_table(["scene", "CoC", "lines", "line tests", "segments", "overflow", "merged", "occluded", "too small",
                     "tile clip"], rows)
# ---- the conventional-GPU pipeline and accumulation buffering (reports/paper/gpu_methods.md) -----

GPU_METHODS = ["gpu_hexagon3d", "gpu_wedge", "gpu_reduced_wedge", "gpu_hexagon2d", "gpu_pe_triangle",
               "gpu_vr_triangle", "gpu_convex_hull", "gpu_adaptive"]
# [Toth 2008] Table 1: vertices, triangles, computation, usability ([McGuire 2010]'s hull and [Toth 2008] §4.7 are not in it).
PAPER_GPU_T1 = {"gpu_hexagon3d": ("12", "20/16", "heavy", "excellent"), "gpu_wedge": ("6", "8", "medium", "good"),
                "gpu_reduced_wedge": ("5", "4", "intense", "excellent"),
                "gpu_hexagon2d": ("6", "4", "medium", "mediocre"), "gpu_pe_triangle": ("3", "1", "light", "poor"),
                "gpu_vr_triangle": ("3", "1", "medium", "very poor")}
# [Toth 2008] Table 2: total output floats (none / triangle / strip constants), bump-mapped textured surface.
PAPER_GPU_T2 = {"gpu_hexagon3d": (858, 788, 123), "gpu_hexagon2d": (234, 164, 59)}


def _gpu_rows(df):
    df = ok_rows(df)
    return df[[is_gpu(a) for a in df["pipeline.algorithm"]]]


@named_values("gpu_table1")
def gpu_table1_values(df, config):
    """Per GPU method at CoC 8 px (mean over the scenes): output vertices, strip triangles, geometry-shader
    ops and output floats per input triangle; bound area and fragments per hit fragment; share of fragments
    outside the setup box; the pixel-shader STE."""
    import pandas as pd

    df = _gpu_rows(df)
    coc = 8 if (df["camera.coc_px"] == 8).any() else sorted(df["camera.coc_px"].unique())[0]
    df = df[df["camera.coc_px"] == coc]
    rows = []
    for m in GPU_METHODS:
        sub = df[df["pipeline.algorithm"] == m]
        if not len(sub):
            continue
        n = sub["gpu.gs_triangles_in"].astype(float)
        hit = (sub["gpu.fragments"] - sub["gpu.fragments_zero_hit"]).astype(float)
        per = lambda c: float((sub[c].astype(float) / n).mean())  # noqa: E731
        rows.append({"method": m, "vertices": per("gpu.gs_vertices"), "triangles": per("gpu.gs_triangles"),
                     "gs_ops": per("gpu.gs_ops"), "floats": per("gpu.gs_floats"),
                     "area": float((sub["gpu.bound_area"].astype(float) / 1000.0 / hit).mean()),
                     "fragments": float((sub["gpu.fragments"].astype(float) / hit).mean()),
                     "outside": float((sub["gpu.fragments_outside_box"].astype(float) / sub["gpu.fragments"].astype(float)).mean()),
                     "ste": float(sub["raster.ste"].mean())})
    out = pd.DataFrame(rows)
    out.attrs["keys"] = ["method"]
    return out


@named_table("gpu_table1")
def gpu_table1(df, config) -> list[str]:
    """[Toth 2008] Table 1 measured at CoC 8 px: per input triangle (mean over the scenes) output vertices,
    strip triangles, geometry-shader ops, output floats; bound area and fragments against hit fragments."""
    rows = []
    for r in gpu_table1_values(df, config).itertuples():
        paper = PAPER_GPU_T1.get(r.method, ("", "", "", ""))
        rows.append([r.method, f"{r.vertices:.2f}", paper[0], f"{r.triangles:.2f}", paper[1], f"{r.gs_ops:.0f}", paper[2],
                     f"{r.floats:.0f}", f"{r.area:.2f}", f"{r.fragments:.2f}", f"{100 * r.outside:.1f}%", f"{r.ste:.3f}",
                     paper[3]])
    return md_table(["method", "vertices / tri", "paper", "triangles / tri", "paper", "GS ops / tri", "paper",
                     "floats / tri", "bound area / hit px", "fragments / hit fragment", "fragments outside setup box",
                     "PS STE", "paper usability"], rows)


@named_table("gpu_fallbacks")
def gpu_fallbacks(df, config) -> list[str]:
    """Fallbacks by cause ([Toth 2008] §4.8) summed over the sweep, per method."""
    df = _gpu_rows(df)
    cols = ["gpu.fallback_near", "gpu.fallback_motion", "gpu.fallback_degenerate", "gpu.fallback_vr",
            "gpu.fallback_reduced", "gpu.volume_clipped", "gpu.adaptive_pe", "gpu.adaptive_hexagon"]
    rows = []
    for m in GPU_METHODS:
        sub = df[df["pipeline.algorithm"] == m]
        if len(sub):
            rows.append([m, f"{int(sub['gpu.gs_triangles_in'].sum())}"] + [f"{int(sub[c].sum())}" for c in cols])
    return md_table(["method", "triangles"] + [c.split(".", 1)[1] for c in cols], rows)


@named_values("gpu_vs_tile")
def gpu_vs_tile_values(df, config):
    """Per scene and CoC: tile's Mops and kcycles, the GPU method with the fewest ops and the one with the
    fewest estimated cycles, their ratios to tile, the GPU's bottleneck."""
    import pandas as pd

    df = ok_rows(df)
    rows = []
    for s in _scenes(df):
        for coc in sorted(df["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            tile = sub[sub["pipeline.algorithm"] == "tile"]
            gpu = sub[[is_gpu(a) for a in sub["pipeline.algorithm"]]]
            if not len(tile) or not len(gpu):
                continue
            t_ops, t_cyc = float(tile["ops.total"].iloc[0]), float(tile["timing.cycles"].iloc[0])
            bo = gpu.loc[gpu["ops.total"].astype(float).idxmin()]
            bc = gpu.loc[gpu["timing.cycles"].astype(float).idxmin()]
            rows.append({"scene": s, "coc": float(coc), "tile_mops": t_ops / 1e6, "best_ops": bo["pipeline.algorithm"],
                         "ops_ratio": float(bo["ops.total"]) / t_ops, "tile_kcycles": t_cyc / 1e3,
                         "best_cycles": bc["pipeline.algorithm"], "cycles_ratio": float(bc["timing.cycles"]) / t_cyc,
                         "bottleneck": str(bc["timing.bottleneck"])})
    out = pd.DataFrame(rows)
    out.attrs["keys"] = ["scene", "coc"]
    return out


@named_table("gpu_vs_tile", reads=("timing.",))
def gpu_vs_tile(df, config) -> list[str]:
    """Per scene and CoC: the GPU method with the fewest ops and the one with the fewest estimated
    cycles, and their ratios to tile."""
    rows = [[r.scene, f"{r.coc:g}", f"{r.tile_mops:.2f}", r.best_ops, f"{r.ops_ratio:.2f}", f"{r.tile_kcycles:.1f}",
             r.best_cycles, f"{r.cycles_ratio:.2f}", r.bottleneck] for r in gpu_vs_tile_values(df, config).itertuples()]
    return md_table(["scene", "CoC [px]", "tile Mops", "best GPU (ops)", "ops GPU / tile", "tile kcycles",
                     "best GPU (cycles)", "cycles GPU / tile", "GPU bottleneck"], rows)


@named_table("gpu_table2", reads=("timing.",))
def gpu_table2(df, config) -> list[str]:
    """[Toth 2008] Table 2 in kind: per input triangle output floats, per fragment interpolated floats and
    re-derived setup ops, per constant type; the paper's output floats beside."""
    df = _gpu_rows(df)
    rows = []
    for m in GPU_METHODS:
        for i, const in enumerate(["none", "triangle", "strip"]):
            r = _first(df, {"pipeline.algorithm": m, "pipeline.gpu_constants": const})
            if r is None:
                continue
            n, frag = float(r["gpu.gs_triangles_in"]), float(r["gpu.fragments"])
            paper = PAPER_GPU_T2.get(m)
            rows.append([m, const, f"{float(r['gpu.gs_floats']) / n:.1f}", str(paper[i]) if paper else "",
                         f"{float(r['gpu.interp_floats']) / frag:.1f}",
                         "39" if paper and const == "none" else ("4" if paper else ""),
                         f"{float(r['ops.ps_setup']) / frag:.2f}", f"{float(r['gpu.gs_ops']) / n:.0f}",
                         f"{float(r['timing.cycles']) / 1e3:.1f}"])
    return md_table(["method", "constants", "output floats / tri", "paper", "interpolated floats / fragment",
                     "paper", "re-derived setup ops / fragment", "GS ops / tri", "kcycles"], rows)


def _equal_error_spp(spp, err, target):
    """The spp at which the log-log interpolated curve err(spp) reaches target (NaN outside the range)."""
    order = np.argsort(spp)
    x, y = np.log(np.asarray(spp, float)[order]), np.log(np.asarray(err, float)[order])
    t = math.log(target)
    for i in range(len(x) - 1):
        lo, hi = min(y[i], y[i + 1]), max(y[i], y[i + 1])
        if lo <= t <= hi and y[i] != y[i + 1]:
            return float(math.exp(x[i] + (t - y[i]) * (x[i + 1] - x[i]) / (y[i + 1] - y[i])))
    return math.nan


@named_values("accumulation_k")
def accumulation_k_values(df, config):
    """Per scene, CoC and N passes: RMSE of accumulation and of stratified at N spp, the stratified spp of
    equal RMSE, k = N / that spp, the ghosting of both."""
    import pandas as pd

    df = ok_rows(df)
    rows = []
    for s in _scenes(df):
        for coc in sorted(df["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            st = sub[sub["samples.kind"] == "stratified"].sort_values("samples.spp")
            ac = sub[sub["samples.kind"] == "accumulation"].sort_values("samples.spp")
            if not len(st) or not len(ac):
                continue
            for _, r in ac.iterrows():
                n = int(r["samples.spp"])
                eq = _equal_error_spp(st["samples.spp"], st["metric.rmse"], float(r["metric.rmse"]))
                same = st[st["samples.spp"] == n]
                rows.append({"scene": s, "coc": float(coc), "passes": n, "rmse_acc": float(r["metric.rmse"]),
                             "rmse_strat": float(same["metric.rmse"].iloc[0]) if len(same) else math.nan,
                             "equal_spp": eq, "k": n / eq if eq == eq else math.nan,
                             "ghost_acc": float(r["metric.ghosting"]),
                             "ghost_strat": float(same["metric.ghosting"].iloc[0]) if len(same) else math.nan})
    out = pd.DataFrame(rows)
    out.attrs["keys"] = ["scene", "coc", "passes"]
    return out


@named_table("accumulation_k")
def accumulation_k(df, config) -> list[str]:
    """k = N / (stratified spp of equal RMSE) per scene, CoC and N passes; RMSE and ghosting beside."""
    rows = [[r.scene, f"{r.coc:g}", str(r.passes), f"{r.rmse_acc:.4f}", f"{r.rmse_strat:.4f}",
             f"{r.equal_spp:.1f}" if r.equal_spp == r.equal_spp else "out of range",
             f"{r.k:.2f}" if r.k == r.k else "", f"{r.ghost_acc:.2f}", f"{r.ghost_strat:.2f}", "~4"]
            for r in accumulation_k_values(df, config).itertuples()]
    return md_table(["scene", "CoC [px]", "N passes", "RMSE accumulation", "RMSE stratified (N spp)",
                     "stratified spp of equal RMSE", "k", "ghosting accumulation", "ghosting stratified",
                     "paper k ([Toth 2008] §9.1, perceived)"], rows)


@named_values("gpu_early_depth")
def gpu_early_depth_values(df, config):
    """Per scene, CoC and algorithm: HiZ off against on: fragments depth-culled (GPU), sample tests saved,
    ops and cycles with HiZ over without, GPU / tile cycles with HiZ in both."""
    import pandas as pd

    df = ok_rows(df)
    on_col = "pipeline.hiz.enabled"
    rows = []
    for s in _scenes(df):
        for coc in sorted(df["camera.coc_px"].unique()):
            sub = df[(df["scene.name"] == s) & (df["camera.coc_px"] == coc)]
            t_on, t_off = _first(sub, {"pipeline.algorithm": "tile", on_col: True}), _first(sub, {"pipeline.algorithm": "tile", on_col: False})
            for alg in list(dict.fromkeys(sub["pipeline.algorithm"].astype(str))):
                off, on = _first(sub, {"pipeline.algorithm": alg, on_col: False}), _first(sub, {"pipeline.algorithm": alg, on_col: True})
                if off is None or on is None:
                    continue
                gpu = is_gpu(alg)
                frags = float(off["gpu.fragments"]) if gpu else math.nan
                saved = (float(off["gpu.ps_samples_tested"]) - float(on["gpu.ps_samples_tested"])) if gpu else \
                    float(on["zcull.samples_culled"])
                rows.append({"scene": s, "coc": float(coc), "algorithm": alg, "gpu": gpu,
                             "culled": float(on["gpu.fragments_depth_culled"]) / frags if gpu and frags else math.nan,
                             "saved": saved, "ops_ratio": float(on["ops.total"]) / float(off["ops.total"]),
                             "cycles_ratio": float(on["timing.cycles"]) / float(off["timing.cycles"]),
                             "vs_tile": float(on["timing.cycles"]) / float(t_on["timing.cycles"]) if gpu and t_on is not None else math.nan,
                             "vs_tile_off": float(off["timing.cycles"]) / float(t_off["timing.cycles"]) if gpu and t_off is not None else math.nan})
    out = pd.DataFrame(rows)
    tile_saved = out[~out["gpu"]].set_index(["scene", "coc"])["saved"]
    out["saved_vs_tile"] = [r.saved / tile_saved.get((r.scene, r.coc), math.nan) if r.gpu else math.nan
                            for r in out.itertuples()]
    out.attrs["keys"] = ["scene", "coc", "algorithm"]
    return out


@named_table("gpu_early_depth", reads=("timing.",))
def gpu_early_depth(df, config) -> list[str]:
    """Per scene, CoC and algorithm: HiZ off against on ([Toth 2008] §9.7's depth interval for the gpu_*
    pipeline, ẑ against HiZ for tile)."""
    rows = [[r.scene, f"{r.coc:g}", r.algorithm, f"{100 * r.culled:.1f}%" if r.gpu else "", f"{r.saved:.3g}",
             f"{r.ops_ratio:.3f}", f"{r.cycles_ratio:.3f}", f"{r.vs_tile:.2f}" if r.gpu else ""]
            for r in gpu_early_depth_values(df, config).itertuples()]
    return md_table(["scene", "CoC [px]", "algorithm", "fragments depth-culled", "sample tests saved",
                     "ops HiZ / none", "cycles HiZ / none", "cycles GPU / tile (both HiZ)"], rows)


# ---- the numerical-precision study (configs/paper/precision_*.yaml, point kind precision) ---------------

def _pct(x) -> str:
    return "n/a" if x is None or x != x else f"{100 * float(x):.3f} %"


def _yes(v) -> str:
    return "yes" if str(v) == "True" else "NO"


def _arith(r) -> str:
    a = r.get("point.options.arithmetic")
    return f"fixed, frac_bits {int(r['point.options.frac_bits'])}" if a == "fixed" else str(a)


def _num(r, k):
    return r.get(f"numerics.{k}")


def _precision_rows(df, keys=("point.options.viewport",)):
    df = ok_rows(df)
    order = {"float32": 0, "float64": 1, "fixed": 2}
    recs = [r for _, r in df.iterrows()]
    return sorted(recs, key=lambda r: (*[str(r.get(k)) if k == "point.options.cls" else float(r.get(k)) for k in keys],
                                       order.get(r.get("point.options.arithmetic"), 3),
                                       float(r.get("point.options.frac_bits") or 0)))


@named_table("precision_2d")
def precision_2d(df, config) -> list[str]:
    """The 2D tile test and sample test per viewport and arithmetic (study 2d)."""
    rows = []
    for r in _precision_rows(df):
        v = int(r["point.options.viewport"])
        if r["point.options.arithmetic"] == "fixed":
            rows.append([v, _arith(r), int(_num(r, "int_bits_tile")), int(_num(r, "int_bits_sample")),
                         int(_num(r, "total_bits")), _yes(_num(r, "safe")),
                         f"{int(_num(r, 'int_bits_bound'))} ({int(_num(r, 'bound_total_bits'))}), {_yes(_num(r, 'bound_safe'))}",
                         int(_num(r, "triangles")), int(_num(r, "samples")), _pct(_num(r, "differ")),
                         f"{_num(r, 'dmax'):.4g}", int(_num(r, "tiles")), int(_num(r, "tile_violations")),
                         _pct(_num(r, "cull_lost")), int(_num(r, "below_overflows"))])
        else:
            rows.append([v, _arith(r), "-", "-", 32, _yes(_num(r, "safe")), "-", int(_num(r, "triangles")),
                         int(_num(r, "samples")), _pct(_num(r, "differ")), f"{_num(r, 'dmax'):.4g}", int(_num(r, "tiles")),
                         int(_num(r, "tile_violations")), _pct(_num(r, "cull_lost")), "-"])
    return md_table(["viewport [px]", "arithmetic", "fewest int_bits: tile test (set-up)", "fewest int_bits: sample test",
                     "total bits", "safe", "closed-form int_bits (total bits), safe", "triangles", "samples",
                     "samples differing from float64", "max distance of a differing sample [px]", "tiles",
                     "tiles culled beyond DELTA", "tile culls lost", "overflows at int_bits - 1"], rows)


@named_table("precision_4d")
def precision_4d(df, config) -> list[str]:
    """The 4D tile test per viewport and arithmetic (study 4d)."""
    rows = []
    for r in _precision_rows(df):
        fixed = r["point.options.arithmetic"] == "fixed"
        rows.append([int(r["point.options.viewport"]), _arith(r), int(_num(r, "triangles")), int(_num(r, "tiles")),
                     int(_num(r, "culled64")), _pct(_num(r, "cull_lost")), f"{int(_num(r, 'checked'))} / {int(_num(r, 'hits'))}",
                     f"{int(_num(r, 'int_bits_band'))} ({int(_num(r, 'total_bits'))})" if fixed else "-",
                     int(_num(r, "int_bits_all")) if fixed else "-", int(_num(r, "below_overflows")) if fixed else "-"])
    return md_table(["viewport [px]", "arithmetic", "triangles", "tiles", "lens cells culled (float64)", "cull lost",
                     "culled pairs checked: samples / ray-cast hits", "fewest int_bits in band (total bits)",
                     "fewest int_bits all", "overflowing tests at all - 1"], rows)


@named_table("precision_box")
def precision_box(df, config) -> list[str]:
    """INTERVAL's box bounds per viewport and arithmetic (study box)."""
    rows = []
    for r in _precision_rows(df):
        fixed = r["point.options.arithmetic"] == "fixed"
        rows.append([int(r["point.options.viewport"]), _arith(r), int(_num(r, "triangles")), int(_num(r, "boxes")),
                     int(_num(r, "hits")), f"{int(_num(r, 'outside'))} / {int(_num(r, 'outside64'))}",
                     f"{_num(r, 'grow_mean'):.3g} / {_num(r, 'grow_max'):.3g}",
                     f"{int(_num(r, 'int_bits_band'))} ({int(_num(r, 'total_bits'))})" if fixed else "-",
                     int(_num(r, "int_bits_all")) if fixed else "-", int(_num(r, "below_overflows")) if fixed else "-"])
    return md_table(["viewport [px]", "arithmetic", "triangles", "boxes", "ray-cast hits",
                     "hits outside (format / float64)", "growth mean / max [px]", "fewest int_bits in band (total bits)",
                     "fewest int_bits all", "overflowing boxes at all - 1"], rows)


@named_table("precision_5d")
def precision_5d(df, config) -> list[str]:
    """The motion tile tests per viewport, class and arithmetic (study 5d)."""
    rows = []
    for r in _precision_rows(df, ("point.options.viewport", "point.options.cls")):
        fixed = r["point.options.arithmetic"] == "fixed"
        rows.append([int(r["point.options.viewport"]), r["point.options.cls"], _arith(r), int(_num(r, "triangles")),
                     int(_num(r, "samples")), int(_num(r, "hits")), int(_num(r, "culled64")), _pct(_num(r, "cull_lost")),
                     f"{int(_num(r, 'outside'))} / {int(_num(r, 'outside64'))}",
                     f"{int(_num(r, 'int_bits_band'))} / {int(_num(r, 'int_bits_band_h5'))} ({int(_num(r, 'total_bits'))})"
                     if fixed else "-",
                     f"{int(_num(r, 'int_bits_all'))} / {int(_num(r, 'int_bits_all_h5'))}" if fixed else "-",
                     int(_num(r, "below_overflows")) if fixed else "-"])
    return md_table(["viewport [px]", "class", "arithmetic", "triangles", "samples", "ray-cast hits", "excluded by float64",
                     "cull lost", "hits excluded (format / float64)",
                     "fewest int_bits in band: t̂ + lens sets / H5 (total bits)", "fewest int_bits all: t̂ + lens sets / H5",
                     "overflowing tests at all - 1"], rows)


@named_table("precision_nd")
def precision_nd(df, config) -> list[str]:
    """The sample test per viewport, class and arithmetic (study nd)."""
    rows = []
    for r in _precision_rows(df, ("point.options.viewport", "point.options.cls")):
        fixed = r["point.options.arithmetic"] == "fixed"
        rows.append([int(r["point.options.viewport"]), r["point.options.cls"], _arith(r), int(_num(r, "samples")),
                     int(_num(r, "sample_bad")), _pct(_num(r, "differ")), f"{_num(r, 'dmax'):.4g}", _pct(_num(r, "in_band")),
                     int(_num(r, "int_bits_band")) if fixed else "-", int(_num(r, "int_bits_all")) if fixed else "-"])
    return md_table(["viewport [px]", "class", "arithmetic", "samples", "beyond stated", "differing beyond 10^-3 px",
                     "max distance of a differing sample [px]", "in band", "fewest int_bits (in band)",
                     "fewest int_bits (all)"], rows)


def precision_label(r) -> str:
    """'default', 'sample fixed 4', 'tile float32', 'tile + sample fixed 4, 14 int bits', 'depth fixed 16' of a
    render row, from its pipeline.precision columns."""
    parts, bits = [], set()
    for stage, default in (("tile", "float64"), ("sample", "float32"), ("depth", "float32")):
        plain = r.get(f"pipeline.precision.{stage}")
        F = r.get(f"pipeline.precision.{stage}.fixed.frac_bits")
        if F is not None and F == F:
            parts.append((stage, f"fixed {int(F)}"))
            bits.add(int(r.get(f"pipeline.precision.{stage}.fixed.int_bits")))
        elif isinstance(plain, str) and plain != default:
            parts.append((stage, plain))
    if not parts:
        return "default"
    kinds = {k for _, k in parts}
    text = (" + ".join(s for s, _ in parts) + " " + kinds.pop()) if len(kinds) == 1 else ", ".join(f"{s} {k}" for s, k in parts)
    small = [b for b in bits if b < 40 and b != 1]
    return text + (f", {small[0]} int bits" if small else "")


@named_values("precision_render")
def precision_render_values(df, config):
    """Per render (CoC, precision label): the image RMSE, samples differing and their share, the samples tested
    and 2D tiles and H5 cells culled against the default precision's, and the overflow counters."""
    import pandas as pd

    out = []
    for _, r in ok_rows(df).iterrows():
        tested, base = float(r["raster.samples_tested"]), float(r["numerics.tested_base"])
        c2, c2b = float(r.get("tile.culled_2d", 0)), float(r["numerics.culled_2d_base"])
        h5, h5b = float(r.get("tile.H5_cells_culled", 0)), float(r["numerics.culled_H5_base"])
        out.append({"coc": float(r["camera.coc_px"]), "label": precision_label(r),
                    "spacing": r.get("scene.params.spacing"),
                    "frac_bits": r.get("pipeline.precision.depth.fixed.frac_bits"),
                    "rmse": float(r["numerics.rmse"]), "differ": int(r["numerics.samples_differ"]),
                    "samples": int(r["numerics.samples"]),
                    "differ_share": float(r["numerics.samples_differ"]) / float(r["numerics.samples"]),
                    "tested": tested, "tested_base": base, "tested_ratio": tested / base, "tested_rise": tested / base - 1,
                    "culled_2d": c2, "culled_2d_base": c2b, "culled_2d_lost": 1 - c2 / c2b if c2b else 0.0,
                    "culled_H5": h5, "culled_H5_base": h5b, "culled_H5_lost": 1 - h5 / h5b if h5b else 0.0,
                    "sample_overflows": int(r.get("precision.sample_overflows", 0)),
                    "tile_overflows": int(r.get("precision.tile_overflows", 0)),
                    "tile4d_overflows": int(r.get("precision.tile4d_overflows", 0)),
                    "tile5d_overflows": int(r.get("precision.tile5d_overflows", 0))})
    frame = pd.DataFrame(out)
    frame.attrs["keys"] = ["coc", "label", "spacing", "frac_bits"]
    return frame


@named_table("precision_render")
def precision_render(df, config) -> list[str]:
    """Image error and culls lost at fewer bits (study render on spot)."""
    v = precision_render_values(df, config)
    rows = [[f"{r.coc:g}", r.label, f"{r.rmse:.3g}", f"{r.differ} of {r.samples}", f"{r.culled_2d:.0f} ({r.culled_2d_base:.0f})",
             _pct(r.culled_2d_lost), f"{r.tested_ratio:.4f}", r.sample_overflows, r.tile_overflows, r.tile4d_overflows]
            for r in v.itertuples()]
    return md_table(["CoC [px]", "precision", "image RMSE", "samples differing", "2D tiles culled (default)",
                     "tile culls lost", "samples tested / default", "sample overflows", "2D tile overflows",
                     "4D tile-test overflows"], rows)


@named_table("precision_motion")
def precision_motion(df, config) -> list[str]:
    """Moving triangles: culls lost at fewer bits in renders (study render on motion_field)."""
    v = precision_render_values(df, config)
    rows = [[f"{r.coc:g}", r.label, f"{r.differ} of {r.samples}", f"{r.tested_ratio:.4f}",
             f"{r.culled_H5:.0f} ({r.culled_H5_base:.0f})", r.tile5d_overflows] for r in v.itertuples()]
    return md_table(["CoC [px]", "tile precision", "samples differing", "samples tested / default",
                     "H5 cells culled (default)", "motion tile-test overflows"], rows)


@named_table("precision_depth")
def precision_depth(df, config) -> list[str]:
    """A fixed-point depth buffer (study render on depth_layers) beside the closed-form resolved gap at w = 2."""
    v = precision_render_values(df, config)
    near = float(ok_rows(df)["camera.near"].iloc[0]) if "camera.near" in df.columns else 0.01
    rows = [[f"{r.spacing:g}", f"{int(r.frac_bits)}", f"{r.differ} of {r.samples}", f"{2.0 ** -r.frac_bits * 4 / near:.3g}"]
            for r in v.itertuples() if r.frac_bits == r.frac_bits]
    return md_table(["spacing", "frac_bits", "samples differing from float32", "smallest resolved gap at w = 2 (closed form)"],
                    rows)


# ---- the line-sample wheel (configs/paper/methods_wheel.yaml) ---------------------------------------

def _case_label(r) -> str:
    return f"{r['scene.name']} {int(r['camera.width'])} px, CoC {float(r['camera.coc_px']):g}"


@named_values("wheel_choice")
def wheel_choice_values(df, config):
    """Per (case, wheel): RMSE at the case's typical work (the geometric mean work of its points) from a
    power-law fit of RMSE against work over the wheel's points, over the best wheel's; per wheel the mean
    over the cases (geometric, as `mean_ratio`; `excess` = mean_ratio - 1); `chosen` the wheel of least
    excess, `best_wheel` each case's best."""
    import pandas as pd

    df = ok_rows(df).dropna(subset=["metric.rmse"])
    rows = []
    for case, g in df.groupby(df.apply(_case_label, axis=1), sort=False):
        work = np.array([_work(r) for _, r in g.iterrows()])
        at = math.exp(float(np.mean(np.log(work))))
        est = {}
        for wheel, gw in g.groupby("samples.wheel"):
            w = np.log([_work(r) for _, r in gw.iterrows()])
            e = np.log(gw["metric.rmse"].to_numpy(float))
            slope, icpt = np.polyfit(w, e, 1) if len(set(w)) > 1 else (0.0, float(np.mean(e)))
            est[int(wheel)] = math.exp(icpt + slope * math.log(at))
        best = min(est, key=est.get)
        for wheel, v in est.items():
            rows.append({"case": case, "wheel": wheel, "work": at, "rmse_at": v, "ratio": v / est[best],
                         "best_wheel": best})
    frame = pd.DataFrame(rows)
    mean = frame.groupby("wheel")["ratio"].apply(lambda r: float(np.exp(np.mean(np.log(r)))))
    frame["mean_ratio"] = frame["wheel"].map(mean)
    frame["excess"] = frame["mean_ratio"] - 1.0
    frame["chosen"] = frame["wheel"] == int(mean.idxmin())
    frame.attrs["keys"] = ["case", "wheel"]
    return frame


@named_table("wheel_choice")
def wheel_choice(df, config) -> list[str]:
    """Each wheel's RMSE at equal operations over the best wheel's, per case; the mean; the chosen wheel."""
    v = wheel_choice_values(df, config)
    wheels = sorted(v["wheel"].unique())
    rows = []
    for case, g in v.groupby("case", sort=False):
        ratio = dict(zip(g["wheel"], g["ratio"]))
        rows.append([case, f"{g['work'].iloc[0]:.3g}"] + [f"{ratio.get(w, math.nan):.3f}" for w in wheels]
                    + [str(int(g["best_wheel"].iloc[0]))])
    mean = dict(zip(v["wheel"], v["mean_ratio"]))
    chosen = int(v.loc[v["chosen"], "wheel"].iloc[0])
    rows.append(["**mean (geometric)**", ""] + [f"**{mean[w]:.3f}**" for w in wheels] + [f"**chosen: {chosen}**"])
    return md_table(["case", "work at [ops]"] + [f"wheel of {w}: RMSE / best" for w in wheels] + ["best wheel"], rows)


# ---- sampled simulation's bin size (configs/paper/sampling.yaml) --------------------------------------

SAMPLING_COUNTERS = ("raster.samples_tested", "ops.total", "raster.samples_hit")


def _binom_cdf(k: int, n: int, p: float) -> float:
    """P(X <= k) for X ~ Binomial(n, p)."""
    return sum(math.comb(n, i) * p ** i * (1 - p) ** (n - i) for i in range(k + 1))


@named_values("bin_choice")
def bin_choice_values(df, config):
    """Per (bin size, counter): the sampled strata, the draws, the coverage of the 95% intervals against the
    whole frame (exact point of the same bin size), the mean half-width over the frame's value, the one-sided
    binomial p-value of that coverage against 95%; per bin size `valid` (strata >= sim.sampling.FEW_STRATA
    and every counter's p >= 0.05) and `chosen` (the largest valid bin size)."""
    import pandas as pd
    from sim.sampling import FEW_STRATA

    df = ok_rows(df)
    rows = []
    for b, g in df.groupby("pipeline.bin_size"):
        exact = g[g["pipeline.sample_fraction"] == 1.0]
        drawn = g[g["pipeline.sample_fraction"] < 1.0]
        if not len(exact) or not len(drawn):
            continue
        for c in SAMPLING_COUNTERS:
            truth = float(exact[c].iloc[0])
            est, hw = drawn[c].to_numpy(float), drawn[f"{c}.ci95"].to_numpy(float)
            n, k = len(est), int(np.sum(np.abs(est - truth) <= hw))
            rows.append({"bin_size": int(b), "counter": c, "strata": float(drawn["sample.strata"].mean()), "draws": n,
                         "covered": k, "coverage": k / n, "p": _binom_cdf(k, n, 0.95),
                         "halfwidth": float(np.mean(hw)) / truth, "wall_s": float(drawn["time.wall_s"].mean()),
                         "wall_exact_s": float(exact["time.wall_s"].iloc[0])})
    frame = pd.DataFrame(rows)
    valid = {b: bool(g["strata"].iloc[0] >= FEW_STRATA and (g["p"] >= 0.05).all()) for b, g in frame.groupby("bin_size")}
    frame["valid"] = frame["bin_size"].map(valid)
    chosen = max((b for b, ok in valid.items() if ok), default=None)
    frame["chosen"] = frame["bin_size"] == chosen
    frame.attrs["keys"] = ["bin_size", "counter"]
    return frame


@named_table("bin_choice")
def bin_choice(df, config) -> list[str]:
    """Per bin size: strata, coverage and half-width per counter, validity, the chosen size."""
    v = bin_choice_values(df, config)
    rows = []
    for b, g in v.groupby("bin_size"):
        cov = "; ".join(f"{r.counter}: {r.covered}/{r.draws} ({r.coverage:.0%}, p {r.p:.2g})" for r in g.itertuples())
        hw = " / ".join(f"{r.halfwidth:.2%}" for r in g.itertuples())
        rows.append([str(b), f"{g['strata'].iloc[0]:.0f}", cov, hw, f"{g['wall_s'].iloc[0]:.2f} ({g['wall_exact_s'].iloc[0]:.2f})",
                     ("**chosen**" if g["chosen"].iloc[0] else "valid") if g["valid"].iloc[0] else "no"])
    return md_table(["bin [px]", "strata", "coverage of the 95% intervals (p against 95%)",
                     "mean half-width / frame value (" + " / ".join(SAMPLING_COUNTERS) + ")",
                     "wall time of a draw [s] (whole frame)", "valid"], rows)

"""The hardware page (reports/paper/hardware.md, configs/paper/hardware*.yaml): every method at equal image
error, what it costs there (operations, estimated cycles and bottleneck, DRAM bytes, energy), the hardware it
needs to reach a frame-time target (the area proxy of docs/hardware.md, over re-timed hardware variants), and
the verdict as sentences generated from those tables.

Equal error. Per scene, the target is the error (RMSE or FLIP, against the scene's converged reference) of
stratified point sampling at TARGET_SPP samples per pixel. Every exact point method renders the same image
from the same table, so the point family's error curve is one curve per scene and level of detail; each
other family (accumulation buffering's passes, line samples, each with and without level of detail) has its
own. A family's n at the target (spp, passes or lines) is interpolated log-log between the two grid points
that bracket it; its 95 % interval comes from the least-squares power law of the family's curve (inverse
prediction: the standard error of log n at the target, Student's t with points - 2 degrees of freedom).
Each method's costs are interpolated log-log along its own n grid to that n and to the interval's ends.

The interior (one scene at 1920 x 1080) is too costly for a full sweep: its error curves come from the same
scene at a lower resolution with the blur kept in physical units (INTERIOR_ERROR), its operations at the
equal-error n from sampled simulation at 1920 x 1080 (INTERIOR_SAMPLED: estimates with 95 % intervals), and
its cycles, DRAM bytes and energy from one whole-frame render per method at one n (INTERIOR), scaled to the
equal-error n (and to level of detail) by the sampled ratio of all counted operations.

Design space. The retime sections (DESIGN) re-time each method's stored work records over hardware variants
(sample-test lanes with the GPU shader lanes alongside, tile-test throughput with the 2D rasterizer alongside,
DRAM bandwidth) and render it again with smaller depth and texture caches. The area proxy of a variant sums,
over the units the method gives work, throughput x the unit's area per item and clock (AREA_UNITS), plus
the caches' KiB x the SRAM area per KiB; docs/hardware.md gives every weight and its source. The frame-time
target is FRAME_RATE_HZ at the configured clock for 1920 x 1080, scaled by pixels for smaller frames.
"""
from __future__ import annotations

import json
import math

import numpy as np

from .frames import ok_rows
from .tables import algorithm_fact, is_gpu, is_lines, md_table, named_table, named_values, page_rows

TARGET_SPP = 16          # the target error: stratified point sampling at this spp
FRAME_RATE_HZ = 30       # the frame-time target: 1080p at 30 Hz (33 Mcycles at 1 GHz)
TARGET_PIXELS = 1920 * 1080
METRICS = ("rmse", "flip")

SMALL = ("hardware_defocus", "hardware_motion")
INTERIOR_ERROR, INTERIOR, INTERIOR_SAMPLED = "hardware_interior_error", "hardware_interior", "hardware_interior_sampled"
DESIGN = ("hardware_design_defocus", "hardware_design_motion", "hardware_design_interior")
RESOLUTION = "hardware_resolution"

# ---- the area proxy (docs/hardware.md): mm^2 at 45 nm ----------------------------------------------------
# [Horowitz 2014] Fig. 1.1.9, area of one 32-bit unit at 45 nm: integer add 137 um^2, multiply 3495 um^2;
# float add 4184 um^2, multiply 7700 um^2. One operation per clock is charged as a multiply-add (as the
# energy table charges every counted operation), an upper bound for adds and compares.
INT_OP_MM2 = (137 + 3495) * 1e-6
FLOAT_OP_MM2 = (4184 + 7700) * 1e-6
# SRAM: the 45 nm six-transistor bit cell of [Mistry 2007], 0.346 um^2, x 8192 bits a KiB (cells only).
SRAM_KIB_MM2 = 0.346 * 8192 * 1e-6
# Per unit: (integer or float op slots per item and clock, what an item is). The sample-test lane runs the
# fixed-point 5D test (kHwInside5D, 40 operations, docs/op_costs.md); a tile test about 64 operations and a
# triangle set-up about 256 (the means of ops.tile per tile test and ops.setup per triangle of `tile` on the
# static scenes of the page are printed beside the table); a depth test its interpolation and compare
# (kDepth + kDepthTest = 7); the 2D rasterizer three edge tests a pixel (3 x kRasterEdge = 9); the GPU's
# shader lanes one float operation a clock each.
AREA_UNITS = {
    "setup": (256, "int", "triangle"),
    "tile_test": (64, "int", "tile test"),
    "sample_test": (40, "int", "sample test (lane)"),
    "depth": (7, "int", "depth test"),
    "raster2d": (9, "int", "pixel"),
    "pixel_shader": (1, "float", "operation (lane)"),
    "geometry_shader": (1, "float", "operation (lane)"),
}
CACHES = {"depth": "depth_buffer.cache_bytes", "color": "color_buffer.cache_bytes", "texture": "tex_cache.size_bytes"}


def unit_mm2(unit: str) -> float:
    slots, kind, _ = AREA_UNITS[unit]
    return slots * (INT_OP_MM2 if kind == "int" else FLOAT_OP_MM2)


# ---- rows --------------------------------------------------------------------------------------------------

def _get(r, k, default=math.nan):
    v = r.get(k, default) if hasattr(r, "get") else default
    return default if v is None else v


def _true(r, k) -> bool:
    return str(_get(r, k, "")) == "True"


LINE_FAMILY = "lines"  # the sample family of an algorithm whose samples are lines (sim.algorithm_info)


def kind(r) -> str:
    """The sample family of a row: 'lines', 'accumulation' or 'points'."""
    if is_lines(r["pipeline.algorithm"]):
        return LINE_FAMILY
    return "accumulation" if r["samples.kind"] == "accumulation" else "points"


def lod(r) -> bool:
    return _true(r, "pipeline.lod.enabled")


def family(r) -> str:
    return kind(r) + (" +LoD" if lod(r) else "")


def method(r) -> str:
    """The method of a row: its algorithm, with +H5 (tile's H5 planes for moving triangles) and +LoD."""
    return f"{r['pipeline.algorithm']}{' +H5' if _true(r, 'pipeline.halfspace.H5') else ''}{' +LoD' if lod(r) else ''}"


def base_method(r) -> str:
    return f"{r['pipeline.algorithm']}{' +H5' if _true(r, 'pipeline.halfspace.H5') else ''}"


def n_of(r) -> float:
    """spp, passes or lines per pixel."""
    return float(r["samples.n_lines"] if kind(r) == "lines" else r["samples.spp"])


def scene_label(r) -> str:
    """'teapot (defocus)', 'spot_wall (motion)', 'spot_wall (defocus + motion)': the scene and its blur, from
    the triangles' dimension classes."""
    moving = float(_get(r, "setup.class_3d", 0)) + float(_get(r, "setup.class_5d", 0)) > 0
    lens = float(_get(r, "setup.class_4d", 0)) + float(_get(r, "setup.class_5d", 0)) > 0
    blur = "defocus + motion" if moving and lens else "motion" if moving else "defocus" if lens else "in focus"
    return f"{r['scene.name']} ({blur})"


def pipeline_of(r) -> str:
    """'5D' (the sample pipeline: 5D rasterizer, line samples), 'GPU' (a conventional GPU's) or
    'accumulation' (a GPU's pinhole passes)."""
    if kind(r) == "accumulation":
        return "accumulation"
    return "GPU" if is_gpu(r["pipeline.algorithm"]) else "5D"


def ops_all(r) -> float:
    """Every counted operation: ops.total + ops.interp + ops.segments."""
    seg = _get(r, "ops.segments", 0.0)
    return float(r["ops.total"]) + float(_get(r, "ops.interp", 0.0)) + (0.0 if seg != seg else float(seg))


def ops_all_ci(r) -> float:
    """The 95 % half-width of ops_all of a sampled row (the half-widths of its parts added: an upper bound)."""
    return sum(float(_get(r, f"{k}.ci95", 0.0)) if _get(r, f"{k}.ci95", 0.0) == _get(r, f"{k}.ci95", 0.0) else 0.0
               for k in ("ops.total", "ops.interp", "ops.segments"))


def frame_target(r) -> float:
    """The frame-time target of a row's frame: FRAME_RATE_HZ at the configured clock for 1920 x 1080, scaled by
    the frame's pixels."""
    clock = float(_get(r, "hardware.clock_ghz", 1.0)) * 1e9
    return clock / FRAME_RATE_HZ * float(r["camera.width"]) * float(r["camera.height"]) / TARGET_PIXELS


def _rows(df):
    return [r for _, r in ok_rows(df).iterrows()]


# ---- curves and interpolation ------------------------------------------------------------------------------

T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228}


def loglog_at(xs, ys, x):
    """y at x on the log-log polyline through (xs, ys) sorted by x, extrapolated along the nearest segment;
    a single point gives its y at its own x only (else nan)."""
    pts = sorted((float(a), float(b)) for a, b in zip(xs, ys) if a > 0 and b > 0 and b == b)
    if not pts or not x == x:
        return math.nan
    if len(pts) == 1:
        return pts[0][1] if math.isclose(pts[0][0], x) else math.nan
    lx = math.log(x)
    i = 0
    while i < len(pts) - 2 and lx > math.log(pts[i + 1][0]):
        i += 1
    (x0, y0), (x1, y1) = pts[i], pts[i + 1]
    t = (lx - math.log(x0)) / (math.log(x1) - math.log(x0))
    return math.exp(math.log(y0) + t * (math.log(y1) - math.log(y0)))


def n_at_error(ns, errs, target):
    """The n at which the error curve (ns, errs) reaches target: log-log interpolation between the bracketing
    grid points (nan when the target lies outside the curve's range, e.g. beneath a family's error floor)."""
    pts = sorted((float(n), float(e)) for n, e in zip(ns, errs) if e > 0)
    lt = math.log(target)
    for (n0, e0), (n1, e1) in zip(pts, pts[1:]):
        lo, hi = sorted((math.log(e0), math.log(e1)))
        if lo <= lt <= hi and e0 != e1:
            t = (lt - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(n0) + t * (math.log(n1) - math.log(n0)))
    for n, e in pts:
        if math.isclose(e, target, rel_tol=1e-12):
            return n
    return math.nan


def fit_halfwidth(ns, errs, n_star) -> float:
    """The 95 % half-width of log n* from the least-squares power law log e = a + b log n of the curve: the
    inverse prediction's standard error s / |b| sqrt(1/m + (log n* - mean)^2 / Sxx), times t(m - 2); nan with
    fewer than 3 points."""
    x, y = np.log(np.asarray(ns, float)), np.log(np.asarray(errs, float))
    m = len(x)
    if m < 3 or not n_star == n_star or n_star <= 0:
        return math.nan
    b, a = np.polyfit(x, y, 1)
    s = math.sqrt(float(np.sum((y - (a + b * x)) ** 2)) / (m - 2))
    sxx = float(np.sum((x - x.mean()) ** 2))
    if b == 0 or sxx == 0:
        return math.nan
    se = s / abs(b) * math.sqrt(1 / m + (math.log(n_star) - x.mean()) ** 2 / sxx)
    return T975.get(m - 2, 1.96) * se


def curves(rows, scene: str) -> dict:
    """{family: {n: {metric: mean error}}} of one scene (the point methods' identical images averaged)."""
    out: dict = {}
    for r in rows:
        if scene_label(r) != scene or _get(r, "metric.rmse") != _get(r, "metric.rmse"):
            continue
        cell = out.setdefault(family(r), {}).setdefault(n_of(r), {})
        for m in (*METRICS, "ghosting"):
            v = _get(r, f"metric.{m}")
            if v == v:
                cell.setdefault(m, []).append(float(v))
    return {f: {n: {m: float(np.mean(v)) for m, v in cell.items()} for n, cell in sorted(c.items())}
            for f, c in out.items()}


def equal_error_n(curve: dict, metric: str, target: float, defines_target: bool) -> tuple[float, float, float]:
    """(n*, low, high) of one family's curve at the target error; the family that defines the target is
    exactly at TARGET_SPP."""
    if defines_target:
        return float(TARGET_SPP), float(TARGET_SPP), float(TARGET_SPP)
    ns = [n for n in curve if metric in curve[n]]
    errs = [curve[n][metric] for n in ns]
    n_star = n_at_error(ns, errs, target)
    hw = fit_halfwidth(ns, errs, n_star)
    if not n_star == n_star:
        return math.nan, math.nan, math.nan
    if not hw == hw:
        return n_star, math.nan, math.nan
    return n_star, n_star * math.exp(-hw), n_star * math.exp(hw)


# ---- costs -------------------------------------------------------------------------------------------------

COST_FIGURES = ("ops", "cycles", "dram", "energy")


def _cost(r, fig: str) -> float:
    if fig == "ops":
        return ops_all(r)
    if fig == "cycles":
        return float(_get(r, "timing.cycles"))
    if fig == "dram":
        return float(_get(r, "dram.bytes"))
    return float(_get(r, "energy.frame")) * 1e-6  # uJ


class FullCosts:
    """Costs of whole-frame rows along each method's n grid (the small scenes)."""

    def __init__(self, rows):
        self.by: dict = {}
        for r in rows:
            self.by.setdefault((scene_label(r), method(r)), []).append(r)

    def methods(self, scene: str) -> list[str]:
        return [m for s, m in self.by if s == scene]

    def family(self, scene, m) -> str:
        return family(self.by[scene, m][0])

    def pipeline(self, m, scene) -> str:
        return pipeline_of(self.by[scene, m][0])

    def at(self, scene, m, n) -> dict:
        rows = self.by[scene, m]
        ns = [n_of(r) for r in rows]
        out = {f: loglog_at(ns, [_cost(r, f) for r in rows], n) for f in COST_FIGURES}
        near = min(rows, key=lambda r: abs(math.log(n_of(r)) - math.log(n)) if n == n and n > 0 else 0)
        out["bottleneck"] = str(_get(near, "timing.bottleneck", ""))
        out["ghosting"] = _ghost_at(rows, n)
        out["pipeline"] = pipeline_of(rows[0])
        out["ops_ci"] = 0.0
        return out


def _ghost_at(rows, n) -> float:
    pts = sorted((n_of(r), float(_get(r, "metric.ghosting"))) for r in rows if _get(r, "metric.ghosting") == _get(r, "metric.ghosting"))
    if not pts or not n == n:
        return math.nan
    xs, ys = [math.log(p[0]) for p in pts], [p[1] for p in pts]
    return float(np.interp(math.log(n), xs, ys))


class InteriorCosts:
    """The interior's costs at 1920 x 1080: operations at n from the sampled rows (with their 95 % intervals);
    cycles, DRAM bytes and energy from the method's whole-frame render (its algorithm without level of detail,
    at the render's n), scaled by the sampled ratio of all counted operations at n (and with level of detail)
    over the sampled operations of that render's method and n. A method without sampled rows (the point methods,
    whose equal-error n is the whole-frame render's) takes the render's figures."""

    def __init__(self, full_rows, sampled_rows, error_rows):
        self.full = {base_method(r): r for r in full_rows}
        self.sampled: dict = {}
        for r in sampled_rows:
            self.sampled.setdefault(method(r), []).append(r)
        self.ghost: dict = {}
        for r in error_rows:
            self.ghost.setdefault(family(r), []).append(r)
        self.scene = scene_label(full_rows[0]) if full_rows else ""
        self.fam = {method(r): family(r) for r in [*full_rows, *sampled_rows]}
        self.pipe = {method(r): pipeline_of(r) for r in [*full_rows, *sampled_rows]}

    def methods(self, scene: str) -> list[str]:
        return list(dict.fromkeys([*[m for m in self.full], *self.sampled])) if scene == self.scene else []

    def family(self, scene, m) -> str:
        return self.fam[m]

    def pipeline(self, m, scene="") -> str:
        return self.pipe.get(m, "")

    def _sampled_ops(self, m, n) -> tuple[float, float]:
        rows = self.sampled.get(m, [])
        if not rows:
            return math.nan, math.nan
        ns = [n_of(r) for r in rows]
        v = loglog_at(ns, [ops_all(r) for r in rows], n)
        rel = loglog_at(ns, [ops_all_ci(r) / ops_all(r) if ops_all(r) else 0.0 for r in rows], n) if len(rows) > 1 else (
            ops_all_ci(rows[0]) / ops_all(rows[0]) if ops_all(rows[0]) else math.nan)
        return v, rel

    def at(self, scene, m, n) -> dict:
        base = m.replace(" +LoD", "")
        full = self.full.get(base)
        out = {f: math.nan for f in COST_FIGURES}
        out.update(bottleneck="", ghosting=_ghost_at(self.ghost.get(self.fam.get(m, ""), []), n), ops_ci=math.nan,
                   pipeline=self.pipe.get(m, ""))
        if full is None:
            return out
        n_full = n_of(full)
        own_ops, own_rel = self._sampled_ops(m, n)
        if m == base and math.isclose(n, n_full):  # the render itself
            ratio, rel = 1.0, 0.0
            own_ops, own_rel = ops_all(full), 0.0
        else:
            ref_ops, ref_rel = self._sampled_ops(base, n_full)
            ratio = own_ops / ref_ops if ref_ops else math.nan
            rel = math.hypot(own_rel, ref_rel) if own_rel == own_rel and ref_rel == ref_rel else math.nan
        out["ops"], out["ops_ci"] = own_ops, own_ops * own_rel if own_rel == own_rel else math.nan
        for f in ("cycles", "dram", "energy"):
            out[f] = _cost(full, f) * ratio
        out["scale_ci"] = rel
        out["bottleneck"] = str(_get(full, "timing.bottleneck", ""))
        out["n_full"] = n_full
        return out


def _scenes(rows) -> list[str]:
    return list(dict.fromkeys(scene_label(r) for r in rows))


def equal_error_rows(err_rows, costs, scenes) -> list[dict]:
    """Per scene, metric and method: the family's n at the target error (with its interval) and the method's
    costs there (and at the interval's ends)."""
    out = []
    for scene in scenes:
        cv = curves(err_rows, scene)
        base = cv.get("points", {}).get(float(TARGET_SPP))
        if base is None:
            continue
        for metric in METRICS:
            target = base.get(metric, math.nan)
            nstar = {f: equal_error_n(c, metric, target, f == "points") for f, c in cv.items()}
            for m in costs.methods(scene):
                f = costs.family(scene, m)
                n, lo, hi = nstar.get(f, (math.nan,) * 3)
                at = costs.at(scene, m, n) if n == n else {k: math.nan for k in COST_FIGURES} | {"pipeline": costs.pipeline(m, scene)}
                row = {"scene": scene, "metric": metric, "target": target, "method": m, "family": f,
                       "pipeline": at.get("pipeline", ""), "n": n, "n_lo": lo, "n_hi": hi,
                       "bottleneck": at.get("bottleneck", ""), "ghosting": at.get("ghosting", math.nan),
                       "ops_ci": at.get("ops_ci", math.nan), "scale_ci": at.get("scale_ci", math.nan),
                       "n_full": at.get("n_full", math.nan)}
                lo_at = costs.at(scene, m, lo) if lo == lo else {}
                hi_at = costs.at(scene, m, hi) if hi == hi else {}
                for fig in COST_FIGURES:
                    row[fig] = at.get(fig, math.nan)
                    ends = [d.get(fig, math.nan) for d in (lo_at, hi_at)]
                    ends = [e for e in ends if e == e]
                    row[f"{fig}_lo"] = min(ends) if ends else math.nan
                    row[f"{fig}_hi"] = max(ends) if ends else math.nan
                out.append(row)
    return out


def _small_frames():
    rows = []
    for name in SMALL:
        try:
            rows += _rows(page_rows(name))
        except KeyError:
            pass
    return rows


def _interior():
    try:
        err, full, smp = (_rows(page_rows(n)) for n in (INTERIOR_ERROR, INTERIOR, INTERIOR_SAMPLED))
    except KeyError:
        return [], None
    return err, InteriorCosts(full, smp, err)


def all_equal_error() -> list[dict]:
    small = _small_frames()
    out = equal_error_rows(small, FullCosts(small), _scenes(small)) if small else []
    err, costs = _interior()
    if costs is not None and costs.scene:
        out += equal_error_rows(err, costs, [costs.scene])
    return out


@named_values("hardware_equal")
def hardware_equal_values(df, config):
    """Per scene, metric (rmse, flip) and method: n at the target error (95 % interval), operations, cycles,
    DRAM bytes, energy (uJ) there, the bottleneck unit, the ghosting, and each figure over the scene's best
    5D-pipeline method (the fewest cycles among the sample pipeline's point methods)."""
    import pandas as pd

    out = pd.DataFrame(all_equal_error())
    if len(out):
        for fig in COST_FIGURES:
            out[f"{fig}_ratio"] = math.nan
        for (s, m), g in out.groupby(["scene", "metric"]):
            pts = g[(g["pipeline"] == "5D") & (g["family"] == "points")]
            if not len(pts):
                continue
            best = pts.loc[pts["cycles"].astype(float).idxmin()]
            for fig in COST_FIGURES:
                out.loc[g.index, f"{fig}_ratio"] = g[fig].astype(float) / float(best[fig])
            out.loc[g.index, "best_5d"] = best["method"]
    out.attrs["keys"] = ["scene", "metric", "method"]
    return out


def _f(v, spec="{:.3g}") -> str:
    return "" if v is None or v != v else spec.format(v)


def _ci(v, lo, hi, spec="{:.3g}") -> str:
    if v != v:
        return "not reached"
    if lo == lo and hi == hi and not (math.isclose(lo, v) and math.isclose(hi, v)):
        return f"{spec.format(v)} [{spec.format(lo)}, {spec.format(hi)}]"
    return spec.format(v)


def _eq_table(rows) -> list[str]:
    body = []
    for r in rows:
        ops = _ci(r["ops"], r["ops_lo"], r["ops_hi"])
        if r.get("ops_ci", 0) == r.get("ops_ci", 0) and r.get("ops_ci", 0):
            ops += f" ± {_f(r['ops_ci'])}"
        scale = r.get("scale_ci", math.nan)
        sc = f" (± {scale:.1%})" if scale == scale and scale else ""
        nf = r.get("n_full", math.nan)
        body.append([r["method"], _ci(r["n"], r["n_lo"], r["n_hi"], "{:.1f}"), ops,
                     _ci(r["cycles"], r["cycles_lo"], r["cycles_hi"]) + sc, r["bottleneck"] + (f" (at n = {nf:g})" if nf == nf and not math.isclose(nf, r["n"]) else ""),
                     _ci(r["dram"], r["dram_lo"], r["dram_hi"]) + sc, _ci(r["energy"], r["energy_lo"], r["energy_hi"]) + sc,
                     _f(r["ghosting"], "{:.2f}"), _f(r.get("cycles_ratio", math.nan), "{:.2f}")])
    return md_table(["method", "n at equal error [95% CI]", "operations", "est. cycles", "bottleneck", "DRAM bytes",
                     "energy [uJ]", "ghosting", "cycles / best 5D"], body)


@named_table("hardware_equal", reads=("timing.",))
def hardware_equal(df, config) -> list[str]:
    """The equal-error table of the section's scenes: per scene and metric, every method's n at the target
    error and its costs there."""
    v = hardware_equal_values(df, config)
    mine = set(_scenes(_rows(df)))
    lines = []
    for (scene, metric), g in v.groupby(["scene", "metric"], sort=False):
        if scene not in mine:
            continue
        rows = g.sort_values("cycles").to_dict("records")
        lines += ["", f"**{scene}, equal {metric.upper()}** (target {g['target'].iloc[0]:.4g}: stratified points at "
                      f"{TARGET_SPP} spp)", ""] + _eq_table(rows)
    return lines[1:]


# ---- the convex hull against tile on moving scenes -----------------------------------------------------

@named_values("hardware_hull")
def hardware_hull_values(df, config):
    """Per moving scene and spp: gpu_convex_hull's operations and cycles over tile's and over tile +H5's (the
    same table, so the same image and error)."""
    import pandas as pd

    rows = [r for r in _small_frames() if "motion" in scene_label(r)]
    out = []
    by = {(scene_label(r), method(r), n_of(r)): r for r in rows}
    for (s, m, n), r in by.items():
        if not is_gpu(r["pipeline.algorithm"]) or kind(r) != "points":
            continue
        for ref in ("tile", "tile +H5"):
            t = by.get((s, ref, n))
            if t is None:
                continue
            out.append({"scene": s, "spp": n, "gpu": m, "against": ref, "ops_ratio": ops_all(r) / ops_all(t),
                        "cycles_ratio": float(r["timing.cycles"]) / float(t["timing.cycles"]),
                        "gpu_bottleneck": str(r["timing.bottleneck"]), "tile_bottleneck": str(t["timing.bottleneck"]),
                        "ste_gpu": float(r["raster.ste"]), "ste_tile": float(t["raster.ste"])})
    frame = pd.DataFrame(out)
    frame.attrs["keys"] = ["scene", "spp", "against"]
    return frame


@named_table("hardware_hull", reads=("timing.",))
def hardware_hull(df, config) -> list[str]:
    v = hardware_hull_values(df, config)
    body = [[r.scene, f"{r.spp:g}", r.against, f"{r.ops_ratio:.2f}", f"{r.cycles_ratio:.1f}", r.gpu_bottleneck,
             r.tile_bottleneck, f"{r.ste_gpu:.3f}", f"{r.ste_tile:.3f}"] for r in v.itertuples()]
    return md_table(["scene", "spp", "against", "ops hull / tile", "cycles hull / tile", "hull bottleneck",
                     "tile bottleneck", "STE hull", "STE tile"], body)


# ---- the design space --------------------------------------------------------------------------------------

def effective_hw(r, key: str) -> float:
    """A hardware key of a retime row: point.hardware's value where the variant sets it, else the section's."""
    v = _get(r, f"point.hardware.{key}")
    return float(v) if v == v else float(_get(r, f"hardware.{key}"))


def area_proxy(r) -> tuple[float, dict]:
    """(mm^2, {part: mm^2}) of a row's hardware: every unit the method gives work, throughput x its area per
    item and clock, plus the depth and colour caches and, when it fetches texels, the texture cache."""
    parts = {}
    for unit in AREA_UNITS:
        if float(_get(r, f"timing.{unit}.work", 0.0)) > 0:
            parts[unit] = effective_hw(r, f"{unit}.throughput") * unit_mm2(unit)
    for name, key in CACHES.items():
        if name == "texture" and not float(_get(r, "timing.texture.work", 0.0)) > 0:
            continue
        parts[f"{name} cache"] = effective_hw(r, key) / 1024 * SRAM_KIB_MM2
    return sum(parts.values()), parts


def design_rows() -> list[dict]:
    out = []
    for name in DESIGN:
        try:
            rows = _rows(page_rows(name))
        except KeyError:
            continue
        for r in rows:
            area, parts = area_proxy(r)
            out.append({"scene": scene_label(r), "method": method(r), "pipeline": pipeline_of(r), "n": n_of(r),
                        "lanes": effective_hw(r, "sample_test.throughput"),
                        "tile_tests": effective_hw(r, "tile_test.throughput"),
                        "dram": effective_hw(r, "dram.bytes_per_clock"),
                        "depth_kib": effective_hw(r, "depth_buffer.cache_bytes") / 1024,
                        "tex_kib": effective_hw(r, "tex_cache.size_bytes") / 1024,
                        "cycles": float(r["timing.cycles"]), "bottleneck": str(r["timing.bottleneck"]),
                        "target": frame_target(r), "area": area, "parts": parts,
                        "pixels": float(r["camera.width"]) * float(r["camera.height"])})
    return out


def pareto(points):
    """The (area, cycles, item) points no other point beats in both (smaller area and fewer cycles)."""
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def _config(d) -> str:
    return (f"{d['lanes']:g} lanes, {d['tile_tests']:g} tile tests/clk, {d['dram']:g} B/clk, "
            f"depth cache {d['depth_kib']:g} KiB, tex cache {d['tex_kib']:g} KiB")


@named_values("hardware_design")
def hardware_design_values(df, config):
    """Per scene and method: the smallest area proxy among the variants that reach the frame-time target (its
    configuration, cycles and the DRAM bandwidth it was re-timed with), the fewest cycles of any variant, and
    the Pareto front's size; `least_area` marks the method with the smallest such area per scene."""
    import pandas as pd

    out = []
    rows = design_rows()
    for (s, m) in dict.fromkeys((d["scene"], d["method"]) for d in rows):
        g = [d for d in rows if d["scene"] == s and d["method"] == m]
        ok = [d for d in g if d["cycles"] <= d["target"]]
        best = min(ok, key=lambda d: (d["area"], d["dram"])) if ok else None
        fastest = min(g, key=lambda d: d["cycles"])
        front = pareto([(d["area"], d["cycles"], d) for d in g])
        out.append({"scene": s, "method": m, "pipeline": g[0]["pipeline"], "n": g[0]["n"], "target": g[0]["target"],
                    "reached": best is not None, "area": best["area"] if best else math.nan,
                    "config": _config(best) if best else "", "cycles": best["cycles"] if best else math.nan,
                    "bottleneck": best["bottleneck"] if best else fastest["bottleneck"],
                    "min_cycles": fastest["cycles"], "min_cycles_area": fastest["area"], "front": len(front),
                    "variants": len(g), "front_members": "; ".join(f"{a:.2f} mm² → {c:.3g}" for a, c, _ in front)})
    frame = pd.DataFrame(out)
    if len(frame):
        frame["least_area"] = False
        for s, g in frame.groupby("scene"):
            reached = g[g["reached"]]
            if len(reached):
                frame.loc[reached["area"].astype(float).idxmin(), "least_area"] = True
    frame.attrs["keys"] = ["scene", "method"]
    return frame


@named_table("hardware_design", reads=("timing.",))
def hardware_design(df, config) -> list[str]:
    """Per scene and method: the smallest configuration (area proxy) that reaches the frame-time target."""
    v = hardware_design_values(df, config)
    body = []
    for r in v.sort_values(["scene", "area"]).itertuples():
        body.append([r.scene, r.method + (" **(least area)**" if r.least_area else ""), f"{r.n:g}", f"{r.target:.3g}",
                     f"{r.area:.2f}" if r.reached else "not reached", r.config, _f(r.cycles), r.bottleneck,
                     f"{r.min_cycles:.3g} ({r.min_cycles_area:.2f} mm²)", f"{r.front} of {r.variants}"])
    return md_table(["scene", "method", "n", "target [cycles]", "smallest area [mm²]", "its configuration",
                     "its cycles", "bottleneck", "fewest cycles of any variant (area)", "Pareto front"], body)


@named_table("hardware_area")
def hardware_area(df, config) -> list[str]:
    """The area proxy's weights (docs/hardware.md), as the page uses them."""
    body = [[u, f"{s}", "32-bit integer" if k == "int" else "32-bit float", what, f"{unit_mm2(u):.4f}"]
            for u, (s, k, what) in AREA_UNITS.items()]
    body.append(["SRAM (depth, colour, texture caches)", "", "6T bit cells", "KiB", f"{SRAM_KIB_MM2:.5f}"])
    return md_table(["unit", "op slots per item", "datapath", "item per clock", "mm² per item and clock (45 nm)"], body)


def pareto_figure_rows():
    """Rows for the Pareto figure: per design variant its area, cycles over the target, scene and method."""
    import pandas as pd

    return pd.DataFrame([{k: v for k, v in d.items() if k != "parts"} | {"cycles_over_target": d["cycles"] / d["target"]}
                         for d in design_rows()])


# ---- [Toth 2008] Fig. 16 in kind: resolution --------------------------------------------------------------

@named_values("hardware_resolution")
def hardware_resolution_values(df, config):
    """Per resolution and family (stratified points, accumulation): RMSE, FLIP, ghosting, cycles per pixel; and
    per family whether each error falls from the lowest to the highest resolution."""
    import pandas as pd

    rows = _rows(page_rows(RESOLUTION))
    out = []
    for r in rows:
        out.append({"width": float(r["camera.width"]), "coc": float(r["camera.coc_px"]), "family": kind(r),
                    "rmse": float(r["metric.rmse"]), "flip": float(_get(r, "metric.flip")),
                    "ghosting": float(r["metric.ghosting"]),
                    "cycles_per_pixel": float(r["timing.cycles"]) / (float(r["camera.width"]) * float(r["camera.height"]))})
    frame = pd.DataFrame(out).sort_values(["family", "width"])
    for f, g in frame.groupby("family"):
        lo, hi = g.iloc[0], g.iloc[-1]
        for m in ("rmse", "flip", "ghosting"):
            frame.loc[g.index, f"{m}_falls"] = bool(hi[m] < lo[m])
            frame.loc[g.index, f"{m}_change"] = hi[m] / lo[m] if lo[m] else math.nan
    frame.attrs["keys"] = ["family", "width"]
    return frame


@named_table("hardware_resolution", reads=("timing.",))
def hardware_resolution(df, config) -> list[str]:
    """Per family and frame width: RMSE, FLIP, ghosting and cycles per pixel."""
    v = hardware_resolution_values(df, config)
    body = [[r.family, f"{r.width:g}", f"{r.coc:g}", f"{r.rmse:.4g}", f"{r.flip:.4g}", f"{r.ghosting:.2f}",
             f"{r.cycles_per_pixel:.3g}"] for r in v.itertuples()]
    return md_table(["family", "width [px]", "CoC [px]", "RMSE", "FLIP", "ghosting", "cycles per pixel"], body)


# ---- the verdict ---------------------------------------------------------------------------------------------

@named_values("hardware_verdict")
def hardware_verdict_values(df, config):
    """Per scene and metric: the best 5D method (fewest cycles among the sample pipeline's point methods), the best
    conventional-GPU method, accumulation and line samples (each with level of detail where it is cheaper), and
    their cycles, energy and operations over the best 5D method's."""
    import pandas as pd

    eq = hardware_equal_values(df, config)
    out = []
    if not len(eq):
        return pd.DataFrame(out)
    for (s, metric), g in eq.groupby(["scene", "metric"], sort=False):
        unreached = sorted(set(g[g["cycles"].astype(float) != g["cycles"].astype(float)]["pipeline"]))
        g = g[g["cycles"].astype(float) == g["cycles"].astype(float)]
        five = g[(g["pipeline"] == "5D") & (g["family"].str.startswith("points"))]
        if not len(five):
            continue
        best = five.loc[five["cycles"].astype(float).idxmin()]
        row = {"case": s, "scene": s.split(" (")[0], "blur": _blur_key(s), "metric": metric, "best_5d": best["method"],
               "best_5d_cycles": float(best["cycles"]), "best_5d_energy": float(best["energy"])}
        cheapest = g.loc[g["cycles"].astype(float).idxmin()]
        row["cheapest"], row["cheapest_pipeline"] = cheapest["method"], cheapest["pipeline"]
        row["fewest_ops"] = g.loc[g["ops"].astype(float).idxmin()]["method"]
        row["least_energy"] = g.loc[g["energy"].astype(float).idxmin()]["method"]
        row["five_d_wins"] = bool(cheapest["pipeline"] == "5D")
        for name, sel in (("gpu", g["pipeline"] == "GPU"), ("accumulation", g["pipeline"] == "accumulation"),
                          ("lines", g["family"].map(lambda f: f.split(" ")[0]) == LINE_FAMILY)):
            part = g[sel]
            if not len(part):
                row[name] = ""
                continue
            b = part.loc[part["cycles"].astype(float).idxmin()]
            row[name] = b["method"]
            for fig in COST_FIGURES:
                row[f"{name}_{fig}"] = float(b[fig]) / float(best[fig])
            row[f"{name}_ghosting"] = float(b["ghosting"])
        row["ghosting_5d"] = float(best["ghosting"])
        row["unreached"] = ", ".join(p for p in unreached if p not in {row.get("gpu") and "GPU", row.get("accumulation") and "accumulation"})
        out.append(row)
    frame = pd.DataFrame(out)
    frame.attrs["keys"] = ["scene", "blur", "metric"]
    return frame


def _blur_key(label: str) -> str:
    """'defocus', 'motion' or 'both' of a scene label ('spot_wall (defocus + motion)' -> 'both')."""
    blur = label.split(" (")[-1].rstrip(")")
    return "both" if "+" in blur else blur.replace(" ", "_")


def _times(x: float) -> str:
    if x != x:
        return ""
    return f"{x:.1f}× more" if x >= 1 else f"{1 / x:.1f}× fewer"


@named_table("hardware_verdict", reads=("timing.",))
def hardware_verdict(df, config) -> list[str]:
    """The verdict, one sentence per scene and metric, written from the equal-error tables."""
    v = hardware_verdict_values(df, config)
    lines = []
    for r in v.to_dict("records"):
        parts = [f"- **{r['case']}, equal {r['metric'].upper()}:** the best 5D rasterizer is `{r['best_5d']}` "
                 f"({r['best_5d_cycles']:.3g} cycles)."]
        for name, what in (("gpu", "the best conventional-GPU method"), ("accumulation", "accumulation buffering"),
                           ("lines", "line samples")):
            if r.get(name):
                parts.append(f"{what[0].upper() + what[1:]} (`{r[name]}`) {'need' if what.endswith('samples') else 'needs'} {_times(r[f'{name}_cycles'])} cycles, "
                             f"{_times(r[f'{name}_energy'])} energy and {_times(r[f'{name}_ops'])} operations.")
        parts.append(f"Fewest cycles overall: `{r['cheapest']}` ({r['cheapest_pipeline']}); least energy: "
                     f"`{r['least_energy']}`; fewest operations: `{r['fewest_ops']}`.")
        if r.get("accumulation"):
            worse = r["accumulation_ghosting"] > r["ghosting_5d"]
            parts.append(f"Under the ghosting measure (the error's lag-one autocorrelation) "
                         f"{'stochastic points win' if worse else 'accumulation does not lose'}: "
                         f"{r['accumulation_ghosting']:.2f} for accumulation against {r['ghosting_5d']:.2f}.")
        if r.get("unreached"):
            parts.append(f"Not reached within its grid of samples, passes or lines: {r['unreached']}.")
        lines.append(" ".join(parts))
    return lines


# ---- row functions of the page's derived columns (experiments/config/columns.py ROW_FUNCTIONS) -------------

def area_column(df):
    """The area proxy [mm²] of every row (area_proxy)."""
    return [area_proxy(r)[0] for _, r in df.iterrows()]


def target_column(df):
    """The frame-time target [cycles] of every row's frame (frame_target)."""
    return [frame_target(r) for _, r in df.iterrows()]


def method_column(df):
    return [method(r) for _, r in df.iterrows()]


def family_column(df):
    return [family(r) for _, r in df.iterrows()]


def scene_column(df):
    return [scene_label(r) for _, r in df.iterrows()]


def n_column(df):
    return [n_of(r) for _, r in df.iterrows()]

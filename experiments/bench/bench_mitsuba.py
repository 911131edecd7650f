"""`make bench`: rast5d against the renderer a user would pick for defocus and motion-blur images only,
Mitsuba 3, side by side on the same scenes, frames, sample counts and sampler class.

Both renderers see the same triangles with the same per-vertex colours (rast5d's vertex colours;
Mitsuba's albedo AOV of a diffuse BSDF reading them as a mesh attribute), the same thin-lens camera
(field of view, focus distance, aperture radius: Mitsuba's `thinlens`), a box filter of one pixel and
the same samples per pixel from a stratified sampler (rast5d's `SampleTable.stratified`, Mitsuba's
`stratified`). Motion blur: rast5d samples time in the shutter; Mitsuba has no deforming-mesh motion,
so its image is the average over shutter slices (the mesh moved to each slice's middle time, the
pixel's samples split between the slices), every slice's BVH update counted in its time.

Each image's error is its RMSE (linear RGB over every pixel) against a converged reference: Mitsuba's
vectorised variant at more samples (REFERENCE_SPP_FACTOR times; with motion, a slice per four of the
reference's samples, up to REFERENCE_SLICES_MAX). The reference's own noise adds to every error in
quadrature.

Times are wall seconds of the render call with 2 threads each (Mitsuba: `mi.render` on a loaded scene
whose kernels are compiled, the minimum of the repeats; the scene's load and BVH build are given
apart; rast5d: `sim.render`, everything included, timing model off and on), the renderers interleaved
in every repeat so that load from other processes shifts them alike. Mitsuba's `scalar_rgb` variant
runs at the smallest frame only (it is far slower).

Also the 1080p frame: the largest interior, 64 spp, CoC 10, `tile`, 2 threads, timing on.

Needs the optional `bench` extra (`pip install rast5d[bench]`: mitsuba) and, for the vectorised
variant, LLVM >= 16 (Debian: `apt-get install libllvm19`; DRJIT_LIBLLVM_PATH names the library, found
in the usual places when unset). Where either is missing the page says so and the rest runs.

Writes reports/bench/bench_mitsuba.md. `python -m experiments.bench.bench_mitsuba --help`."""
from __future__ import annotations

import glob
import math
import os
import time
from pathlib import Path

import numpy as np

from experiments.bench import machine, bench_parser, write_page
from experiments.paths import reports_dir

# (label, scene name, subdivide, motion): about 400 to 124k triangles.
SCENES = (("motion_field", "motion_field", 0, True), ("spot_wall", "spot_wall", 0, True),
          ("teapot", "teapot", 0, False), ("bunny", "bunny", 0, False),
          ("modern_hall x4", "modern_hall", 1, False))
SIZES = ((160, 120), (640, 480), (1920, 1080))
SPP = 16
COC_PX = 10.0
THREADS = 2
REFERENCE_SPP_FACTOR = 16
SLIVER = 1e-4               # triangles thinner than this are left out of Mitsuba's mesh (NaN albedo)
MOTION_SLICES = 4            # Mitsuba's slices per image at SPP (SPP / MOTION_SLICES samples each)
REFERENCE_SLICES_MAX = 64
GOAL_RATIO = 5.0             # rast5d tile at least this much faster than llvm_ad_rgb from GOAL_FROM up
GOAL_FROM = 640 * 480
LLVM_GLOBS = ("/usr/lib/x86_64-linux-gnu/libLLVM-1[6-9]*.so*", "/usr/lib/x86_64-linux-gnu/libLLVM-[2-9][0-9]*.so*",
              "/usr/lib/llvm-[1-9][0-9]/lib/libLLVM*.so*", "/usr/lib/aarch64-linux-gnu/libLLVM-1[6-9]*.so*")


def find_llvm() -> str | None:
    """DRJIT_LIBLLVM_PATH, else a libLLVM >= 16 in the usual places, else None."""
    path = os.environ.get("DRJIT_LIBLLVM_PATH")
    if path:
        return path if os.path.exists(path) else None
    for pattern in LLVM_GLOBS:
        found = sorted(glob.glob(pattern))
        if found:
            return found[-1]
    return None


def load_mitsuba():
    """(mitsuba module, variants available here, why not) : the module or None with the reason."""
    llvm = find_llvm()
    if llvm:
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", llvm)
    try:
        import mitsuba as mi
    except ImportError as e:
        return None, [], (f"Mitsuba 3 is not installed ({e}): `pip install rast5d[bench]` (or `make bench`, "
                          "which installs the bench extra)")
    variants = [v for v in ("llvm_ad_rgb", "scalar_rgb") if v in mi.variants()]
    why = ""
    if "llvm_ad_rgb" in variants:
        try:
            mi.set_variant("llvm_ad_rgb")
            import drjit as dr

            dr.zeros(mi.Float, 4)  # touches the LLVM backend
        except Exception as e:  # noqa: BLE001 - no usable LLVM: the variant is left out
            variants.remove("llvm_ad_rgb")
            why = (f"Mitsuba's llvm_ad_rgb variant is unavailable here ({type(e).__name__}: {e}); it needs "
                   "LLVM >= 16 (Debian: apt-get install libllvm19; DRJIT_LIBLLVM_PATH names the library)")
    return mi, variants, why


def _view_space(camera, positions: np.ndarray) -> np.ndarray:
    """World (N, 3, 3) -> the camera's view space (camera at the origin looking down -z, +y up)."""
    m = camera.view_matrix()
    return np.asarray(positions, np.float64) @ m[:3, :3].T + m[:3, 3]


def _area(p: np.ndarray) -> np.ndarray:
    """Twice the area of each triangle as Mitsuba sees it (float32 vertices)."""
    p = np.asarray(p, np.float32).astype(np.float64)
    return np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def _sliver(p: np.ndarray) -> np.ndarray:
    """Twice the area over the squared perimeter (float32 vertices): 0 for a degenerate triangle."""
    q = np.asarray(p, np.float32).astype(np.float64)
    per = sum(np.linalg.norm(q[:, (j + 1) % 3] - q[:, j], axis=1) for j in range(3))
    return _area(p) / np.maximum(per * per, 1e-300)


class MitsubaScene:
    """The scene's triangles in Mitsuba (view space, vertex colours as the mesh attribute
    ``vertex_color``, albedo AOV), a thin-lens sensor of the camera, and a stratified sampler."""

    def __init__(self, mi, variant: str, scene, camera, spp: int):
        mi.set_variant(variant)
        import drjit as dr

        if variant.startswith("llvm"):
            dr.set_thread_count(THREADS)
        self.mi, self.camera, self.spp = mi, camera, spp
        n = scene.n_triangles
        self.p0 = _view_space(camera, scene.positions)
        p1 = scene.positions_t1 if scene.positions_t1 is not None else scene.positions
        self.p1 = _view_space(camera, p1)
        colors = np.asarray(scene.colors if scene.colors is not None else np.full((n, 3, 3), 0.8), np.float32)
        # Degenerate triangles and slivers (area under SLIVER of the squared perimeter) give NaN albedo
        # in Mitsuba's intersector where a ray grazes one; they cover (next to) nothing and are left
        # out of its mesh (counted in self.dropped).
        keep = (_sliver(self.p0) > SLIVER) | (_sliver(self.p1) > SLIVER)
        self.p0, self.p1, colors = self.p0[keep], self.p1[keep], colors[keep]
        n = int(keep.sum())
        self.dropped = int((~keep).sum())
        self.moving = bool(np.any(self.p0 != self.p1))
        t0 = time.perf_counter()
        mesh = mi.Mesh("triangles", 3 * n, n, has_vertex_normals=False, has_vertex_texcoords=False,
                       props=self._mesh_props())
        self.params = mi.traverse(mesh)
        # The buffers' own types (a JIT array in a vectorised variant, a dynamic array in a scalar one).
        self.floats = type(self.params["vertex_positions"])
        self.params["vertex_positions"] = self.floats(self.p0.astype(np.float32).ravel())
        self.params["faces"] = type(self.params["faces"])(np.arange(3 * n, dtype=np.uint32))
        mesh.add_attribute("vertex_color", 3, self.floats(colors.ravel()))
        self.params.update()
        self.scene = mi.load_dict({"type": "scene", "integrator": {"type": "aov", "aovs": "albedo:albedo"},
                                   "sensor": self._sensor(spp), "mesh": mesh})
        self.scene_params = mi.traverse(self.scene)
        self.load_s = time.perf_counter() - t0
        self.key = [k for k in self.scene_params.keys() if k.endswith("vertex_positions")][0]

    def _mesh_props(self):
        props = self.mi.Properties()
        props["bsdf"] = self.mi.load_dict({"type": "diffuse", "reflectance": {"type": "mesh_attribute",
                                                                               "name": "vertex_color"}})
        return props

    def _sensor(self, spp: int) -> dict:
        c = self.camera
        mi = self.mi
        return {"type": "thinlens" if c.coc_px > 0 else "perspective", "fov": c.fov_y_deg, "fov_axis": "y",
                **({"aperture_radius": c.aperture_radius, "focus_distance": c.focus_distance} if c.coc_px > 0 else {}),
                "near_clip": c.near, "far_clip": 1e6,
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0]),
                "sampler": {"type": "stratified", "sample_count": spp},
                "film": {"type": "hdrfilm", "width": c.width, "height": c.height, "rfilter": {"type": "box"},
                         "pixel_format": "rgb", "component_format": "float32"}}

    def render(self, spp: int, slices: int = 1, seed: int = 0) -> np.ndarray:
        """(H, W, 3) float32: one render at spp, or with motion the mean of ``slices`` renders at
        spp / slices samples each, the mesh at each slice's middle time."""
        mi = self.mi
        if not self.moving or slices <= 1:
            return np.array(mi.render(self.scene, spp=spp, seed=seed), dtype=np.float32)
        acc = None
        for k in range(slices):
            t = (k + 0.5) / slices
            self.scene_params[self.key] = self.floats((self.p0 + t * (self.p1 - self.p0)).astype(np.float32).ravel())
            self.scene_params.update()
            img = np.array(mi.render(self.scene, spp=max(1, spp // slices), seed=seed * slices + k), dtype=np.float64)
            acc = img if acc is None else acc + img
        self.scene_params[self.key] = self.floats(self.p0.astype(np.float32).ravel())
        self.scene_params.update()
        return (acc / slices).astype(np.float32)


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2)))


def _scene(name: str, subdivide: int):
    import models

    return models.named(name, subdivide=subdivide) if subdivide else models.named(name)


def side_by_side(mi, variants, sizes=SIZES, scenes=SCENES, spp: int = SPP, repeats: int = 2) -> list[dict]:
    """Rows (scene, triangles, size, renderer, wall, load, rmse) for every scene, size and renderer."""
    import sim

    table = sim.SampleTable.stratified(spp=spp, seed=1)
    cfg = sim.PipelineConfig(algorithm="tile", threads=THREADS)
    rows = []
    for label, name, sub, _ in scenes:
        scene = _scene(name, sub)
        for w, h in sizes:
            cam = sim.Camera.for_scene(scene, width=w, height=h, coc_px=COC_PX)
            runs = {}   # renderer -> (fn, load seconds)
            for timing in (False, True):
                runs[f"rast5d tile, timing {'on' if timing else 'off'}"] = (
                    lambda timing=timing: sim.render(scene, cam, table, cfg, timing=timing).image, 0.0)
            ms = {}
            for v in variants:
                if v == "scalar_rgb" and w * h > sizes[0][0] * sizes[0][1]:
                    continue  # far slower: the smallest frame only
                ms[v] = MitsubaScene(mi, v, scene, cam, spp)
                slices = MOTION_SLICES if ms[v].moving else 1
                runs[f"mitsuba {v}"] = (lambda m=ms[v], s=slices, v=v: (mi.set_variant(v), m.render(spp, s))[1],
                                        ms[v].load_s)
            best, images = {}, {}
            for k in range(repeats):
                for r, (fn, _) in runs.items():
                    t0 = time.perf_counter()
                    img = fn()
                    dt = time.perf_counter() - t0
                    if k == 0:
                        images[r] = img
                    best[r] = min(dt, best.get(r, dt))
            ref_v = "llvm_ad_rgb" if "llvm_ad_rgb" in ms else next(iter(ms), None)
            ref = None
            if ref_v is not None:
                mi.set_variant(ref_v)
                m = ms[ref_v]
                ref_spp = spp * REFERENCE_SPP_FACTOR
                ref = m.render(ref_spp, min(REFERENCE_SLICES_MAX, ref_spp // 4) if m.moving else 1, seed=7)
            for r in runs:
                rows.append(dict(scene=label, triangles=scene.n_triangles, size=f"{w}x{h}", pixels=w * h,
                                 dropped=max((m.dropped for m in ms.values()), default=0),
                                 moving=any(m.moving for m in ms.values()) or bool(scene.positions_t1 is not None),
                                 renderer=r, wall=best[r], load=runs[r][1],
                                 rmse=rmse(images[r], ref) if ref is not None else math.nan))
                print(f"{label:15} {w}x{h:<5} {r:28} {best[r]:8.3f} s  RMSE {rows[-1]['rmse']:.5f}", flush=True)
    return rows


def hd_frame(repeats: int = 2) -> dict:
    """The 1080p frame: the largest interior (modern_hall, every triangle split in four), 1920x1080,
    64 spp, CoC 10, tile, 2 threads, timing on; wall and CPU seconds (minima)."""
    import sim

    scene = _scene("modern_hall", 1)
    cam = sim.Camera.for_scene(scene, width=1920, height=1080, coc_px=10.0)
    table = sim.SampleTable.stratified(spp=64, seed=1)
    cfg = sim.PipelineConfig(algorithm="tile", threads=2)
    sim.render(scene, cam, sim.SampleTable.stratified(spp=1, seed=1), cfg, timing=False)  # page cache
    wall = cpu = math.inf
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        r = sim.render(scene, cam, table, cfg, timing=True)
        wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    return dict(triangles=scene.n_triangles, wall=wall, cpu=cpu, cycles=r.flat_stats["timing.cycles"],
                records=r.flat_stats["timing.records"])


def _geomean(xs) -> float:
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return math.exp(sum(map(math.log, xs)) / len(xs)) if xs else math.nan


def run(quick: bool = False, out=None) -> dict:
    out = reports_dir() / "bench" if out is None else Path(out)
    load0 = os.getloadavg()[0]
    t_start = time.perf_counter()
    mi, variants, why = load_mitsuba()
    sizes = SIZES[:1] if quick else SIZES
    scenes = SCENES[:2] if quick else SCENES
    rows = side_by_side(mi, variants, sizes, scenes, repeats=1 if quick else 2) if mi is not None else []
    hd = None if quick else hd_frame()
    load1 = os.getloadavg()[0]
    lines = ["# bench_mitsuba: rast5d against Mitsuba 3", "",
             f"`python -m experiments.bench.bench_mitsuba` (part of `make bench`), {machine()}, "
             f"load average {load0:.1f} at the start and {load1:.1f} at the end, "
             f"{time.perf_counter() - t_start:.0f} s. Compare the ratios (measured in one run), not the seconds.", ""]
    consts = {"REFERENCE_SPP_FACTOR": f"{REFERENCE_SPP_FACTOR}", "REFERENCE_SLICES_MAX": f"{REFERENCE_SLICES_MAX}"}
    for para in __doc__.split("\n\n")[1:4]:  # what is compared and how, from this module's own text
        text = " ".join(para.split())
        for k, v in consts.items():
            text = text.replace(k, v)
        lines += [text, ""]
    if mi is None or not variants:
        lines += ["**Mitsuba was not run:** " + (why or "no usable variant"), ""]
    elif why:
        lines += ["**Note:** " + why, ""]
    if rows:
        import mitsuba as _m
        import drjit as _dr

        lines += [f"Mitsuba {_m.__version__} (Dr.Jit {_dr.__version__}), variants: {', '.join(variants)}; "
                  f"{SPP} spp, CoC {COC_PX:g} px, {THREADS} threads each; motion: {MOTION_SLICES} slices.", "",
                  "## Wall time and error, scene x size x renderer", "",
                  "RMSE: against the reference (linear RGB). Mitsuba's time is the render of a loaded scene; "
                  "its load (mesh, BVH, kernels' first compile excluded) is the last column.", "",
                  "| scene | triangles | size | renderer | wall [s] | RMSE | Mitsuba load [s] |",
                  "|---|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['size']} | {r['renderer']} | {r['wall']:.3f} | "
                         f"{r['rmse']:.5f} | {r['load']:.3f} |")
        dropped = {r["scene"]: r["dropped"] for r in rows if r["dropped"]}
        if dropped:
            lines += ["", "Left out of Mitsuba's mesh (degenerate or sliver triangles, area under "
                      f"{SLIVER:g} of the squared perimeter, which its intersector shades NaN): "
                      + ", ".join(f"{k} {v:,}" for k, v in dropped.items()) + "."]
        lines += ["", "## Ratios: Mitsuba's wall time over rast5d's (above 1: rast5d is faster)", "",
                  "| scene | size | " + " | ".join(f"{v} / tile, timing {t}" for v in variants for t in ("off", "on"))
                  + " | RMSE tile / llvm_ad_rgb |", "|---|---|" + "---|" * (2 * len(variants) + 1)]
        by = {(r["scene"], r["size"], r["renderer"]): r for r in rows}
        ratios = {(v, t): [] for v in variants for t in ("off", "on")}
        for label, *_ in scenes:
            for w, h in sizes:
                size = f"{w}x{h}"
                cells = []
                for v in variants:
                    for t in ("off", "on"):
                        m, a = by.get((label, size, f"mitsuba {v}")), by.get((label, size, f"rast5d tile, timing {t}"))
                        q = m["wall"] / a["wall"] if m and a else math.nan
                        if w * h >= GOAL_FROM:
                            ratios[(v, t)].append(q)
                        cells.append(f"{q:.1f}" if math.isfinite(q) else "n/a")
                m, a = by.get((label, size, "mitsuba llvm_ad_rgb")), by.get((label, size, "rast5d tile, timing off"))
                e = a["rmse"] / m["rmse"] if m and a and m["rmse"] > 0 else math.nan
                lines.append(f"| {label} | {size} | " + " | ".join(cells) + (f" | {e:.2f} |" if math.isfinite(e) else " | n/a |"))
        lines += ["", f"## Goal: `tile` at least {GOAL_RATIO:g}x faster than llvm_ad_rgb at 640x480 and above", "",
                  "| timing | geometric mean of the ratios | smallest ratio | met |", "|---|---|---|---|"]
        for t in ("off", "on"):
            qs = [q for q in ratios.get(("llvm_ad_rgb", t), []) if math.isfinite(q)]
            if qs:
                lines.append(f"| {t} | {_geomean(qs):.1f} | {min(qs):.1f} | {'yes' if min(qs) >= GOAL_RATIO else 'no'} |")
        fixed = [r for r in rows if r["size"] == f"{sizes[0][0]}x{sizes[0][1]}"]
        if fixed:
            lines += ["", f"At {sizes[0][0]}x{sizes[0][1]} the frame is small enough that fixed costs show: see the "
                      "first rows of each scene (rast5d's setup of every triangle, Mitsuba's kernel launches per pass)."]
    if hd:
        lines += ["", "## 1080p with timing on", "",
                  "The largest interior the repository ships (modern_hall, every triangle split in four), 1920x1080, "
                  "64 spp, CoC 10 px, `tile`, 2 threads, timing and memory model on (default hardware); minima of "
                  "2 renders.", "",
                  "| triangles | wall [s] | CPU [s] | records | cycles |", "|---|---|---|---|---|",
                  f"| {hd['triangles']:,} | {hd['wall']:.2f} | {hd['cpu']:.2f} | {hd['records']:,.0f} | {hd['cycles']:,.0f} |"]
    page = write_page(out, "bench_mitsuba.md", lines)
    return {"page": page, "rows": rows, "hd": hd, "variants": variants, "why": why}


def main(argv=None) -> int:
    ap = bench_parser(__doc__)
    ap.add_argument("--quick", action="store_true", help="the smallest frame, two scenes, one repeat")
    a = ap.parse_args(argv)
    run(a.quick, a.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

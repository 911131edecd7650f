"""Property-based fuzzing of every binding entry point (sim._core) and the Python constructors in front
of them, over raw arrays and parameters: render (scene arrays, sample tables, textures, occlusion
queries), conservative raster, the sample probe, the sample table's lens-grid buckets, the timing
model, the cache model, the texture set-up helpers, SampleTable construction.

The property: a call returns normally (with finite images and non-negative counters) or raises
ValueError / TypeError; it never crashes the interpreter, hangs, or raises anything else. Inputs mix
plausible values (projected triangles, real sample tables, parameters inside their domains) with
wild ones (NaN, inf, huge, negative, wrong shapes and types).

The fast tier runs a fixed, derandomised set of examples per entry point (RAST5D_FUZZ_EXAMPLES,
default 25); `-m slow` runs the long variant (RAST5D_FUZZ_SLOW_EXAMPLES per entry point, default
2000, random). RAST5D_FUZZ_SECONDS bounds the long variant by time instead: each entry point gets an
equal share and runs rounds of RAST5D_FUZZ_SLOW_EXAMPLES examples under successive seeds (from
RAST5D_FUZZ_SEED, default 0) until its share is spent, all in one process. RAST5D_FUZZ_LOG names a JSON file that receives the count of inputs tried per entry
point (per process, `<RAST5D_FUZZ_LOG>.<pid>.json`, for the record of a long run)."""
from __future__ import annotations

import atexit
import json
import os
import time
from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, seed, settings, strategies as st

import sim
from sim import params as sp

pytestmark = pytest.mark.smoke

ALLOWED = (ValueError, TypeError)


def _log():
    """This process's counts to <RAST5D_FUZZ_LOG>.<pid>.json (rewritten, so a killed run keeps them)."""
    path = os.environ.get("RAST5D_FUZZ_LOG")
    if path and TRIED:
        with open(f"{path}.{os.getpid()}.json", "w") as f:
            json.dump(dict(TRIED), f, indent=1, sort_keys=True)


class _Tried(Counter):
    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        if sum(self.values()) % 50 == 0:
            _log()


TRIED = _Tried()
atexit.register(_log)

FAST = settings(max_examples=int(os.environ.get("RAST5D_FUZZ_EXAMPLES", 25)), deadline=None, derandomize=True,
                database=None, suppress_health_check=list(HealthCheck))
LONG = settings(max_examples=int(os.environ.get("RAST5D_FUZZ_SLOW_EXAMPLES", 2000)), deadline=None,
                database=None, suppress_health_check=list(HealthCheck))

# ---- strategies ---------------------------------------------------------------------------------------

SPECIAL = [0.0, -0.0, 1e-38, -1e-38, 1e-7, 1.0, -1.0, 0.5, 1e30, -1e30, 3.4e38, -3.4e38, float("nan"),
           float("inf"), float("-inf")]
wild_float = st.one_of(st.floats(-4, 4), st.floats(width=32), st.sampled_from(SPECIAL))
wild_int = st.one_of(st.integers(-3, 70), st.sampled_from([-2**31, 2**31 - 1, 2**40, -1, 0, 1]))


def _maybe_wild(draw, arr: np.ndarray, p_wild: float = 0.3) -> np.ndarray:
    """Copy of arr with, sometimes, a few entries replaced by wild floats."""
    arr = np.array(arr, dtype=np.float32, copy=True)
    if arr.size and draw(st.floats(0, 1)) < p_wild:
        for _ in range(draw(st.integers(1, 3))):
            idx = draw(st.integers(0, arr.size - 1))
            arr.flat[idx] = np.float32(draw(wild_float))
    return arr


@st.composite
def camera_params(draw):
    """A RenderParams with a small frame: camera fields mostly valid, sometimes wild; pipeline
    fields drawn from their declared domains (sometimes outside them)."""
    w, h = draw(st.integers(1, 40)), draw(st.integers(1, 40))
    cam = sim.Camera(width=w, height=h, coc_px=draw(st.floats(0, 30)),
                     focus_distance=draw(st.floats(0.5, 20)), near=draw(st.floats(0.01, 1.0)),
                     lens=draw(st.sampled_from(["disk", "square", "hexagon"])))
    p = sim._core.RenderParams()
    for k, v in cam.engine_params().items():
        setattr(p, k, v)
    p.lens_shape = cam.lens
    if draw(st.floats(0, 1)) < 0.1:  # wild camera values straight into the engine
        setattr(p, draw(st.sampled_from(["coc_x_px", "coc_y_px", "focus_w", "near_w"])), draw(wild_float))
    for spec in sp.layer("pipeline"):
        rows = spec.members if spec.kind == "group" else (spec,)
        for row in rows:
            if row.engine is None or row.engine in ("threads", "memory_limit_bytes"):
                continue
            value = draw(_domain_value(row))
            try:
                setattr(p, row.engine, value)
            except (TypeError, ValueError):
                pass
    p.threads = draw(st.sampled_from([1, 2]))
    return p, cam


def _domain_value(row):
    if row.choices is not None:
        names = list(row.choices)
        return st.one_of(st.sampled_from(names), st.just("nope")) if row.type == "str" else st.sampled_from(names)
    if row.values is not None:
        vals = list(row.values)
        if row.type == "str":
            return st.sampled_from(vals)
        return st.one_of(st.sampled_from(vals), wild_int) if row.type == "int" else st.sampled_from(vals)
    if row.type == "bool":
        return st.booleans()
    if row.type == "int":
        lo, hi = (row.bounds[0], row.bounds[1]) if row.bounds else (-4, 64)
        lo = -4 if lo is None else lo
        hi = 64 if hi is None else min(hi, max(lo, 0) + 64)
        return st.one_of(st.integers(lo, hi), st.integers(-4, 64))
    if row.type == "float":
        return st.one_of(st.floats(-2, 64), wild_float)
    if row.type == "range":
        return st.one_of(st.just(list(row.default)), st.lists(wild_float, min_size=2, max_size=2),
                         st.tuples(st.floats(-1, 1), st.floats(-1, 1)).map(sorted).map(list))
    return st.just(row.default)


@st.composite
def triangles(draw, cam: sim.Camera, n_max: int = 6):
    """(v0, v1) engine vertices: projected world triangles (static or moving, some behind the camera
    or crossing the focus plane), sometimes raw wild arrays or wrong shapes."""
    n = draw(st.integers(0, n_max))
    kind = draw(st.sampled_from(["projected", "projected", "projected", "raw", "shape"]))
    if kind == "shape":
        shape = draw(st.sampled_from([(n, 3), (n, 3, 4), (n, 2, 3), (3, 3), (n, 3, 3, 1)]))
        a = np.zeros(shape, np.float32)
        return a, a
    if kind == "raw":
        a = np.array(draw(st.lists(wild_float, min_size=n * 9, max_size=n * 9)), np.float32).reshape(n, 3, 3)
        b = np.array(draw(st.lists(wild_float, min_size=n * 9, max_size=n * 9)), np.float32).reshape(n, 3, 3)
        return a, b
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    center = rng.normal(0, 2, (n, 1, 3)) + [0, 0, -draw(st.floats(-1, 12))]
    p0 = center + rng.normal(0, draw(st.sampled_from([0.01, 0.5, 2, 50])), (n, 3, 3))
    p1 = p0 + (rng.normal(0, draw(st.sampled_from([0.0, 0.3, 3])), (n, 1, 3)))
    with np.errstate(all="ignore"):
        v0, v1 = cam.engine_vertices(p0, p1)
    return _maybe_wild(draw, v0, 0.15), _maybe_wild(draw, v1, 0.15)


@st.composite
def sample_arrays(draw):
    """(samples, lens_index, lens_uv, table-or-None) from a real generator, sometimes perturbed or
    reshaped."""
    kind = draw(st.sampled_from(sim.SampleTable.generators()))
    params = dict(spp=draw(st.sampled_from([1, 2, 4, 8, 16])), seed=draw(st.integers(0, 5)),
                  period=draw(st.sampled_from([1, 2, 4, 8])))
    if kind == "multiview":
        params["views"] = draw(st.sampled_from([1, 2, 4]))
    try:
        table = sim.SampleTable.create(kind, **params)
    except ValueError:
        table = sim.SampleTable.create("random", spp=4, seed=0, period=2)
    samples = table.samples("disk")
    if getattr(table, "n_lens", 0):
        li = np.ascontiguousarray(table.lens_index, np.int32)
        luv = np.ascontiguousarray(table.lens_positions("disk"), np.float32)
    else:
        li, luv = np.zeros((0,), np.int32), np.zeros((0, 2), np.float32)
    samples = _maybe_wild(draw, samples, 0.2)
    if li.size and draw(st.floats(0, 1)) < 0.2:
        li = li.copy()
        li.flat[draw(st.integers(0, li.size - 1))] = np.clip(draw(wild_int), -2**31, 2**31 - 1)
    if draw(st.floats(0, 1)) < 0.05:
        samples = samples.reshape(-1, 5)[: draw(st.integers(0, 8))].reshape(1, 1, -1, 5) if samples.size else samples
    return samples, li, luv


@st.composite
def texture_inputs(draw, n: int):
    """(uvs, tex_slots, textures) for n triangles: small odd-sized textures of 1..5 channels."""
    k = draw(st.integers(0, 2))
    textures = []
    for _ in range(k):
        shape = (draw(st.integers(1, 9)), draw(st.integers(1, 9)), draw(st.integers(1, 5)))
        t = np.random.default_rng(draw(st.integers(0, 99))).random(shape).astype(np.float32)
        textures.append(_maybe_wild(draw, t, 0.1))
    uvs = _maybe_wild(draw, np.random.default_rng(draw(st.integers(0, 99))).normal(0, 3, (n, 3, 2)), 0.1)
    slots = np.array(draw(st.lists(st.integers(-2, 3), min_size=n * 4, max_size=n * 4)), np.int32).reshape(n, 4)
    if draw(st.booleans()):
        return None, None, textures
    return uvs, slots, textures


def _check_render_output(out, p, colors):
    img = out["image"]
    assert img.shape == (p.height, p.width, 3)
    if np.abs(colors).max(initial=0) < 1e30:  # (colours near float32's end may sum to inf)
        assert np.isfinite(img).all()
    assert all(v >= 0 for v in out["counters"].values())


def _call(fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except ALLOWED:
        return None


# ---- the entry points --------------------------------------------------------------------------------

def _render_case(data, query: bool):
    TRIED["render" + ("+query" if query else "")] += 1
    p, cam = data.draw(camera_params())
    v0, v1 = data.draw(triangles(cam))
    n = v0.shape[0] if v0.ndim else 0
    colors = _maybe_wild(data.draw, np.full((n, 3, 3), 0.5) if v0.ndim == 3 else np.zeros((n, 3, 3)), 0.05)
    samples, li, luv = data.draw(sample_arrays())
    uvs, slots, textures = data.draw(texture_inputs(n))
    if query:
        p.query_first = data.draw(st.integers(-3, n + 3))
        _call(setattr, p, "query_mode", data.draw(st.sampled_from(sim.intervals.query_modes() + ["none", "nope"])))
    p.record_timing = data.draw(st.booleans())
    p.texture_sample_distribution_index = data.draw(st.integers(-2, 3))
    _call(setattr, p, "lens_grid", data.draw(st.sampled_from([1, 2, 4, 8, 16, 0, 3])))
    out = _call(sim._core.render, p, v0, v1, colors, samples, li, luv, data.draw(st.booleans()),
                uvs=uvs, tex_slots=slots, textures=textures)
    if out is not None:
        _check_render_output(out, p, colors)


@FAST
@given(st.data())
def test_fuzz_render(data):
    _render_case(data, query=False)


@FAST
@given(st.data())
def test_fuzz_occlusion_query(data):
    _render_case(data, query=True)


def _conservative_case(data):
    TRIED["conservative_raster"] += 1
    p, cam = data.draw(camera_params())
    v0, v1 = data.draw(triangles(cam))
    reduce = data.draw(st.booleans())
    out = _call(sim._core.conservative_raster, p, v0, v1, reduce, data.draw(st.integers(0, 5000)))
    if out is not None and reduce:
        assert out["count"].shape == (p.height, p.width) and (out["count"] >= 0).all()


@FAST
@given(st.data())
def test_fuzz_conservative_raster(data):
    _conservative_case(data)


def _probe_case(data):
    TRIED["probe"] += 1
    p, cam = data.draw(camera_params())
    v0, v1 = data.draw(triangles(cam, n_max=1))
    v0 = v0[0] if v0.ndim == 3 and len(v0) else np.zeros((3, 3), np.float32)
    v1 = v1[0] if v1.ndim == 3 and len(v1) else v0
    m = data.draw(st.integers(0, 16))
    pts = np.array(data.draw(st.lists(wild_float, min_size=5 * m, max_size=5 * m)), np.float32).reshape(m, 5)
    _call(sim._core.probe, p, v0, v1, pts, data.draw(st.booleans()))


@FAST
@given(st.data())
def test_fuzz_probe(data):
    _probe_case(data)


def _probe_4d_case(data):
    TRIED["precision_probe_4d"] += 1
    p, cam = data.draw(camera_params())
    v0, _ = data.draw(triangles(cam, n_max=1))
    v0 = v0[0] if v0.ndim == 3 and len(v0) else np.zeros((3, 3), np.float32)
    p.precision_tile = data.draw(st.sampled_from(["float64", "float32", {"fixed": {"int_bits": 8, "frac_bits": 0}},
                                                  {"fixed": {"int_bits": 40, "frac_bits": 4}},
                                                  {"fixed": {"int_bits": 62, "frac_bits": 18}}]))
    k = data.draw(st.integers(0, 6))
    tiles = np.array(data.draw(st.lists(wild_float, min_size=4 * k, max_size=4 * k)), np.float64).reshape(k, 4)
    if data.draw(st.booleans()):  # lens boxes for the screen bounds (wild values are refused or bounded)
        kb = data.draw(st.integers(0, 4))
        boxes = np.array(data.draw(st.lists(wild_float, min_size=4 * kb, max_size=4 * kb)), np.float64).reshape(kb, 4)
        _call(sim._core.precision_probe_4d, p, v0, tiles, boxes)
    else:
        _call(sim._core.precision_probe_4d, p, v0, tiles)


@FAST
@given(st.data())
def test_fuzz_precision_probe_4d(data):
    _probe_4d_case(data)


def _probe_5d_case(data):
    TRIED["precision_probe_5d"] += 1
    p, cam = data.draw(camera_params())
    v0, v1 = data.draw(triangles(cam, n_max=1))
    v0 = v0[0] if v0.ndim == 3 and len(v0) else np.zeros((3, 3), np.float32)
    v1 = v1[0] if v1.ndim == 3 and len(v1) else v0
    p.precision_tile = data.draw(st.sampled_from(["float64", "float32", {"fixed": {"int_bits": 8, "frac_bits": 0}},
                                                  {"fixed": {"int_bits": 40, "frac_bits": 4}},
                                                  {"fixed": {"int_bits": 62, "frac_bits": 18}}]))
    k = data.draw(st.integers(0, 6))
    tiles = np.array(data.draw(st.lists(wild_float, min_size=4 * k, max_size=4 * k)), np.float64).reshape(k, 4)
    m = k if data.draw(st.floats(0, 1)) < 0.9 else data.draw(st.integers(0, 7))  # sometimes a wrong count
    pts = np.array(data.draw(st.lists(wild_float, min_size=5 * m, max_size=5 * m)), np.float64).reshape(m, 5)
    _call(sim._core.precision_probe_5d, p, v0, v1, tiles, pts)


@FAST
@given(st.data())
def test_fuzz_precision_probe_5d(data):
    _probe_5d_case(data)


def _gpu_bound_case(data):
    TRIED["gpu_bound"] += 1
    p, cam = data.draw(camera_params())
    v0, v1 = data.draw(triangles(cam, n_max=1))
    v0 = v0[0] if v0.ndim == 3 and len(v0) else np.zeros((3, 3), np.float32)
    v1 = v1[0] if v1.ndim == 3 and len(v1) else v0
    method = data.draw(st.sampled_from(["pe_triangle", "vr_triangle", "hexagon2d", "wedge", "reduced_wedge",
                                        "hexagon3d", "convex_hull", "adaptive", "box", "nope"]))
    _call(sim._core.gpu_bound, method, p, v0, v1, data.draw(st.booleans()))


@FAST
@given(st.data())
def test_fuzz_gpu_bound(data):
    _gpu_bound_case(data)


def _buckets_case(data):
    TRIED["lens_grid_buckets"] += 1
    samples, _, _ = data.draw(sample_arrays())
    _call(sim._core.lens_grid_buckets, samples, data.draw(wild_int))


@FAST
@given(st.data())
def test_fuzz_lens_grid_buckets(data):
    _buckets_case(data)


def _table_case(data):
    TRIED["sample_table"] += 1
    if data.draw(st.booleans()):
        kind = data.draw(st.sampled_from(sim.SampleTable.generators() + ["nope"]))
        kw = {k: data.draw(st.one_of(wild_int, st.sampled_from([1, 4, 16]))) for k in
              data.draw(st.sets(st.sampled_from(["spp", "seed", "period", "n_lens", "views"])))}
        for k in data.draw(st.sets(st.sampled_from(["lens", "time"]))):
            kw[k] = data.draw(st.one_of(st.booleans(), st.just(3)))
        if kw.get("spp", 1) * kw.get("period", 1) ** 2 > 20000:
            kw["period"] = 1
        t = _call(sim.SampleTable.create, kind, **kw)
    else:
        samples, li, luv = data.draw(sample_arrays())
        if data.draw(st.booleans()):
            samples = samples[0, 0]
        t = _call(sim.SampleTable.from_array, samples, lens_index=li if li.size else None,
                  lens_positions=luv if li.size else None,
                  lens=data.draw(st.sampled_from(["any", "disk", "square", "hexagon", "x"])))
    if t is not None:
        s = _call(t.samples, "disk")
        if s is not None:
            assert np.isfinite(s).all()


@FAST
@given(st.data())
def test_fuzz_sample_table_construction(data):
    _table_case(data)


def _texture_case(data):
    TRIED["texture_setup"] += 1
    which = data.draw(st.sampled_from(["lod", "address", "scene"]))
    if which == "lod":
        n = data.draw(st.integers(0, 4))
        v0 = np.array(data.draw(st.lists(wild_float, min_size=9 * n, max_size=9 * n)), np.float32).reshape(n, 3, 3)
        uvs = np.array(data.draw(st.lists(wild_float, min_size=6 * n, max_size=6 * n)), np.float32).reshape(n, 3, 2)
        _call(sim._core.triangle_lod, v0, uvs, data.draw(wild_int), data.draw(wild_int), data.draw(wild_float))
    elif which == "address":
        layout = data.draw(st.sampled_from(sim.texture_layouts() + ["nope"]))
        _call(sim._core.texel_address, data.draw(wild_int), data.draw(wild_int), layout, data.draw(wild_int),
              data.draw(wild_int), data.draw(wild_int))
    else:  # models.Scene with textures, through sim.render
        import models

        n = data.draw(st.integers(1, 3))
        _, _, textures = data.draw(texture_inputs(n))
        rng = np.random.default_rng(data.draw(st.integers(0, 99)))
        pos = rng.normal(0, 1, (n, 3, 3)) + [0, 0, -4]
        scene = _call(models.Scene.from_arrays, pos, uvs=rng.normal(0.5, 1, (n, 3, 2)),
                      textures=textures or None,
                      texture_ids=rng.integers(-1, max(len(textures), 1), n) if textures else None)
        if scene is not None:
            cfg = _call(sim.PipelineConfig, shading=data.draw(st.sampled_from(sim.shading_modes())),
                        texture_filter=data.draw(st.sampled_from(sim.texture_filters())),
                        texture_layout=data.draw(st.sampled_from(sim.texture_layouts())),
                        texture_count=data.draw(st.integers(0, 2)), threads=1)
            if cfg is not None:
                r = _call(sim.render, scene, sim.Camera(width=12, height=12, coc_px=3),
                          sim.SampleTable.create("stratified", spp=4, seed=1), cfg)
                if r is not None:
                    assert np.isfinite(r.image).all()


@FAST
@given(st.data())
def test_fuzz_texture_setup(data):
    _texture_case(data)


def _timing_case(data):
    TRIED["timing_and_cache"] += 1
    if data.draw(st.booleans()):
        dtype = sim._core.timing_record_dtype()
        n = data.draw(st.integers(0, 20))
        raw = np.frombuffer(np.random.default_rng(data.draw(st.integers(0, 99))).bytes(n * dtype.itemsize),
                            dtype=dtype).copy()
        if data.draw(st.booleans()):  # plausible records: small counts, bins in range
            for name in dtype.names:
                raw[name] = np.abs(raw[name].astype(np.int64)) % 50
        k = data.draw(st.sampled_from([len(sim._core.timing_units()), 0, 3]))
        lists = [data.draw(st.lists(st.one_of(st.floats(0.01, 64), wild_float), min_size=k, max_size=k))
                 for _ in range(2)]
        fifo = data.draw(st.lists(st.one_of(st.integers(1, 64), wild_int), min_size=k, max_size=k))
        out = _call(sim._core.timing_estimate, raw, lists[0], lists[1], fifo, data.draw(wild_float),
                    data.draw(wild_float), data.draw(st.one_of(st.integers(1, 4), wild_int)))
        if out is not None:
            assert all(np.isfinite(v) and v >= 0 for v in out.values())
    else:
        lines = np.random.default_rng(data.draw(st.integers(0, 99))).integers(
            0, data.draw(st.integers(1, 2**63 - 1)), data.draw(st.integers(0, 200)), dtype=np.uint64)
        _call(sim._core.simulate_cache, lines, data.draw(wild_int), data.draw(wild_int))


@FAST
@given(st.data())
def test_fuzz_timing_and_cache_models(data):
    _timing_case(data)


# ---- the long variant ----------------------------------------------------------------------------------

CASES = {"render": lambda d: _render_case(d, False), "occlusion_query": lambda d: _render_case(d, True),
         "conservative_raster": _conservative_case, "probe": _probe_case, "gpu_bound": _gpu_bound_case,
         "precision_probe_4d": _probe_4d_case,
         "precision_probe_5d": _probe_5d_case,
         "lens_grid_buckets": _buckets_case,
         "sample_table": _table_case, "texture_setup": _texture_case, "timing_and_cache": _timing_case}


@pytest.mark.slow
@pytest.mark.parametrize("entry", sorted(CASES))
def test_fuzz_long(entry):
    def run(data):
        CASES[entry](data)

    share = float(os.environ.get("RAST5D_FUZZ_SECONDS", 0)) / len(CASES)
    first = int(os.environ.get("RAST5D_FUZZ_SEED", 0))
    if share <= 0:
        LONG(given(data=st.data())(run))()
        return
    end, n = time.monotonic() + share, first
    while time.monotonic() < end:
        seed(n)(LONG(given(data=st.data())(run)))()
        TRIED[f"{entry}.rounds"] += 1
        n += 1

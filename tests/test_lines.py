"""Line samples ([Tzeng 2012] §3-4; algorithm 'lines'): closed-form coverage of a
defocused edge, agreement with point sampling (heuristics off, unlimited buffer), the tile-clipped
path's image, documented == counted operations, and clear errors for wrong combinations."""
from __future__ import annotations

import numpy as np
import pytest

import sim
from models import Scene

W, H = 24, 8


def _quad(x0, x1, y0, y1, z, color=(1.0, 1.0, 1.0)):
    a, b, c, d = (x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)
    pos = np.array([[a, b, c], [a, c, d]], dtype=np.float64)
    col = np.broadcast_to(np.asarray(color, dtype=np.float64), (2, 3, 3)).copy()
    return pos, col


def _scene(*quads):
    pos = np.concatenate([q[0] for q in quads])
    col = np.concatenate([q[1] for q in quads])
    return Scene.from_arrays(pos, colors=col)


def _lines_config(**lines):
    base = {"buffer_size": 0, "min_weight": 0.0, "occlusion": False, "merge": False, "merge_depth": 0.0,
            "merge_color": 0.0, "merge_gap": 0.0, "tile_clip": False}
    base.update(lines)
    return sim.PipelineConfig(algorithm="lines", threads=1, lines=base)


def _kappa(p1, p2):
    return 0.5 * (p2 * np.abs(p2) - p1 * np.abs(p1))


def test_defocused_edge_matches_closed_form_per_line():
    """A large white quad at w = 10 with its right edge at the image centre, focus 5, CoC 8 px at
    infinity: the edge moves by u K (1 - F/w) = 4u px. A line (c, s) at screen x covers the lens
    points with x < x_e + 4 p c; its κ-weighted coverage has a closed form, and the pixel is the
    mean over its lines."""
    cam = sim.Camera(width=W, height=H, focus_distance=5.0, coc_px=8.0)
    scene = _scene(_quad(-500.0, 0.0, -500.0, 500.0, -10.0))
    table = sim.SampleTable.lines(n_lines=8, seed=3)
    img = sim.render(scene, cam, table, _lines_config(), timing=False).image
    smp = table.samples("disk").astype(np.float64)
    x_e, shift = W / 2.0, 8.0 * (1.0 - 5.0 / 10.0)
    expect = np.zeros((H, W))
    for py in range(H):
        for px in range(W):
            s = smp[py % table.period, px % table.period]
            d = (px + s[:, 0] - x_e) / shift  # covered where p c > d
            c = s[:, 2]
            q = np.clip(d / c, -1.0, 1.0)
            k = np.where(c > 0, _kappa(q, 1.0), _kappa(-1.0, q))
            expect[py, px] = k.mean()
    np.testing.assert_allclose(img[..., 0], expect, atol=2e-5)
    # The wagon-wheel average over angles converges to the disk's area fraction (sanity of κ).
    assert 0.0 < img[0, 0, 0] <= 1.0 and img[0, W - 1, 0] == 0.0


def test_kappa_weights_are_unbiased_for_the_disk():
    """Over uniform angles, the κ-weighted coverage of u > d equals the disk area with u > d."""
    d = 0.3
    theta = (np.arange(20000) + 0.5) / 20000 * np.pi
    c = np.cos(theta)
    q = np.clip(d / c, -1.0, 1.0)
    k = np.where(c > 0, _kappa(q, 1.0), _kappa(-1.0, q))
    area = (np.arccos(d) - d * np.sqrt(1 - d * d)) / np.pi
    assert abs(k.mean() - area) < 1e-4


def _layered_scene():
    return _scene(
        _quad(-500.0, 500.0, -500.0, 500.0, -12.0, (0.2, 0.4, 0.9)),   # background, behind focus
        _quad(-0.6, 0.35, -0.3, 0.5, -3.0, (0.9, 0.3, 0.1)),         # in front of focus
        _quad(0.1, 1.2, -0.6, 0.2, -5.5, (0.2, 0.9, 0.3)),           # near focus
    )


def _wheel_angles_squeezed(table, share: float):
    """The table with every line's angle θ in [0, π) moved to share x θ: the wagon wheels then miss the last
    (1 - share) of the lens directions, a biased line sampler (the κ weights are unbiased only over uniform
    angles: test_kappa_weights_are_unbiased_for_the_disk)."""
    arr = np.array(table.samples("disk"))
    theta = np.arctan2(arr[..., 3], arr[..., 2]) % np.pi * share
    arr[..., 2], arr[..., 3] = np.cos(theta), np.sin(theta)
    table._final = arr.astype(np.float32)
    table._samples_cache.clear()
    return table


def _line_and_point_means(share: float = 1.0, seeds: int = 6):
    """(difference of the per-pixel means, combined standard error of that difference) of `seeds` renders
    with 64 lines (heuristics off, unlimited buffer: an unbiased estimator) and of two brute-force renders
    with 1024 stratified points."""
    cam = sim.Camera(width=W, height=16, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    scene = _layered_scene()
    lines = np.array([sim.render(scene, cam, _wheel_angles_squeezed(sim.SampleTable.lines(n_lines=64, seed=s), share)
                                 if share != 1.0 else sim.SampleTable.lines(n_lines=64, seed=s),
                                 _lines_config(), timing=False).image for s in range(seeds)])
    points = np.array([sim.render(scene, cam, sim.SampleTable.stratified(spp=1024, seed=s, time=False),
                                  sim.PipelineConfig(algorithm="bruteforce", threads=1), timing=False).image
                       for s in (5, 6)])
    se = np.sqrt(lines.var(0, ddof=1) / len(lines) + points.var(0, ddof=1) / len(points))
    return lines.mean(0) - points.mean(0), se


def test_lines_agree_with_point_sampling():
    """Heuristics off and an unlimited buffer: an unbiased estimate. The mean of six 64-line renders and the
    mean of two 1024-point renders (brute force) agree to within twice their combined standard error, RMS over
    the image (measured: 1.3 times). Power: a line sampler whose wheels miss a tenth of the lens directions
    (test_a_biased_line_sampler_is_caught) differs by about 4 times the standard error (RMS 0.008 against
    0.002 here) and fails, as does one missing a fifth (RMS 0.015), which a bound of RMSE < 0.02 on one
    render would let pass."""
    diff, se = _line_and_point_means()
    noise = np.sqrt(np.mean(se ** 2))
    rms = np.sqrt(np.mean(diff ** 2))
    assert rms < 2 * noise, (rms, noise)
    assert abs(diff.mean()) < 4 * noise / np.sqrt(diff.size) + 1e-4, (diff.mean(), noise)


def test_a_biased_line_sampler_is_caught():
    """The agreement test above fails on a biased line sampler: wagon-wheel angles over 0.9 of [0, π)."""
    diff, se = _line_and_point_means(share=0.9)
    assert np.sqrt(np.mean(diff ** 2)) > 2 * np.sqrt(np.mean(se ** 2))


def test_lines_counters_are_nonzero():
    cam = sim.Camera(width=W, height=16, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    s = sim.render(_layered_scene(), cam, sim.SampleTable.lines(n_lines=16, seed=1), _lines_config(),
                   timing=False).flat_stats
    assert s["lines.tests"] > 0 and s["lines.segments"] > 0


def test_occlusion_heuristic_keeps_the_image():
    """The occlusion test removes only fully hidden segments: same image up to float rounding."""
    cam = sim.Camera(width=W, height=16, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    scene = _layered_scene()
    table = sim.SampleTable.lines(n_lines=16, seed=2)
    a = sim.render(scene, cam, table, _lines_config(), timing=False)
    b = sim.render(scene, cam, table, _lines_config(occlusion=True), timing=False)
    np.testing.assert_allclose(a.image, b.image, atol=1e-5)
    assert b.flat_stats["lines.rejected_occluded"] + b.flat_stats["lines.segments_replaced"] > 0


def test_tile_clip_same_image_fewer_tests():
    cam = sim.Camera(width=32, height=24, focus_distance=5.0, coc_px=10.0, fov_y_deg=30.0)
    scene = _layered_scene()
    table = sim.SampleTable.lines(n_lines=16, seed=4)
    cfg = sim.PipelineConfig(algorithm="lines", threads=1)
    a = sim.render(scene, cam, table, cfg, timing=False)
    b = sim.render(scene, cam, table, cfg.replace(lines={**cfg.lines, "tile_clip": True}), timing=False)
    assert np.array_equal(a.image, b.image)
    sa, sb = a.flat_stats, b.flat_stats
    assert sb["lines.culled_tile"] > 0
    assert sb["lines.tests"] + sb["lines.culled_tile"] == sa["lines.tests"]
    assert sb["lines.segments"] == sa["lines.segments"]


@pytest.mark.parametrize("variant", ["default", "small_buffer", "tile_clip", "near", "textured"])
def test_documented_costs_equal_counted(variant):
    """Every counter, operations included, is the same on the fast path (documented costs) and
    the counting scalar path."""
    cam = sim.Camera(width=W, height=16, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    scene = _layered_scene()
    lines = dict(sim.PipelineConfig().lines)
    if variant == "small_buffer":
        lines.update(buffer_size=1, merge=False)
    if variant == "tile_clip":  # several bins: per-triangle work is charged once, in its first bin
        lines.update(tile_clip=True)
        cam = sim.Camera(width=80, height=72, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    if variant == "near":  # a floor crossing the near plane: the near function of the interval
        pos = np.array([[[-5, -1, 1.0], [5, -1, 1.0], [0, -1, -20.0]]])
        scene = Scene.concat(scene, Scene.from_arrays(pos, colors=(0.7, 0.7, 0.2)))
    table = sim.SampleTable.lines(n_lines=8, seed=7)
    cfg = sim.PipelineConfig(algorithm="lines", threads=1, lines=lines)
    if variant == "textured":  # textured segments, their shading lanes and fetches
        scene = Scene.from_arrays(scene.positions, colors=scene.colors,
                                  uvs=(scene.positions[..., :2] * 0.3 + 0.5).astype(np.float32),
                                  texture=np.random.default_rng(1).uniform(0, 1, (32, 32, 3)).astype(np.float32))
        cfg = cfg.replace(texture_count=1, shading="per_sample")
    doc = sim.render(scene, cam, table, cfg, timing=False)
    exact = sim.render(scene, cam, table, cfg.replace(op_count="exact"), timing=False)
    assert np.array_equal(doc.image, exact.image)
    keys = [k for k in doc.flat_stats if k.startswith(("ops.", "lines.", "tile.", "shade.", "tex."))]
    assert {k: doc.flat_stats[k] for k in keys} == {k: exact.flat_stats[k] for k in keys}
    if variant == "small_buffer":
        assert doc.flat_stats["lines.overflows"] > 0


def test_thread_count_does_not_change_results():
    cam = sim.Camera(width=80, height=72, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    scene = _layered_scene()
    table = sim.SampleTable.lines(n_lines=8, seed=7)
    cfg = sim.PipelineConfig(algorithm="lines", threads=1)
    a = sim.render(scene, cam, table, cfg, timing=False)
    b = sim.render(scene, cam, table, cfg.replace(threads=2), timing=False)
    assert np.array_equal(a.image, b.image)
    assert {k: v for k, v in a.flat_stats.items() if k != "time.wall_s"} == \
        {k: v for k, v in b.flat_stats.items() if k != "time.wall_s"}


def test_wrong_combinations_are_clear_errors():
    cam = sim.Camera(width=8, height=8, coc_px=4.0)
    scene = _scene(_quad(-1, 1, -1, 1, -6.0))
    lines_table = sim.SampleTable.lines(n_lines=4)
    with pytest.raises(sim.ConfigError, match="algorithm.*line-sample table"):
        sim.render(scene, cam, lines_table, sim.PipelineConfig(algorithm="bruteforce"))
    with pytest.raises(sim.ConfigError, match="algorithm: 'lines' needs a line-sample table"):
        sim.render(scene, cam, sim.SampleTable.stratified(spp=4), sim.PipelineConfig(algorithm="lines"))
    moving = Scene.from_arrays(scene.positions, positions_t1=scene.positions + 0.1)
    with pytest.raises(sim.ConfigError, match="motion blur needs point samples"):
        sim.render(moving, cam, lines_table, sim.PipelineConfig(algorithm="lines"))
    with pytest.raises(sim.ConfigError, match="camera.lens: line samples .* disk lens.* got .square."):
        sim.render(scene, sim.Camera(width=8, height=8, coc_px=4.0, lens="square"), lines_table,
                   sim.PipelineConfig(algorithm="lines"))
    with pytest.raises(sim.ConfigError, match="shading.*per_lens_cell"):
        sim.render(scene, cam, lines_table, sim.PipelineConfig(algorithm="lines", shading="per_lens_cell"))
    with pytest.raises(sim.ConfigError, match="buffer_size"):
        sim.PipelineConfig(algorithm="lines", lines={**sim.PipelineConfig().lines, "buffer_size": -1})
    with pytest.raises(sim.ConfigError, match="min_weight"):
        sim.PipelineConfig(algorithm="lines", lines={**sim.PipelineConfig().lines, "min_weight": 2.0})
    with pytest.raises(ValueError, match="n_lines"):
        sim.SampleTable.lines(n_lines=6, wheel=4)
    with pytest.raises(ValueError, match="n_lines"):
        sim.SampleTable.lines(n_lines=0)


def test_yaml_lines_config(tmp_path):
    from experiments.config import build, load_config

    path = tmp_path / "c.yaml"
    path.write_text("scene: {name: spot_wall}\ncamera: {width: 16, height: 16, coc_px: 8}\n"
                    "samples: {kind: lines, n_lines: 8}\npipeline: {algorithm: lines}\n")
    scene, camera, table, pipeline = build(load_config(path))
    assert table.kind == "lines" and table.spp == 8 and pipeline.algorithm == "lines"
    bad = tmp_path / "bad.yaml"
    bad.write_text("scene: {name: spot_wall}\nsamples: {kind: stratified, n_lines: 8}\n")
    with pytest.raises(ValueError, match="n_lines"):
        build(load_config(bad))


def test_composite_is_timed():
    """The segment buffers' work reaches the timing model: each offered segment and each composite
    step ([Tzeng 2012] Fig. 3) is one depth-unit item, the composite as one record per bin after the bin's
    triangles. With a slow depth unit the frame is depth-bound, and removing the end-of-bin
    records (re-timing the rest) lowers the estimated cycles."""
    cam = sim.Camera(width=80, height=72, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    hw = sim.HardwareConfig(depth={"throughput": 0.25})
    r = sim.render(_layered_scene(), cam, sim.SampleTable.lines(n_lines=8, seed=7),
                   sim.PipelineConfig(algorithm="lines", threads=2, bin_size=32), hardware=hw,
                   keep_timing_records=True)
    s, recs = r.flat_stats, r.timing_records
    assert s["lines.composite_steps"] > 0
    assert recs["depth_tests"].sum() == s["lines.segments"] + s["lines.composite_steps"]
    end_of_bin = (recs["triangles"] == 0) & (recs["sample_tests"] == 0) & (recs["depth_tests"] > 0)
    assert recs["depth_tests"][end_of_bin].sum() == s["lines.composite_steps"]
    assert set(recs["bin"][end_of_bin]) == set(range(3 * 3))  # every bin with lines composites once
    assert s["timing.cycles"] >= (s["lines.segments"] + s["lines.composite_steps"]) / 0.25
    without = sim.timing.estimate(recs[~end_of_bin], hw)["timing.cycles"]
    assert s["timing.cycles"] - without >= 0.9 * s["lines.composite_steps"] / 0.25


# ---- texturing: each segment textured at its midpoint ([Tzeng 2012] §3.1.2 "Shading") ---------------------------

def _textured_square(z=-6.0, texels=4, seed=3):
    """A square (two triangles) parallel to the lens at view depth -z with uv = its own (x, y)
    normalised, and a random texels x texels texture."""
    x0, x1, y0, y1 = -0.9, 0.7, -0.6, 0.5
    a, b, c, d = (x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)
    pos = np.array([[a, b, c], [a, c, d]], dtype=np.float64)
    uv_of = lambda p: ((p[0] - x0) / (x1 - x0), (p[1] - y0) / (y1 - y0))  # noqa: E731
    uvs = np.array([[uv_of(p) for p in tri] for tri in pos])
    tex = np.random.default_rng(seed).uniform(0.1, 1.0, (texels, texels, 3)).astype(np.float32)
    return pos, uv_of, tex, Scene.from_arrays(pos, uvs=uvs, texture=tex)


def test_textured_segments_match_a_numpy_reference():
    """Heuristics off: each pixel is the mean over its lines of Σ κ(segment) · texture(uv at the
    segment's midpoint). The reference casts float64 rays (experiments/reference/raycaster.py) from the two
    ends of each line through the pixel's screen point: on a plane parallel to the lens the hit point
    is affine in the line parameter p, so each triangle's segment is an intersection of three
    half-lines, its midpoint's uv is affine, and the texture is read by models.textures'
    sample_bilinear (texels larger than pixels: level 0)."""
    from models.textures import sample_bilinear
    from experiments.reference import raycaster as rc

    w, h = 24, 16
    cam = sim.Camera(width=w, height=h, focus_distance=5.0, coc_px=20.0, fov_y_deg=30.0)
    z = -6.0
    pos, uv_of, tex, scene = _textured_square(z)
    table = sim.SampleTable.lines(n_lines=8, seed=3)
    res = sim.render(scene, cam, table, _lines_config().replace(texture_count=1, texture_filter="bilinear"),
                     timing=False)
    smp = table.samples("disk").astype(np.float64)
    ref = np.zeros((h, w, 3))
    for py in range(h):
        for px in range(w):
            for sx, sy, c, s, _ in smp[py % table.period, px % table.period]:
                ends = np.array([[px + sx, py + sy, -c, -s, 0.0], [px + sx, py + sy, c, s, 0.0]])
                org, d = rc.sample_rays(cam, ends)
                hit = (org + (-z / cam.focus_distance) * d)[:, :2]  # view depth -z
                h0, h1 = (hit[0] + hit[1]) / 2, (hit[1] - hit[0]) / 2  # hit(p) = h0 + p h1
                for tri in pos:
                    lo, hi, empty = -1.0, 1.0, False
                    for i in range(3):
                        A, B = tri[i, :2], tri[(i + 1) % 3, :2]
                        g = lambda q: (B[0] - A[0]) * (q[1] - A[1]) - (B[1] - A[1]) * (q[0] - A[0])  # noqa: E731
                        g0, g1 = g(h0), g(h0 + h1) - g(h0)
                        if g1 == 0:
                            empty |= g0 < 0
                        elif g1 > 0:
                            lo = max(lo, -g0 / g1)
                        else:
                            hi = min(hi, -g0 / g1)
                    if empty or lo >= hi:
                        continue
                    col = sample_bilinear(tex, np.array(uv_of(h0 + 0.5 * (lo + hi) * h1))).astype(np.float64)
                    ref[py, px] += _kappa(lo, hi) * col / table.spp
    assert ref.max() > 0.3 and (ref == 0).any()
    np.testing.assert_allclose(res.image, ref, atol=2e-5)
    # Without a shading mode the texture colours the image but no shading or fetch work is counted.
    assert res.flat_stats["tex.fetches"] == 0 and res.flat_stats["shade.quad_requests"] == 0


def test_textured_lines_agree_with_point_sampling():
    """Heuristics off, unlimited buffers, a sinusoidal texture as a planar map in world x, y: with a
    period of 48 units (slow across the frame, 1-6 units wide at these depths) 64 lines agree with
    1024 stratified textured points (brute force) as closely as untextured lines do (RMSE 0.003).
    With a period of 3 units (7.5 px on the background, blurred by 3.5 px) they do not: a line inside
    one triangle is shaded at its midpoint, the lens centre, so the lines keep texture detail that the
    blur removes ([Tzeng 2012] §5's limitation of midpoint shading; docs/shading.md)."""
    cam = sim.Camera(width=W, height=16, focus_distance=5.0, coc_px=6.0, fov_y_deg=30.0)
    base = _layered_scene()
    yy, xx = np.mgrid[0:16, 0:16] / 16.0
    tex = np.stack([0.5 + 0.4 * np.sin(2 * np.pi * xx), 0.5 + 0.4 * np.cos(2 * np.pi * yy),
                    np.full_like(xx, 0.8)], axis=-1).astype(np.float32)
    untextured = sim.render(base, cam, sim.SampleTable.lines(n_lines=64, seed=1), _lines_config(), timing=False)
    rmse = {}
    for period in (48.0, 3.0):
        uvs = (base.positions[..., :2] / period + 0.5).astype(np.float32)
        scene = Scene.from_arrays(base.positions, colors=base.colors, uvs=uvs, texture=tex)
        lines = sim.render(scene, cam, sim.SampleTable.lines(n_lines=64, seed=1),
                           _lines_config().replace(texture_count=1), timing=False)
        points = sim.render(scene, cam, sim.SampleTable.stratified(spp=1024, seed=5, time=False),
                            sim.PipelineConfig(algorithm="bruteforce", threads=1, texture_count=1), timing=False)
        diff = lines.image - points.image
        rmse[period] = float(np.sqrt((diff ** 2).mean()))
        if period == 48.0:
            assert np.abs(diff.mean()) < 2e-3
            assert np.abs(lines.image - untextured.image).max() > 0.1  # the texture did colour the image
    assert rmse[48.0] < 0.01
    assert rmse[3.0] > 0.05  # the midpoint's bias on texture detail at the scale of the blur


@pytest.mark.parametrize("texels, levels", [(4, 1), (256, 2)])
def test_segment_texture_fetches_go_through_the_shading_model(texels, levels):
    """shading: per_sample: every shaded segment (offered and not occluded) is one live shader lane;
    every lane, helpers included, fetches a 2x2 footprint per mip level (trilinear: two levels when
    the triangle's level of detail lies between them); the cache sees one access per distinct line
    of a footprint; the timing records carry the quads, fetches and misses. The modes change the
    counts, never the image; the tile clip and the thread count change neither."""
    cam = sim.Camera(width=32, height=24, focus_distance=5.0, coc_px=20.0, fov_y_deg=30.0)
    _, _, _, scene = _textured_square(texels=texels)
    table = sim.SampleTable.lines(n_lines=8, seed=3)
    cfg = sim.PipelineConfig(algorithm="lines", threads=1, texture_count=1, shading="per_sample")
    r = sim.render(scene, cam, table, cfg, keep_timing_records=True)
    s, recs = r.flat_stats, r.timing_records
    assert s["shade.lanes_live"] == s["lines.segments"] - s["lines.rejected_occluded"] > 0
    assert s["shade.invocations"] == 4 * s["shade.quad_requests"] == s["shade.lanes_live"] + s["shade.lanes_helper"]
    assert s["tex.fetches"] == 4 * levels * s["shade.invocations"]
    assert s["tex.fetches"] / 4 <= s["tex.cache.accesses"] <= s["tex.fetches"]
    assert s["tex.cache.hits"] + s["tex.cache.misses"] == s["tex.cache.accesses"]
    assert s["tex.cache.misses"] >= 1
    assert recs["quads"].sum() == s["shade.quad_requests"]
    assert recs["texel_fetches"].sum() == s["tex.fetches"]
    assert recs["tex_misses"].sum() == s["tex.cache.misses"]
    visit = sim.render(scene, cam, table, cfg, hardware=sim.HardwareConfig(timing={"granularity": "visit"}),
                       keep_timing_records=True)
    assert visit.timing_records["tex_misses"].sum() == s["tex.cache.misses"]
    assert visit.timing_records["texel_fetches"].sum() == s["tex.fetches"]
    none = sim.render(scene, cam, table, cfg.replace(shading="none"), timing=False)
    assert np.array_equal(none.image, r.image)
    for mode in ("msaa", "cache"):
        m = sim.render(scene, cam, table, cfg.replace(shading=mode), timing=False)
        assert np.array_equal(m.image, r.image)
        assert 0 < m.flat_stats["shade.lanes_live"] < s["shade.lanes_live"]
    clip = sim.render(scene, cam, table, cfg.replace(threads=2, lines={**cfg.lines, "tile_clip": True}), timing=False)
    assert np.array_equal(clip.image, r.image)
    for k in ("shade.quad_requests", "shade.lanes_live", "tex.fetches", "tex.cache.accesses", "tex.cache.misses"):
        assert clip.flat_stats[k] == s[k], k


# ---- the tile clip on sub-pixel triangles: what it drops is float32 slivers of the line test ----------

# Seven ceiling triangles of modern_hall (world space, default camera pose), 0.005-0.01 units across at
# view depth ~14: at CoC 50 px they are ~0.07 px wide, and the float32 line test's interval ends carry
# errors of ~1e-6..1e-5 in the line parameter (cancellation in e_0 and in the slopes).
_TINY = np.array([
    [[-5.666111851751825, 3.957722652117028, -13.927814346589525], [-5.658331453028531, 3.957722651892046, -13.923009236454034], [-5.658896069442316, 3.9572936518447706, -13.921999541715204]],
    [[-5.561584071151593, 3.9577226517591932, -13.920171801976785], [-5.561080170713249, 3.9572936517104282, -13.919130296531288], [-5.56956885572266, 3.957293651538991, -13.915468765465686]],
    [[-5.561584071151593, 3.9577226517591932, -13.920171801976785], [-5.56956885572266, 3.957293651538991, -13.915468765465686], [-5.56998009613181, 3.957722651589647, -13.916550658153419]],
    [[-5.56998009613181, 3.957722651589647, -13.916550658153419], [-5.56956885572266, 3.957293651538991, -13.915468765465686], [-5.5783429177964585, 3.957293651402804, -13.912560099047163]],
    [[-5.56998009613181, 3.957722651589647, -13.916550658153419], [-5.5783429177964585, 3.957293651402804, -13.912560099047163], [-5.578658943298755, 3.957722651454889, -13.913672506152718]],
    [[-5.73955589480047, 3.9639746549925516, -13.989229330900141], [-5.741261819628672, 3.963974655537028, -14.000858186997466], [-5.741040582743953, 3.9632046555380867, -14.000880798112206]],
    [[-5.511016870596178, 3.964006657889444, -14.051100751716492], [-5.514567479643722, 3.9648976582756217, -14.059348712403807], [-5.514567479643722, 3.9640066582756224, -14.059348712445523]],
])


def _exact_line_length(cam, tri, pts):
    """float64 length of the part of each line inside the triangle (0: none): the edge functions are
    the triple products det(V_j - L, V_k - L, Q - L) of the ray from lens point L through the focus-plane
    point Q (experiments/reference/raycaster.py's camera model), affine in the line parameter p."""
    from experiments.reference import raycaster as rc

    V = rc.world_to_view(cam, tri)
    ends = []
    for sign in (-1.0, 1.0):
        p = pts.copy()
        p[..., 2:4] *= sign
        org, d = rc.sample_rays(cam, p)
        q = org + d
        ends.append(np.stack([np.einsum("...i,...i->...", np.cross(V[(i + 1) % 3] - org, V[(i + 2) % 3] - org), q - org)
                              for i in range(3)], axis=-1))
    f0, f1 = (ends[0] + ends[1]) / 2, (ends[1] - ends[0]) / 2
    best = np.zeros(f0.shape[:-1])
    for sign in (1.0, -1.0):
        a, b = sign * f0, sign * f1
        with np.errstate(divide="ignore", invalid="ignore"):
            r = -a / b
        lo = np.maximum(np.max(np.where(b > 0, r, -1.0), axis=-1), -1.0)
        hi = np.minimum(np.min(np.where(b < 0, r, 1.0), axis=-1), 1.0)
        ok = ~np.any((b == 0) & (a <= 0), axis=-1) & (hi > lo)
        best = np.maximum(best, np.where(ok, hi - lo, 0.0))
    return best


def test_tile_clip_drops_only_rounding_slivers():
    """The bound the clipped path keeps on sub-pixel triangles (docs/op_costs.md): it skips a line only
    when the line cannot meet the exact lens region, so every segment it drops is one the float32 line
    test made up: a line whose exact (float64) coverage is empty at that pixel, of weight κ < 1e-4.
    One line per render (the same line in every pixel), each triangle alone, heuristics off: a pixel
    is the κ of its line's segment."""
    cam = sim.Camera(width=128, height=72, fov_y_deg=42.99566141876367, focus_distance=6.539783842510974,
                     coc_px=50.0)
    off = {"buffer_size": 0, "min_weight": 0.0, "occlusion": False, "merge": False}
    plain = sim.PipelineConfig(algorithm="lines", threads=1, tile_size=2, lines={**sim.PipelineConfig().lines, **off})
    clipped = plain.replace(lines={**plain.lines, "tile_clip": True})
    yy, xx = np.mgrid[0:72, 0:128]
    dropped = kept_exact = 0
    for seed in range(6):
        table = sim.SampleTable.lines(n_lines=1, wheel=1, period=1, seed=seed)
        line = table.samples("disk")[0, 0, 0].astype(np.float64)
        pts = np.stack([xx + line[0], yy + line[1], np.full(xx.shape, line[2]), np.full(xx.shape, line[3]),
                        np.zeros(xx.shape)], axis=-1)
        for tri in _TINY:
            one = Scene.from_arrays(tri[None])
            a = sim.render(one, cam, table, plain, timing=False).image[..., 0]
            b = sim.render(one, cam, table, clipped, timing=False).image[..., 0]
            diff = a != b
            if not diff.any():
                continue
            exact = _exact_line_length(cam, tri, pts)
            assert np.all(b[diff] == 0.0)           # whole segments dropped, nothing added
            assert np.all(exact[diff] == 0.0)       # ... only where the exact line misses the triangle
            assert a[diff].max() < 1e-4             # ... and they are slivers
            dropped += int(diff.sum())
            kept_exact += int(((exact > 0) & (b > 0)).sum())
    assert dropped > 0 and kept_exact > 0

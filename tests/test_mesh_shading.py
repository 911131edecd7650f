"""The default shading of a mesh without colours (models/shading.py): Lambert under a headlight, per
vertex, at load. Checked against the closed form on a plane, shown to read the shape (the bunny's
colours vary) and switchable off, and to move no operation count."""
from __future__ import annotations

import numpy as np
import pytest

import models
import sim
from models import shading

pytestmark = pytest.mark.smoke


def test_headlight_matches_the_closed_form_on_a_plane():
    """A square at z = -3 facing the camera at the origin: each vertex's colour is
    base * (a + (1 - a) * 3 / |p|), the cosine between the plane's normal and the way to the eye."""
    p = np.array([[[-1, -1, -3], [1, -1, -3], [1, 1, -3]], [[-1, -1, -3], [1, 1, -3], [-1, 1, -3]]], float)
    p[..., 0] *= 2.0  # not symmetric in x and y
    scene = models.Scene.from_arrays(p, colors=(0.5, 0.6, 0.7))
    shaded = shading.apply(scene)
    cos = 3.0 / np.linalg.norm(p, axis=-1)
    want = np.array([0.5, 0.6, 0.7]) * (shading.AMBIENT + (1 - shading.AMBIENT) * cos)[..., None]
    np.testing.assert_allclose(shaded.colors, want, rtol=1e-6)
    # a light elsewhere: the same formula with the light's direction
    eye = np.array([4.0, 0.0, 0.0])
    lit = shading.headlight(scene, eye=eye)
    cos = np.abs((eye - p)[..., 2]) / np.linalg.norm(eye - p, axis=-1)
    np.testing.assert_allclose(lit.colors[..., 0], 0.5 * (shading.AMBIENT + (1 - shading.AMBIENT) * cos), rtol=1e-6)


def _smooth_normals_by_loops(p: np.ndarray) -> np.ndarray:
    """vertex_normals' definition, vertex by vertex: the area-weighted face normals of every triangle with
    a corner at the same position, summed in corner order, made unit (+z for no area, the face's own
    normal where the sum cancels)."""
    face = [np.cross(t[1] - t[0], t[2] - t[0]) for t in p]
    corners = [(i, k) for i in range(len(p)) for k in range(3)]
    out = np.zeros_like(p)
    for i, k in corners:
        acc = np.zeros(3)
        for j, m in corners:
            if np.array_equal(p[j, m], p[i, k]):
                acc = acc + face[j]
        n = acc if np.linalg.norm(acc) > 0 else face[i]
        out[i, k] = n / np.linalg.norm(n) if np.linalg.norm(n) > 0 else (0.0, 0.0, 1.0)
    return out


def test_vertex_normals_sum_the_faces_at_each_shared_position():
    """Smooth normals against a loop over every pair of corners: a closed octahedron (every position
    shared by four faces), a fan whose faces differ in area, a degenerate triangle and a pair of
    faces whose normals cancel; positions up to 10^4 on an axis and as small as 10^-4."""
    rng = np.random.default_rng(5)
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    octa = [[v[a], v[c], v[e]] for a in (0, 1) for c in (2, 3) for e in (4, 5)]
    octa = [t if np.dot(np.cross(t[1] - t[0], t[2] - t[0]), t[0] + t[1] + t[2]) > 0 else t[::-1] for t in octa]
    fan = [[np.zeros(3), [np.cos(a), np.sin(a), rng.uniform(0, 1)], [np.cos(b), np.sin(b), rng.uniform(0, 1)]]
           for a, b in zip(np.linspace(0, 5, 6), np.linspace(1, 6, 6))]
    flat = [[[5, 5, 5], [6, 5, 5], [7, 5, 5]]]  # no area
    cancel = [[[9, 0, 0], [10, 0, 0], [9, 1, 0]], [[9, 0, 0], [9, 1, 0], [10, 0, 0]]]
    for scale in (1.0, 1e4, 1e-4):
        p = np.asarray(octa + fan + flat + cancel, float) * scale + rng.uniform(-3, 3, size=3).round() * scale
        np.testing.assert_allclose(shading.vertex_normals(p), _smooth_normals_by_loops(p), rtol=1e-12, atol=1e-12)


def test_the_bunny_reads_as_a_shape_and_flat_switches_it_off():
    shaded = models.named("bunny", width=64, height=64)
    flat = models.named("bunny", width=64, height=64, shading="flat")
    assert np.ptp(flat.colors.reshape(-1, 3), axis=0).max() == 0
    assert np.ptp(shaded.colors.reshape(-1, 3)[:, 0]) > 0.3  # lit and unlit sides differ
    with pytest.raises(models.SceneError, match="shading: expected one of headlight, flat, got 'phong'"):
        models.named("bunny", width=64, height=64, shading="phong")


def test_coloured_and_textured_meshes_keep_their_colours(tmp_path):
    (tmp_path / "tri.obj").write_text("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n")
    coloured = models.load(tmp_path / "tri.obj")
    assert np.ptp(coloured.colors.reshape(-1, 3), axis=0).max() > 0.5  # the file's vertex colours
    (tmp_path / "plain.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nf 1 2 3\nf 2 4 3\n")
    plain = models.load(tmp_path / "plain.obj")
    kept = models.load(tmp_path / "plain.obj", shading="flat")
    assert np.ptp(kept.colors.reshape(-1, 3), axis=0).max() == 0
    assert not np.array_equal(plain.colors, kept.colors)
    spot = models.named("spot", width=64, height=64)  # textured: untouched
    assert not shading.is_uncoloured(spot)


def test_shading_moves_no_operation_count():
    scene = models.named("teapot", width=48, height=48)
    flat = models.named("teapot", width=48, height=48, shading="flat")
    camera = sim.Camera.for_scene(scene, width=48, height=48, coc_px=4)
    table, config = sim.SampleTable.stratified(spp=4, seed=1), sim.PipelineConfig(algorithm="tile")
    a = sim.render(scene, camera, table, config).flat_stats
    b = sim.render(flat, camera, table, config).flat_stats
    counts = [k for k in a if not k.startswith("time.") and not isinstance(a[k], str)]
    assert len(counts) > 100 and all(a[k] == b[k] or (a[k] != a[k] and b[k] != b[k]) for k in counts)

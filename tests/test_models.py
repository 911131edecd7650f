"""models/: Scene validation, mesh loading, named and procedural scenes, YAML scene files."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

import models
from models import Scene, SceneError
from tests.test_sources import OUTSIDE

pytestmark = pytest.mark.smoke

REPO = Path(__file__).resolve().parent.parent
ASSETS = REPO / "models" / "assets"


def tri_areas(positions: np.ndarray) -> np.ndarray:
    """3D area of each triangle (N, 3, 3)."""
    return 0.5 * np.linalg.norm(np.cross(positions[:, 1] - positions[:, 0], positions[:, 2] - positions[:, 0]), axis=1)


def pinhole_pixels(positions: np.ndarray, width: int, height: int, fov_y_deg: float) -> np.ndarray:
    """Independent pinhole projection (camera at origin looking down -z) to pixels, row 0 at top."""
    f = 1.0 / np.tan(np.radians(fov_y_deg) / 2.0)
    w = -positions[..., 2]
    x_ndc = positions[..., 0] * f / (width / height) / w
    y_ndc = positions[..., 1] * f / w
    return np.stack([(x_ndc + 1) * width / 2, (1 - y_ndc) * height / 2], axis=-1)


def random_triangles(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    pos = rng.uniform(-1, 1, (n, 3, 3))
    pos[..., 2] -= 4.0
    return pos


# ------------------------------------------------------------------------------------------------
# Scene.from_arrays validation


def _nan_at_17() -> np.ndarray:
    pos = random_triangles(20)
    pos[17, 2] = (np.nan, 0.0, 1.0)
    return pos


BAD_INPUTS = {
    "positions_shape": (dict(positions=np.zeros((5, 3))), r"^positions: expected shape \(N, 3, 3\), got \(5, 3\)$"),
    "positions_dtype": (dict(positions=np.full((2, 3, 3), "a")), r"^positions: .*numeric.*<U1"),
    "positions_bool": (dict(positions=np.zeros((2, 3, 3), bool)), r"^positions: .*numeric.*bool"),
    "positions_ragged": (dict(positions=[[[0, 0, 0], [1, 1]]]), r"^positions: "),
    "positions_nan": (
        dict(positions=_nan_at_17()),
        r"^positions: triangle 17 vertex 2 is not finite: \(nan, 0\.0, 1\.0\)$",
    ),
    "positions_t1_inf": (
        dict(positions=random_triangles(3), positions_t1=np.where(np.eye(3, dtype=bool)[None], np.inf, 1.0) * np.ones((3, 3, 3))),
        r"^positions_t1: triangle 0 vertex 0 is not finite",
    ),
    "positions_t1_n": (dict(positions=random_triangles(3), positions_t1=random_triangles(4)), r"^positions_t1: expected shape \(3, 3, 3\), got \(4, 3, 3\)"),
    "colors_n": (dict(positions=random_triangles(3), colors=np.ones((4, 3, 3))), r"^colors: expected shape"),
    "colors_negative": (dict(positions=random_triangles(2), colors=(0.5, -0.1, 0.2)), r"^colors: triangle 0 vertex 0 is negative"),
    "colors_nan": (dict(positions=random_triangles(2), colors=(0.5, np.nan, 0.2)), r"^colors: .*not finite"),
    "uvs_n": (dict(positions=random_triangles(3), uvs=np.zeros((3, 3, 3))), r"^uvs: expected shape \(3, 3, 2\), got \(3, 3, 3\)"),
    "texture_shape": (
        dict(positions=random_triangles(1), uvs=np.zeros((1, 3, 2)), texture=np.zeros((4, 4, 2))),
        r"^texture: expected shape \(H, W, 3\|4\), got \(4, 4, 2\)",
    ),
    "texture_range": (
        dict(positions=random_triangles(1), uvs=np.zeros((1, 3, 2)), texture=np.full((4, 4, 3), 2.0)),
        r"^texture: texel .* not in \[0, 1\]",
    ),
    "texture_needs_uvs": (dict(positions=random_triangles(1), texture=np.zeros((4, 4, 3))), r"^uvs: required"),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_from_arrays_rejects_bad_input(case):
    kwargs, pattern = BAD_INPUTS[case]
    with pytest.raises(SceneError, match=pattern):
        Scene.from_arrays(**kwargs)


def test_from_arrays_converts_and_copies():
    pos = random_triangles(4).astype(np.float32)
    uvs = np.zeros((4, 3, 2))
    tex = np.full((2, 2, 3), 255, np.uint8)
    scene = Scene.from_arrays(pos, colors=np.ones((4, 3)), uvs=uvs, texture=tex)
    assert scene.positions.dtype == np.float64 and scene.positions_t1.dtype == np.float64
    assert scene.colors.dtype == np.float32 and scene.colors.shape == (4, 3, 3)
    assert scene.uvs.dtype == np.float32 and scene.texture_ids.dtype == np.int32
    assert scene.texture.dtype == np.float32 and np.allclose(scene.texture, 1.0)  # sRGB 255 -> 1.0
    assert (scene.texture_ids == 0).all() and scene.is_static
    pos[0, 0, 0] = 99.0
    assert scene.positions[0, 0, 0] != 99.0
    default = Scene.from_arrays(random_triangles(2))
    assert np.allclose(default.colors, 0.8) and default.uvs is None and (default.texture_ids == -1).all()


def test_empty_scene():
    scene = Scene.from_arrays(np.zeros((0, 3, 3)))
    assert scene.n_triangles == 0 and scene.is_static and scene.texture is None
    assert Scene.from_arrays([]).n_triangles == 0
    with pytest.raises(SceneError, match="empty"):
        scene.bounds()


def test_camera_hint_unknown_key():
    with pytest.raises(SceneError, match="camera_hint: unknown key.*'zoom'"):
        Scene.from_arrays(random_triangles(1), camera_hint={"zoom": 2})


def test_transform_motion_concat():
    base = Scene.from_arrays(random_triangles(3), name="a")
    moved = base.with_motion((1.0, 0.0, 0.0))
    assert not moved.is_static and np.allclose(moved.positions_t1 - moved.positions, [1, 0, 0])
    shift = np.eye(4)
    shift[:3, 3] = (0, 2, 0)
    other = np.eye(4)
    other[:3, 3] = (0, 3, 0)
    t = base.transformed(shift, matrix_t1=other)
    assert np.allclose(t.positions - base.positions, [0, 2, 0]) and np.allclose(t.positions_t1 - base.positions, [0, 3, 0])
    with pytest.raises(SceneError, match="matrix: expected an affine"):
        base.transformed(np.ones((4, 4)))
    lo, hi = moved.bounds()
    assert np.allclose(hi, np.maximum(base.positions.reshape(-1, 3).max(0), base.positions.reshape(-1, 3).max(0) + [1, 0, 0]))

    textured = Scene.from_arrays(random_triangles(2), uvs=np.zeros((2, 3, 2)), texture=np.zeros((2, 2, 3)), name="b")
    merged = Scene.concat(textured, base, textured)
    assert merged.n_triangles == 7 and len(merged.textures) == 2
    assert merged.texture_ids.tolist() == [0, 0, -1, -1, -1, 1, 1]
    assert np.array_equal(merged.positions[2:5], base.positions)  # submission order kept
    assert merged.uvs.shape == (7, 3, 2) and merged.name == "b+a+b"
    assert Scene.concat().n_triangles == 0


@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 20),
    st.lists(st.floats(-5, 5), min_size=3, max_size=3),
    st.lists(st.floats(-180, 180), min_size=3, max_size=3),
)
def test_transform_roundtrip(n, translate, angles):
    from models.geometry import compose, rotation_matrix_deg, translation_matrix

    scene = Scene.from_arrays(random_triangles(n, seed=n))
    rotation = rotation_matrix_deg(angles)
    matrix = compose(translation_matrix(translate), rotation)
    inverse = compose(rotation.T, translation_matrix(-np.asarray(translate)))
    back = scene.transformed(matrix).transformed(inverse)
    assert np.allclose(back.positions, scene.positions, atol=1e-9)
    assert back.is_static == scene.is_static


# ------------------------------------------------------------------------------------------------
# Meshes


def test_load_mesh_spot_textured():
    scene = models.load_mesh(ASSETS / "spot" / "spot_triangulated.obj")
    assert scene.n_triangles == 5856 and scene.name == "spot_triangulated"
    assert scene.uvs is not None and scene.uvs.shape == (5856, 3, 2)
    assert scene.texture is not None and scene.texture.shape == (1024, 1024, 3) and scene.texture.dtype == np.float32
    assert 0.0 <= scene.texture.min() and scene.texture.max() <= 1.0
    assert (scene.texture_ids == 0).all()
    colors = scene.colors.reshape(-1, 3)
    assert np.ptp(colors, axis=0).max() > 0.3  # the black patches and the white hide both show
    # the vertex colours are the texture sampled bilinearly at the UVs
    from models.textures import sample_bilinear

    assert np.allclose(scene.colors, sample_bilinear(scene.texture, scene.uvs)[..., :3], atol=1e-3)


def test_load_mesh_bunny_and_colour():
    scene = models.load_mesh(ASSETS / "stanford-bunny" / "stanford-bunny.obj", color=(0.2, 0.4, 0.6), name="b")
    assert scene.n_triangles == 69451 and scene.uvs is None and scene.texture is None and scene.name == "b"
    assert np.allclose(scene.colors, [0.2, 0.4, 0.6])
    assert np.isfinite(scene.positions).all()


def test_load_mesh_missing_and_garbage(tmp_path):
    missing = tmp_path / "nope.obj"
    with pytest.raises(SceneError, match=re.escape(f"mesh: file not found: {missing}")):
        models.load_mesh(missing)
    garbage = tmp_path / "garbage.obj"
    garbage.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(SceneError, match=re.escape(str(garbage))):
        models.load_mesh(garbage)
    bad_ply = tmp_path / "bad.ply"
    bad_ply.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(SceneError, match=re.escape(str(bad_ply))):
        models.load_mesh(bad_ply)
    broken = tmp_path / "broken.obj"
    broken.write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match=re.escape(str(broken))):
        models.load_mesh(broken)
    with pytest.raises(SceneError, match="not a file"):
        models.load_mesh(tmp_path)


def test_load_mesh_ply_and_obj_with_material(tmp_path):
    box = trimesh.creation.box()
    box.export(tmp_path / "box.ply")
    scene = models.load_mesh(tmp_path / "box.ply")
    assert scene.n_triangles == 12 and np.allclose(scene.bounds()[0], -0.5)

    image = np.zeros((4, 4, 3), np.uint8)
    image[:, :2] = (255, 0, 0)  # left half red, right half blue
    image[:, 2:] = (0, 0, 255)
    Image.fromarray(image).save(tmp_path / "tex.png")
    (tmp_path / "quad.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd tex.png\n")
    (tmp_path / "quad.obj").write_text(
        "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "vt 0.2 0.5\nvt 0.8 0.5\nvt 0.8 0.5\nvt 0.2 0.5\nusemtl m\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
    )
    quad = models.load_mesh(tmp_path / "quad.obj")
    assert quad.n_triangles == 2 and quad.texture.shape == (4, 4, 3) and (quad.texture_ids == 0).all()
    left = quad.uvs[..., 0] < 0.5
    assert np.allclose(quad.colors[left], [1, 0, 0]) and np.allclose(quad.colors[~left], [0, 0, 1])


# ------------------------------------------------------------------------------------------------
# Named scenes


@pytest.mark.parametrize("name", models.scene_names())
def test_named_scene_builds(name):
    scene = models.named(name)
    assert isinstance(scene, Scene) and scene.n_triangles > 0 and scene.name == name
    assert np.isfinite(scene.positions).all() and np.isfinite(scene.positions_t1).all()
    assert scene.camera_hint.get("focus_distance", 0) > 0
    assert set(scene.camera_hint) <= {"width", "height", "fov_y_deg", "focus_distance", "eye", "target", "up", "near"}
    # the scene is in front of the default camera (at least partly)
    assert (scene.positions[..., 2] < 0).any()


def test_scene_registry_errors():
    with pytest.raises(SceneError, match=r"unknown scene 'nope'.*bunny.*spot_wall"):
        models.named("nope")
    with pytest.raises(SceneError, match=r"unknown parameter\(s\) sizee"):
        models.named("quad", sizee=2)
    with pytest.raises(SceneError, match="size: expected a positive number"):
        models.named("quad", size=-1)
    assert "spot_wall" in models.scene_names() and models.scene_names() == sorted(models.scene_names())


def test_register_scene_requires_keyword_defaults():
    with pytest.raises(TypeError, match="keyword-only with a default"):

        @models.register_scene("bad_scene_for_test")
        def bad(size):  # noqa: ARG001
            """Bad."""


def test_mixed_sizes_area_distribution():
    scene = models.named("mixed_sizes")
    hint = scene.camera_hint
    assert scene.n_triangles == 20000 and hint["width"] == hint["height"] == 512
    assert (scene.positions[..., 2] < 0).all()
    depth = -scene.positions[..., 2]
    assert depth.min() >= 2.0 - 1e-9 and depth.max() <= 10.0 + 1e-9
    px = pinhole_pixels(scene.positions, hint["width"], hint["height"], hint["fov_y_deg"])
    e1, e2 = px[:, 1] - px[:, 0], px[:, 2] - px[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert area.min() >= 1.0 * (1 - 1e-6) and area.max() <= 1e5 * (1 + 1e-6)
    assert area.min() < 1.1 and area.max() > 0.9e5
    # log-uniform: each decade holds about a fifth of the triangles
    per_decade = np.histogram(np.log10(area), bins=5, range=(0, 5))[0] / area.size
    assert np.allclose(per_decade, 0.2, atol=0.02), per_decade
    # reasonably fat: no interior angle below 15 degrees
    angles = []
    for k in range(3):
        a, b = px[:, (k + 1) % 3] - px[:, k], px[:, (k + 2) % 3] - px[:, k]
        cos = np.einsum("ij,ij->i", a, b) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
        angles.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    assert np.min(angles) > 15.0, np.min(angles)
    centroid = px.mean(axis=1)
    assert ((centroid >= 0) & (centroid <= 512)).all()


def test_mixed_sizes_deterministic():
    a = models.named("mixed_sizes", n=500, seed=7)
    b = models.named("mixed_sizes", n=500, seed=7)
    c = models.named("mixed_sizes", n=500, seed=8)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.colors, b.colors)
    assert not np.array_equal(a.positions, c.positions)


@pytest.mark.hardcases
def test_behind_camera_has_vertex_behind_and_is_visible():
    scene = models.named("behind_camera")
    assert (scene.positions[..., 2] > 0).any()
    straddling = (scene.positions[..., 2] > 0).any(axis=1) & (scene.positions[..., 2] < 0).any(axis=1)
    assert straddling.all()
    hint = scene.camera_hint
    front = scene.positions[scene.positions[..., 2] < 0]
    px = pinhole_pixels(front, hint["width"], hint["height"], hint["fov_y_deg"])
    inside = (px[:, 0] >= 0) & (px[:, 0] < hint["width"]) & (px[:, 1] >= 0) & (px[:, 1] < hint["height"])
    assert inside.any()


@pytest.mark.hardcases
def test_degenerate_has_zero_area_and_edge_on():
    scene = models.named("degenerate")
    area = tri_areas(scene.positions)
    assert (area == 0).sum() >= 3 and (area > 0.5).any()
    plane_through_origin = np.abs(np.linalg.det(scene.positions)) <= 1e-12
    edge_on = plane_through_origin & (area > 0.1)
    assert edge_on.sum() >= 1
    # through the pinhole the edge-on triangles project to a line (zero screen area)
    hint = scene.camera_hint
    px = pinhole_pixels(scene.positions[edge_on], hint["width"], hint["height"], hint["fov_y_deg"])
    e1, e2 = px[:, 1] - px[:, 0], px[:, 2] - px[:, 0]
    assert np.allclose(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0], 0.0, atol=1e-6)
    # and their vertices are at different depths, so an off-centre lens point sees an area
    assert (np.ptp(scene.positions[edge_on][..., 2], axis=1) > 0.5).all()


@pytest.mark.hardcases
def test_focus_crossing_spans_focus_plane():
    scene = models.named("focus_crossing")
    focus = scene.camera_hint["focus_distance"]
    depth = -scene.positions[..., 2]
    assert ((depth.min(axis=1) < focus) & (depth.max(axis=1) > focus)).all()
    near_count = (depth < focus).sum(axis=1)
    assert sorted(near_count.tolist()) == [1, 2]


def test_motion_scenes_move():
    assert not models.named("moving_quads").is_static
    assert not models.named("spot_wall").is_static
    assert not models.named("quad", translation_t1=(0.5, 0, 0)).is_static
    assert models.named("quad").is_static
    speeds = np.linalg.norm(models.named("moving_quads").positions_t1 - models.named("moving_quads").positions, axis=-1)
    assert len(np.unique(np.round(speeds, 6))) >= 4  # different speeds (and a static backdrop)


def test_spot_wall_default_scene():
    scene = models.named("spot_wall")
    assert len(scene.textures) == 1 and scene.texture.shape == (1024, 1024, 3)
    focus = scene.camera_hint["focus_distance"]
    textured = scene.texture_ids == 0
    cow_depth = -scene.positions[textured][..., 2]
    assert cow_depth.min() < focus < cow_depth.max()  # focus on the cow
    assert (-scene.positions[~textured][..., 2]).max() > 2 * focus  # the wall is well behind it
    hint = scene.camera_hint
    px = pinhole_pixels(scene.positions[textured], hint["width"], hint["height"], hint["fov_y_deg"])
    extent = np.ptp(px.reshape(-1, 2), axis=0) / [hint["width"], hint["height"]]
    assert 0.3 < extent.max() < 0.8  # the cow fills roughly half the frame


def test_modern_hall():
    scene = models.named("modern_hall")
    assert scene.n_triangles == 30911 and len(scene.textures) == 3
    # rotating into view space leaves 3 of the 2,432 zero-area triangles with ~1e-16 area
    assert (tri_areas(scene.positions) < 1e-12).sum() == 2432
    assert scene.uvs is not None and (scene.texture_ids >= 0).any() and (scene.texture_ids == -1).any()
    world = models.named("modern_hall", camera_space=False)
    assert (tri_areas(world.positions) == 0).sum() == 2432
    hint = world.camera_hint
    # the world-space version with eye/target/up looks at the same picture as the view-space version
    eye, target, up = (np.array(hint[k]) for k in ("eye", "target", "up"))
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    rotation = np.stack([right, np.cross(back, right), back])
    view = (world.positions - eye) @ rotation.T
    assert np.allclose(view, scene.positions, atol=1e-4)
    assert abs(hint["fov_y_deg"] - 43.0) < 0.1 and (hint["width"], hint["height"]) == (640, 360)


# ------------------------------------------------------------------------------------------------
# models.load and YAML scene files


@pytest.mark.parametrize("stem", ["bunny", "spot", "teapot", "modern_hall", "spot_wall"])
def test_yaml_scene_files_load(stem):
    scene = models.load(f"configs/scenes/{stem}.yaml")
    assert scene.n_triangles > 0 and scene.name == stem and scene.camera_hint["focus_distance"] > 0
    assert (scene.positions[..., 2] < 0).any()


def test_load_dispatch():
    assert models.load("quad", size=2.0).n_triangles == 2
    assert models.load(ASSETS / "teapot" / "teapot.obj").n_triangles == 6320
    with pytest.raises(SceneError, match="overrides"):
        models.load("configs/scenes/spot.yaml", distance=3)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return path


def test_yaml_composition(tmp_path):
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box().export(tmp_path / "meshes" / "box.obj")
    path = _write(
        tmp_path,
        "name: combo\n"
        "objects:\n"
        "  - mesh: meshes/box.obj\n"
        "    transform: {scale: [1, 2, 1], rotate_deg: [0, 90, 0], translate: [0, 0, -5]}\n"
        "    motion: {translate: [0.5, 0, 0]}\n"
        "    color: [0.1, 0.2, 0.3]\n"
        "  - scene: quad\n"
        "    params: {size: 2, depth: 8}\n"
        "camera_hint: {focus_distance: 5, width: 64}\n",
    )
    scene = models.load(path)
    assert scene.n_triangles == 14 and scene.name == "combo" and not scene.is_static
    box = scene.positions[:12]
    assert np.allclose(box.reshape(-1, 3).min(0), [-0.5, -1, -5.5]) and np.allclose(box.reshape(-1, 3).max(0), [0.5, 1, -4.5])
    assert np.allclose(scene.colors[:12], [0.1, 0.2, 0.3])
    assert scene.camera_hint["focus_distance"] == 5 and scene.camera_hint["width"] == 64
    assert scene.camera_hint["fov_y_deg"] == 45.0  # kept from the quad's own hint


@pytest.mark.parametrize(
    "text, pattern",
    [
        ("objects: []\nzoom: 2\n", r"unknown key 'zoom' in \(top level\)"),
        ("objects:\n  - scene: quad\n    colour: [1, 0, 0]\n", r"unknown key 'colour' in objects\[0\]"),
        ("objects:\n  - scene: quad\n    transform: {rotate: [0, 1, 0]}\n", r"unknown key 'rotate' in objects\[0\]\.transform"),
        ("objects:\n  - scene: quad\n    motion: {rotate_deg: [0, 1, 0]}\n", r"unknown key 'rotate_deg' in objects\[0\]\.motion"),
        ("objects: []\ncamera_hint: {fov: 40}\n", r"unknown key 'fov' in camera_hint"),
        ("objects:\n  - scene: quad\n    params: {sizee: 2}\n", r"objects\[0\]: scene 'quad': unknown parameter\(s\) sizee"),
        ("objects:\n  - scene: quad\n    mesh: a.obj\n", r"exactly one of 'mesh' or 'scene'"),
        ("objects:\n  - mesh: missing.obj\n", r"objects\[0\]\.mesh: file not found: missing\.obj"),
        ("objects:\n  - scene: nope\n", r"unknown scene 'nope'"),
        ("objects: []\nobjects: []\n", r"duplicate key 'objects'"),
        ("- just a list\n", r"expected a mapping"),
        ("objects:\n  - scene: quad\n    color: [1, -1, 0]\n", r"objects\[0\]\.color"),
    ],
)
def test_yaml_errors_name_key_and_file(tmp_path, text, pattern):
    path = _write(tmp_path, text)
    with pytest.raises(SceneError) as info:
        models.load(path)
    assert str(path) in str(info.value)
    assert re.search(pattern, str(info.value)), str(info.value)


# ------------------------------------------------------------------------------------------------
# Assets


def test_assets_are_self_contained():
    for name in ("spot/spot_texture.png", "stanford-bunny/LICENSE-STANFORD.txt", "teapot/SOURCE.txt",
                 "modern-hall/LICENSE.txt", "modern-hall/scene.xml", "common-3d-test-models-README.md"):
        assert (ASSETS / name).is_file(), name
    readme = (ASSETS / "README.md").read_text()
    assert "non-commercial" in readme and "CC BY 3.0" in readme
    for path in list((REPO / "models").glob("*.py")) + list((REPO / "configs" / "scenes").glob("*.yaml")):
        text = path.read_text()
        assert not OUTSIDE.search(text), path  # no path into the shared folder beside the project

"""Scene importers (models.load on Mitsuba XML, glTF/GLB and bare meshes), scene framing, the empty-frame
warning and the resolution of relative scene paths. Every file is written by the test; positions are
checked against transforms computed here (scipy rotations), placement in the picture against a pinhole
projection written here and Mitsuba's documented camera frame (+x is the image's left)."""
from __future__ import annotations

import base64
import json
import struct
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

import models
import sim
from models import SceneError, SceneImportWarning
from models.scene import srgb_to_linear

pytestmark = pytest.mark.smoke

TRI = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"


def _apply(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def _pixel(point, hint: dict) -> np.ndarray:
    """Pinhole projection of a world point through eye/target/up (pixel units, row 0 at the top)."""
    eye, target, up = (np.asarray(hint[k], dtype=float) for k in ("eye", "target", "up"))
    f = (target - eye) / np.linalg.norm(target - eye)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = np.asarray(point, dtype=float) - eye
    x, y, z = d @ r, d @ u, d @ f
    w, h = hint["width"], hint["height"]
    t = np.tan(np.radians(hint["fov_y_deg"]) / 2)
    return np.array([w / 2 * (1 + x / (z * t * w / h)), h / 2 * (1 - y / (z * t))])


def _render(scene, **camera):
    hint = {**scene.camera_hint, **camera}
    cam = sim.Camera(**hint)
    return sim.render(scene, cam, sim.SampleTable.stratified(spp=4, seed=1), sim.PipelineConfig(algorithm="tile"))


def _covered_centroid(image: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(image.sum(axis=2) > 0)
    assert xs.size, "nothing covered"
    return np.array([xs.mean() + 0.5, ys.mean() + 0.5])


# ------------------------------------------------------------------------------------------------
# Mitsuba XML

def _mitsuba(tmp_path: Path, body: str, sensor: str | None = None, version: str = "3.0.0") -> Path:
    (tmp_path / "tri.obj").write_text(OBJ)
    if sensor is None:
        sensor = ('<sensor type="perspective"><float name="fov" value="60"/><string name="fov_axis" value="x"/>'
                  '<transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>'
                  '<film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/></film>'
                  '</sensor>')
    path = tmp_path / "scene.xml"
    path.write_text(f'<?xml version="1.0"?>\n<scene version="{version}">{sensor}{body}</scene>')
    return path


def test_mitsuba_transforms_in_document_order(tmp_path):
    body = ('<shape type="obj"><string name="filename" value="tri.obj"/><transform name="toWorld">'
            '<scale x="2" y="3" z="1"/><rotate y="1" angle="30"/><translate x="1" y="-2" z="0.5"/>'
            '<matrix value="1 0 0 0.25  0 1 0 0  0 0 1 -1  0 0 0 1"/></transform></shape>')
    scene = models.load(_mitsuba(tmp_path, body, version="0.5.0"))
    expected = np.diag([2.0, 3.0, 1.0]) @ TRI.T
    expected = Rotation.from_rotvec([0, np.radians(30), 0]).as_matrix() @ expected
    expected = expected.T + [1.0, -2.0, 0.5] + [0.25, 0.0, -1.0]
    assert scene.n_triangles == 1
    np.testing.assert_allclose(scene.positions[0], expected, atol=1e-6)


def test_mitsuba3_defaults_values_and_primitives(tmp_path):
    body = ('<default name="s" value="2"/>'
            '<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>'
            '<shape type="rectangle"><transform name="to_world"><scale value="$s"/>'
            '<translate value="0 0 -3"/></transform><ref id="red"/></shape>'
            '<shape type="cube"><bsdf type="twosided"><bsdf type="principled">'
            '<rgb name="base_color" value="0.1, 0.2, 0.3"/></bsdf></bsdf></shape>'
            '<shape type="sphere"><point name="center" x="5" y="0" z="0"/><float name="radius" value="0.5"/></shape>')
    scene = models.load(_mitsuba(tmp_path, body))
    rect, cube, sphere = scene.positions[:2], scene.positions[2:14], scene.positions[14:]
    assert rect.reshape(-1, 3)[:, :2].min() == -2 and rect.reshape(-1, 3)[:, :2].max() == 2
    assert np.all(rect[..., 2] == -3)
    assert cube.min() == -1 and cube.max() == 1 and len(cube) == 12
    np.testing.assert_allclose(np.linalg.norm(sphere - [5, 0, 0], axis=-1), 0.5, atol=1e-9)
    np.testing.assert_allclose(scene.colors[0], [[0.8, 0.1, 0.1]] * 3, atol=1e-6)
    np.testing.assert_allclose(scene.colors[2], [[0.1, 0.2, 0.3]] * 3, atol=1e-6)
    # the sphere has no bsdf: Mitsuba's default diffuse 0.5
    np.testing.assert_allclose(scene.colors[-1], [[0.5, 0.5, 0.5]] * 3, atol=1e-6)


def test_mitsuba_bitmap_texture(tmp_path):
    pixels = np.zeros((4, 4, 3), np.uint8)
    pixels[:, :, 1] = 200
    Image.fromarray(pixels).save(tmp_path / "green.png")
    body = ('<shape type="obj"><string name="filename" value="tri.obj"/><bsdf type="diffuse">'
            '<texture name="reflectance" type="bitmap"><string name="filename" value="green.png"/></texture>'
            '</bsdf></shape>')
    scene = models.load(_mitsuba(tmp_path, body))
    assert len(scene.textures) == 1 and scene.textures[0].shape[:2] == (4, 4)
    assert (scene.texture_ids == 0).all()
    np.testing.assert_allclose(scene.colors[0, 0], [0, srgb_to_linear(np.float32(200 / 255)), 0], atol=1e-5)


def test_mitsuba_unsupported_elements_are_listed(tmp_path):
    body = ('<emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>'
            '<shape type="serialized"><string name="filename" value="a.serialized"/></shape>'
            '<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>'
            '<shape type="obj"><string name="filename" value="tri.obj"/><bsdf type="dielectric"/></shape>'
            '<medium type="homogeneous" id="fog"/>')
    with pytest.warns(SceneImportWarning) as record:
        scene = models.load(_mitsuba(tmp_path, body))
    text = str(record[0].message)
    for what in ("envmap", "'serialized'", "emitter <shape type='rectangle'>", "dielectric", "<medium"):
        assert what in text, (what, text)
    assert scene.n_triangles == 1
    with pytest.warns(SceneImportWarning):
        assert models.load(tmp_path / "scene.xml", include_emitters=True).n_triangles == 3


def test_mitsuba_sensor_hint_sees_what_the_sensor_sees(tmp_path):
    """A small quad placed on Mitsuba's image left (+x of the sensor frame, up x forward) and above the
    axis appears in the upper left of our render, where the pinhole projection puts it."""
    origin, target, up = np.array([1.0, 2.0, 6.0]), np.array([0.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    forward = (target - origin) / np.linalg.norm(target - origin)
    left = np.cross(up, forward)
    left /= np.linalg.norm(left)
    true_up = np.cross(forward, left)
    centre = origin + 4 * forward + 0.6 * left + 0.3 * true_up
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = 0.1 * left, 0.1 * true_up, forward, centre
    sensor = ('<sensor type="thinlens"><float name="fov" value="50"/><float name="focus_distance" value="4"/>'
              '<transform name="to_world"><lookat origin="1, 2, 6" target="0, 0, 0" up="0, 1, 0"/></transform>'
              '<film type="hdrfilm"><integer name="width" value="96"/><integer name="height" value="64"/></film>'
              '</sensor>')
    body = ('<shape type="rectangle"><transform name="to_world"><matrix value="'
            + " ".join(f"{v:.12g}" for v in matrix.ravel()) + '"/></transform></shape>')
    scene = models.load(_mitsuba(tmp_path, body, sensor=sensor))
    hint = scene.camera_hint
    assert (hint["width"], hint["height"], hint["focus_distance"]) == (96, 64, 4.0)
    expected_fov_y = 2 * np.degrees(np.arctan(np.tan(np.radians(25)) * 64 / 96))  # fov is horizontal
    assert abs(hint["fov_y_deg"] - expected_fov_y) < 1e-9
    centroid = _covered_centroid(_render(scene).image)
    assert centroid[0] < 48 and centroid[1] < 32  # upper left
    np.testing.assert_allclose(centroid, _pixel(centre, hint), atol=1.0)


def test_mitsuba_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text("<scene><shape type='obj'>")
    with pytest.raises(SceneError, match="bad.xml"):
        models.load(bad)
    with pytest.raises(SceneError, match="no shapes"):
        models.load(_mitsuba(tmp_path, '<emitter type="constant"/>'))


def test_modern_hall_uses_the_importer():
    with pytest.warns(SceneImportWarning, match="area light"):
        world = models.load("models/assets/modern-hall/scene.xml")
    named = models.named("modern_hall", camera_space=False)
    np.testing.assert_array_equal(world.positions, named.positions)
    for key in ("eye", "target", "up", "fov_y_deg"):
        np.testing.assert_allclose(world.camera_hint[key], named.camera_hint[key])


# ------------------------------------------------------------------------------------------------
# glTF / GLB

def _png_bytes(pixels: np.ndarray) -> bytes:
    import io

    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, format="PNG")
    return buffer.getvalue()


def _gltf_doc(texture_uri: str | None = None) -> tuple[dict, bytes]:
    positions = TRI.astype(np.float32).tobytes()
    uvs = np.array([[0, 0], [1, 0], [0, 1]], np.float32).tobytes()
    indices = np.array([0, 1, 2, 0], np.uint16).tobytes()  # padded to 4 bytes
    blob = positions + uvs + indices
    material = {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]}, "normalTexture": {"index": 0}}
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"translation": [1, 2, 3], "rotation": [0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)], "children": [1]},
            {"scale": [2, 2, 2], "mesh": 0},
            {"camera": 0, "translation": [0.5, 0.5, 10]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1, "aspectRatio": 2.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [material],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 24},
                        {"buffer": 0, "byteOffset": 60, "byteLength": 6}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point"}]}},
    }
    if texture_uri is not None:
        material["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        doc["textures"] = [{"source": 0}]
        doc["images"] = [{"uri": texture_uri}]
    return doc, blob


def _expected_gltf_triangle() -> np.ndarray:
    rot = Rotation.from_quat([0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)]).as_matrix()  # x, y, z, w
    return (rot @ (2 * TRI).T).T + [1, 2, 3]


def test_gltf_node_transforms_texture_camera(tmp_path):
    pixels = np.zeros((4, 4, 3), np.uint8)
    pixels[:, :2] = (255, 0, 0)
    pixels[:, 2:] = (0, 0, 255)
    (tmp_path / "tex.png").write_bytes(_png_bytes(pixels))
    doc, blob = _gltf_doc("tex.png")
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    path = tmp_path / "scene.gltf"
    path.write_text(json.dumps(doc))
    with pytest.warns(SceneImportWarning) as record:
        scene = models.load(path)
    text = str(record[0].message)
    assert "normalTexture" in text and "KHR_lights_punctual" in text, text
    np.testing.assert_allclose(scene.positions[0], _expected_gltf_triangle(), atol=1e-6)
    assert len(scene.textures) == 1 and scene.textures[0].shape[:2] == (4, 4) and (scene.texture_ids == 0).all()
    hint = scene.camera_hint
    assert hint["eye"] == (0.5, 0.5, 10.0) and hint["target"] == (0.5, 0.5, 9.0) and hint["up"] == (0.0, 1.0, 0.0)
    assert abs(hint["fov_y_deg"] - np.degrees(0.5)) < 1e-9 and hint["near"] == 0.1
    assert hint["width"] == 2 * hint["height"]


def test_glb_same_geometry_and_framing_without_camera(tmp_path):
    doc, blob = _gltf_doc()
    del doc["cameras"], doc["nodes"][2]["camera"]
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    glb = (struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(blob))
           + struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob)
    path = tmp_path / "scene.glb"
    path.write_bytes(glb)
    with pytest.warns(SceneImportWarning):
        scene = models.load(path)
    np.testing.assert_allclose(scene.positions[0], _expected_gltf_triangle(), atol=1e-6)
    hint = scene.camera_hint
    for corner in scene.positions[0]:  # framed: every vertex inside the picture
        px = _pixel(corner, {**hint, "width": 64, "height": 64})
        assert (0 < px).all() and (px < 64).all(), px


# ------------------------------------------------------------------------------------------------
# bare meshes, empty frames, paths

def _torus(path: Path, radius=1.0, tube=0.3) -> int:
    import trimesh

    mesh = trimesh.creation.torus(major_radius=radius, minor_radius=tube)
    mesh.export(path)
    return len(mesh.faces)


def test_bare_mesh_is_framed(tmp_path):
    n = _torus(tmp_path / "torus.obj")
    scene = models.load(tmp_path / "torus.obj")
    assert scene.n_triangles == n
    # the default camera (origin, looking down -z) sits inside the torus's hole: it tests nothing
    with pytest.warns(sim.EmptyFrameWarning, match="tested no samples"):
        empty = sim.render(scene, sim.Camera(width=32, height=32), sim.SampleTable.stratified(spp=4),
                           sim.PipelineConfig(algorithm="tile"))
    assert empty.flat_stats["raster.samples_tested"] == 0
    result = _render(scene, width=32, height=32)
    assert result.flat_stats["raster.samples_tested"] > 0
    lo, hi = scene.bounds()
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    px = np.array([_pixel(c, {**scene.camera_hint, "width": 32, "height": 32}) for c in corners])
    assert (px > 0).all() and (px < 32).all()  # the whole bounding box is in the picture
    # a given pose wins over the framing
    posed = models.load_mesh(tmp_path / "torus.obj")
    assert "eye" not in posed.camera_hint


def test_empty_frame_warning_names_the_cull_causes():
    scene = models.Scene.from_arrays(np.array([[[0, 0, 1.0], [1, 0, 1.0], [0, 1, 1.0]],    # behind the camera
                                               [[50, 0, -1.0], [51, 0, -1.0], [50, 1, -1.0]]]))  # off screen
    with pytest.warns(sim.EmptyFrameWarning) as record:
        sim.render(scene, sim.Camera(width=16, height=16), sim.SampleTable.stratified(spp=1),
                   sim.PipelineConfig())
    text = str(record[0].message)
    assert "1 behind the near plane" in text and "1 off screen" in text, text


def test_cli_renders_imported_scenes_relative_to_the_config(tmp_path):
    (tmp_path / "scenes").mkdir()
    xml = _mitsuba(tmp_path / "scenes", '<shape type="obj"><string name="filename" value="tri.obj"/></shape>')
    (tmp_path / "configs").mkdir()
    config = tmp_path / "configs" / "c.yaml"
    config.write_text("scene: {path: ../scenes/scene.xml}\nsamples: {spp: 4}\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = subprocess.run([sys.executable, "-m", "experiments.cli", "render", str(config)], capture_output=True,
                         text=True, cwd=elsewhere)
    assert out.returncode == 0 and "samples tested" in out.stdout, out.stderr
    assert xml.exists()
    config.write_text("scene: {path: missing.xml}\n")
    out = subprocess.run([sys.executable, "-m", "experiments.cli", "render", str(config)], capture_output=True,
                         text=True, cwd=elsewhere)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    for place in (tmp_path / "configs" / "missing.xml", elsewhere / "missing.xml"):
        assert str(place) in out.stderr, out.stderr


def test_scene_path_in_sweep_and_extends_resolve_against_their_file(tmp_path, monkeypatch):
    from experiments.config import load_config

    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "tri.obj").write_text(OBJ)
    (tmp_path / "base").mkdir()
    (tmp_path / "base" / "b.yaml").write_text("scene: {path: ../meshes/tri.obj}\n")
    (tmp_path / "a.yaml").write_text("extends: base/b.yaml\nsweep:\n  scene.path: [meshes/tri.obj]\n")
    monkeypatch.chdir(tmp_path / "base")
    config = load_config(tmp_path / "a.yaml")
    assert Path(config.scene.path).resolve() == (tmp_path / "meshes" / "tri.obj").resolve()
    assert Path(config.sweep["scene.path"][0]).resolve() == (tmp_path / "meshes" / "tri.obj").resolve()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert models.load(config.scene.path).n_triangles == 1


def test_scene_file_unknown_key_suggests_the_known_one(tmp_path):
    (tmp_path / "tri.obj").write_text(OBJ)
    (tmp_path / "s.yaml").write_text("objects:\n  - mesh: tri.obj\n    transfrom: {scale: 2}\n")
    with pytest.raises(SceneError, match=r"unknown key 'transfrom' in objects\[0\]; did you mean 'transform'"):
        models.load(tmp_path / "s.yaml")


def test_mitsuba_includes_emitter_refs_and_spectra(tmp_path):
    """The layout of Mitsuba 3's own scene files: <include> fragments, an area light referenced by id,
    spectral reflectances (wavelength:value pairs -> band means)."""
    (tmp_path / "frag").mkdir()
    (tmp_path / "frag" / "bsdfs.xml").write_text(
        '<scene version="3.0.0"><bsdf type="diffuse" id="grey"><spectrum name="reflectance" value="0.25"/></bsdf>'
        '<bsdf type="diffuse" id="reddish"><spectrum name="reflectance" '
        'value="400:0.1, 500:0.1, 550:0.3, 600:0.8, 700:0.8"/></bsdf></scene>')
    body = ('<include filename="frag/bsdfs.xml"/><emitter type="area" id="lamp"><rgb name="radiance" value="5"/>'
            '</emitter><shape type="obj"><string name="filename" value="tri.obj"/><ref id="grey"/>'
            '<ref id="lamp"/></shape><shape type="obj"><string name="filename" value="tri.obj"/>'
            '<ref id="grey"/></shape><shape type="rectangle"><ref id="reddish"/></shape>')
    with pytest.warns(SceneImportWarning) as record:
        scene = models.load(_mitsuba(tmp_path, body))
    text = str(record[0].message)
    assert "area light" in text and "band means" in text and "<emitter" not in text, text
    assert scene.n_triangles == 3  # the lamp's triangle is left out
    np.testing.assert_allclose(scene.colors[0, 0], [0.25, 0.25, 0.25])
    red = scene.colors[1, 0]
    np.testing.assert_allclose(red[0], 0.8) and np.testing.assert_allclose(red[2], 0.1)
    assert 0.1 < red[1] < 0.8

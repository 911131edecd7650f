"""The Scene data type: world-space triangles at shutter open and close, colours, UVs and textures.

Contract (other code depends on these names): a Scene is plain numpy arrays, validated once when it is
built, so that the engine can take them as they are. The engine's default camera sits at the origin
looking down -z with +y up, so scenes meant for it live at negative z.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

__all__ = ["Scene", "SceneError", "CAMERA_HINT_KEYS", "DEFAULT_COLOR"]

DEFAULT_COLOR = (0.8, 0.8, 0.8)

# The keys a camera_hint may hold; they mirror sim.Camera's keyword arguments.
CAMERA_HINT_KEYS = frozenset(
    {"width", "height", "fov_y_deg", "focus_distance", "eye", "target", "up", "near"}
)


from sim.errors import SceneError  # noqa: E402 - bad scene input: the message names the field (or file) and value


def _as_numeric_array(field_name: str, value: Any) -> np.ndarray:
    try:
        array = np.asarray(value)
    except (ValueError, TypeError) as exc:  # ragged nested lists and the like
        raise SceneError(f"{field_name}: cannot convert to an array: {exc}") from None
    if array.dtype.kind not in "iuf":
        raise SceneError(
            f"{field_name}: expected a numeric (integer or float) array, got dtype {array.dtype}"
        )
    return array


def _check_shape(field_name: str, array: np.ndarray, expected: tuple, expected_text: str) -> None:
    """expected holds ints or None (any size); expected_text is the shape as written in the message."""
    ok = array.ndim == len(expected) and all(
        want is None or have == want for have, want in zip(array.shape, expected)
    )
    if not ok:
        raise SceneError(f"{field_name}: expected shape {expected_text}, got {tuple(array.shape)}")


def _check_finite_per_vertex(field_name: str, array: np.ndarray) -> None:
    """array is (N, 3, C); names the first triangle and vertex that is not finite."""
    finite = np.isfinite(array).all(axis=-1)
    if not finite.all():
        tri, vert = np.argwhere(~finite)[0]
        values = ", ".join(repr(float(x)) for x in array[tri, vert])
        raise SceneError(f"{field_name}: triangle {tri} vertex {vert} is not finite: ({values})")


def _positions(field_name: str, value: Any, n: int | None) -> np.ndarray:
    array = _as_numeric_array(field_name, value)
    if array.shape == (0,) and n in (None, 0):  # [] is an empty scene
        array = array.reshape(0, 3, 3)
    _check_shape(field_name, array, (n, 3, 3), "(N, 3, 3)" if n is None else f"({n}, 3, 3)")
    array = np.array(array, dtype=np.float64)  # always a copy
    _check_finite_per_vertex(field_name, array)
    return array


def _colors(value: Any, n: int) -> np.ndarray:
    """(N, 3, 3) per vertex, (N, 3) per triangle or (3,) for all; finite and >= 0 (linear RGB)."""
    if value is None:
        return np.full((n, 3, 3), DEFAULT_COLOR, dtype=np.float32)
    array = _as_numeric_array("colors", value).astype(np.float64)
    if array.shape == (3,):
        array = np.broadcast_to(array, (n, 3, 3))
    elif array.shape == (n, 3):
        array = np.broadcast_to(array[:, None, :], (n, 3, 3))
    elif array.shape != (n, 3, 3):
        raise SceneError(
            f"colors: expected shape ({n}, 3, 3) per vertex, ({n}, 3) per triangle or (3,), "
            f"got {tuple(array.shape)}"
        )
    _check_finite_per_vertex("colors", array)
    if (array < 0).any():
        tri, vert, _ = np.argwhere(array < 0)[0]
        values = ", ".join(repr(float(x)) for x in array[tri, vert])
        raise SceneError(f"colors: triangle {tri} vertex {vert} is negative: ({values})")
    return np.array(array, dtype=np.float32)


def _uvs(value: Any, n: int) -> np.ndarray | None:
    if value is None:
        return None
    array = _as_numeric_array("uvs", value)
    _check_shape("uvs", array, (n, 3, 2), f"({n}, 3, 2)")
    array = np.array(array, dtype=np.float32)
    _check_finite_per_vertex("uvs", array)
    return array


def srgb_to_linear(encoded: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB decode of values in [0, 1]."""
    encoded = np.asarray(encoded, dtype=np.float32)
    return np.where(
        encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4
    ).astype(np.float32)


def as_linear_texture(field_name: str, value: Any) -> np.ndarray:
    """(H, W, 3|4). Float input is taken as linear in [0, 1]; uint8/uint16 input as sRGB-encoded
    8/16-bit and decoded (alpha stays linear)."""
    array = _as_numeric_array(field_name, value)
    if array.ndim != 3 or array.shape[2] not in (3, 4) or array.shape[0] == 0 or array.shape[1] == 0:
        raise SceneError(f"{field_name}: expected shape (H, W, 3|4), got {tuple(array.shape)}")
    if array.dtype.kind in "iu":
        if array.dtype not in (np.uint8, np.uint16):
            raise SceneError(
                f"{field_name}: integer textures must be uint8 or uint16 (sRGB-encoded), got {array.dtype}"
            )
        scaled = array.astype(np.float32) / np.float32(np.iinfo(array.dtype).max)
        linear = scaled.copy()
        linear[..., :3] = srgb_to_linear(scaled[..., :3])
        return linear
    linear = np.array(array, dtype=np.float32)
    bad = ~np.isfinite(linear) | (linear < 0) | (linear > 1)
    if bad.any():
        row, col, ch = np.argwhere(bad)[0]
        raise SceneError(
            f"{field_name}: texel (row {row}, column {col}, channel {ch}) = {float(linear[row, col, ch])!r} "
            "is not in [0, 1] (textures are linear values in [0, 1])"
        )
    return linear


def _texture_ids(value: Any, n: int, n_textures: int) -> np.ndarray:
    array = _as_numeric_array("texture_ids", value)
    _check_shape("texture_ids", array, (n,), f"({n},)")
    if array.dtype.kind == "f":
        if not np.array_equal(array, np.round(array)):
            raise SceneError("texture_ids: expected integers")
    array = np.array(array, dtype=np.int32)
    bad = (array < -1) | (array >= n_textures)
    if bad.any():
        tri = int(np.argmax(bad))
        raise SceneError(
            f"texture_ids: triangle {tri} has id {int(array[tri])}, expected -1 (untextured) "
            f"or 0..{n_textures - 1} ({n_textures} textures)"
        )
    return array


def _alpha(value: Any, n: int) -> np.ndarray:
    """(N,) opacity per triangle (or one number for all), finite and in [0, 1]."""
    array = _as_numeric_array("alpha", value).astype(np.float64)
    if array.ndim == 0:
        array = np.full(n, float(array))
    _check_shape("alpha", array, (n,), f"({n},)")
    bad = ~np.isfinite(array) | (array < 0.0) | (array > 1.0)
    if bad.any():
        i = int(np.argmax(bad))
        raise SceneError(f"alpha: triangle {i} has opacity {float(array[i])!r}, expected a number in [0, 1]")
    return np.array(array, dtype=np.float32)


def _camera_hint(value: Any) -> dict:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise SceneError(f"camera_hint: expected a dict, got {type(value).__name__}")
    unknown = sorted(set(value) - CAMERA_HINT_KEYS)
    if unknown:
        raise SceneError(
            f"camera_hint: unknown key(s) {unknown}; known keys: {sorted(CAMERA_HINT_KEYS)}"
        )
    hint = {}
    for key, item in value.items():
        if key in ("eye", "target", "up"):
            vec = _as_numeric_array(f"camera_hint.{key}", item)
            if vec.shape != (3,) or not np.isfinite(vec).all():
                raise SceneError(f"camera_hint.{key}: expected 3 finite numbers, got {item!r}")
            hint[key] = tuple(float(x) for x in vec)
        elif key in ("width", "height"):
            if isinstance(item, bool) or not isinstance(item, (int, np.integer)) or item <= 0:
                raise SceneError(f"camera_hint.{key}: expected a positive integer, got {item!r}")
            hint[key] = int(item)
        else:
            if isinstance(item, bool) or not isinstance(item, (int, float, np.integer, np.floating)):
                raise SceneError(f"camera_hint.{key}: expected a number, got {item!r}")
            number = float(item)
            upper = 180.0 if key == "fov_y_deg" else np.inf
            if not (0.0 < number < upper):
                raise SceneError(f"camera_hint.{key}: expected a value in (0, {upper}), got {item!r}")
            hint[key] = number
    return hint


def _matrix(field_name: str, value: Any) -> np.ndarray:
    array = _as_numeric_array(field_name, value)
    if array.shape != (4, 4):
        raise SceneError(f"{field_name}: expected shape (4, 4), got {tuple(array.shape)}")
    array = np.array(array, dtype=np.float64)
    if not np.isfinite(array).all():
        raise SceneError(f"{field_name}: not finite: {array.tolist()}")
    if not np.array_equal(array[3], [0.0, 0.0, 0.0, 1.0]):
        raise SceneError(
            f"{field_name}: expected an affine matrix (last row 0 0 0 1), got last row {array[3].tolist()}"
        )
    return array


def _apply(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ matrix[:3, :3].T + matrix[:3, 3]


@dataclass(eq=False)
class Scene:
    """Triangles in world space. Build with Scene.from_arrays (validates and copies); the dataclass
    constructor validates too, but does not copy arrays that already have the right dtype."""

    positions: np.ndarray  # (N, 3, 3) float64, world-space vertices at shutter open (t=0)
    positions_t1: np.ndarray  # (N, 3, 3) float64 at shutter close (t=1); equal to positions if static
    colors: np.ndarray  # (N, 3, 3) float32 linear RGB per vertex
    uvs: np.ndarray | None  # (N, 3, 2) float32 texture coordinates, or None
    textures: list[np.ndarray]  # (H, W, 3|4) float32 linear images in [0, 1] (sRGB-decoded)
    texture_ids: np.ndarray  # (N,) int32 index into textures, -1 = untextured
    name: str = "scene"
    camera_hint: dict = field(default_factory=dict)  # keys a subset of CAMERA_HINT_KEYS
    alpha: np.ndarray | None = None  # (N,) float32 opacity in [0, 1] (stochastic transparency), or None

    def __post_init__(self) -> None:
        positions = _as_numeric_array("positions", self.positions)
        _check_shape("positions", positions, (None, 3, 3), "(N, 3, 3)")
        n = positions.shape[0]
        self.positions = np.asarray(positions, dtype=np.float64)
        _check_finite_per_vertex("positions", self.positions)
        t1 = _as_numeric_array("positions_t1", self.positions_t1)
        _check_shape("positions_t1", t1, (n, 3, 3), f"({n}, 3, 3)")
        self.positions_t1 = np.asarray(t1, dtype=np.float64)
        _check_finite_per_vertex("positions_t1", self.positions_t1)
        colors = _as_numeric_array("colors", self.colors)
        _check_shape("colors", colors, (n, 3, 3), f"({n}, 3, 3)")
        self.colors = np.asarray(colors, dtype=np.float32)
        if self.uvs is not None:
            uvs = _as_numeric_array("uvs", self.uvs)
            _check_shape("uvs", uvs, (n, 3, 2), f"({n}, 3, 2)")
            self.uvs = np.asarray(uvs, dtype=np.float32)
        if not isinstance(self.textures, (list, tuple)):
            raise SceneError(f"textures: expected a list of images, got {type(self.textures).__name__}")
        self.textures = [
            t if isinstance(t, np.ndarray) and t.dtype == np.float32 and t.ndim == 3 and t.shape[2] in (3, 4)
            else as_linear_texture(f"textures[{i}]", t)
            for i, t in enumerate(self.textures)
        ]
        self.texture_ids = _texture_ids(self.texture_ids, n, len(self.textures))
        if self.uvs is None and (self.texture_ids >= 0).any():
            raise SceneError("uvs: required when a triangle has a texture (texture_ids >= 0)")
        if not isinstance(self.name, str):
            raise SceneError(f"name: expected a string, got {self.name!r}")
        self.camera_hint = _camera_hint(self.camera_hint)
        if self.alpha is not None:
            self.alpha = _alpha(self.alpha, n)

    # ----------------------------------------------------------------------------------------------
    @staticmethod
    def from_arrays(
        positions: Any,
        colors: Any = None,
        positions_t1: Any = None,
        uvs: Any = None,
        texture: Any = None,
        name: str = "scene",
        *,
        textures: Sequence[Any] | None = None,
        texture_ids: Any = None,
        camera_hint: dict | None = None,
    ) -> "Scene":
        """Validate and copy. positions (N, 3, 3); colors (N, 3, 3), (N, 3) or (3,), default 0.8 grey;
        positions_t1 (N, 3, 3), default static; uvs (N, 3, 2); texture one (H, W, 3|4) image used by
        every triangle (needs uvs). For several textures pass textures=[...] with texture_ids (N,)."""
        pos = _positions("positions", positions, None)
        n = pos.shape[0]
        pos_t1 = pos.copy() if positions_t1 is None else _positions("positions_t1", positions_t1, n)
        cols = _colors(colors, n)
        uv = _uvs(uvs, n)
        if texture is not None and textures is not None:
            raise SceneError("texture: give either texture (one image) or textures (a list), not both")
        if texture is not None:
            if uv is None:
                raise SceneError("uvs: required when texture is given")
            tex_list = [as_linear_texture("texture", texture)]
            if texture_ids is None:
                texture_ids = np.zeros(n, dtype=np.int32)
        elif textures is not None:
            tex_list = [as_linear_texture(f"textures[{i}]", t) for i, t in enumerate(textures)]
        else:
            tex_list = []
        if texture_ids is None:
            texture_ids = np.full(n, -1, dtype=np.int32)
        return Scene(
            positions=pos,
            positions_t1=pos_t1,
            colors=cols,
            uvs=uv,
            textures=tex_list,
            texture_ids=np.array(texture_ids, copy=True),
            name=name,
            camera_hint=dict(camera_hint or {}),
        )

    # ----------------------------------------------------------------------------------------------
    @property
    def n_triangles(self) -> int:
        return int(self.positions.shape[0])

    @property
    def is_static(self) -> bool:
        """True when positions_t1 equals positions exactly (no motion blur)."""
        return bool(np.array_equal(self.positions, self.positions_t1))

    @property
    def texture(self) -> np.ndarray | None:
        """The first texture, or None."""
        return self.textures[0] if self.textures else None

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(min xyz, max xyz) over the vertices at t=0 and t=1."""
        if self.n_triangles == 0:
            raise SceneError(f"bounds: scene {self.name!r} is empty")
        both = np.concatenate([self.positions.reshape(-1, 3), self.positions_t1.reshape(-1, 3)])
        return both.min(axis=0), both.max(axis=0)

    def _replace(self, **changes: Any) -> "Scene":
        fields = dict(
            positions=self.positions,
            positions_t1=self.positions_t1,
            colors=self.colors.copy(),
            uvs=None if self.uvs is None else self.uvs.copy(),
            textures=list(self.textures),  # images are shared, never mutated
            texture_ids=self.texture_ids.copy(),
            name=self.name,
            camera_hint=dict(self.camera_hint),
            alpha=None if self.alpha is None else self.alpha.copy(),
        )
        fields.update(changes)
        return Scene(**fields)

    def transformed(self, matrix: Any = None, *, matrix_t1: Any = None) -> "Scene":
        """Apply a 4x4 affine transform to the whole scene (as one object). matrix acts on the t=0
        vertices; matrix_t1, if given, acts on the t=1 vertices instead of matrix, which makes the
        object move (e.g. a different translation at shutter close). None means the identity."""
        m0 = np.eye(4) if matrix is None else _matrix("matrix", matrix)
        m1 = m0 if matrix_t1 is None else _matrix("matrix_t1", matrix_t1)
        return self._replace(
            positions=_apply(m0, self.positions), positions_t1=_apply(m1, self.positions_t1)
        )

    def with_motion(self, translation_t1: Any = None, matrix_t1: Any = None) -> "Scene":
        """Add linear motion of the whole scene over the shutter, t=0 -> t=1: the t=1 vertices are
        transformed by matrix_t1 (if given) and then shifted by translation_t1 (dx, dy, dz).
        The t=0 vertices stay put, so motion composes with any motion already present."""
        t1 = self.positions_t1
        if matrix_t1 is not None:
            t1 = _apply(_matrix("matrix_t1", matrix_t1), t1)
        if translation_t1 is not None:
            shift = _as_numeric_array("translation_t1", translation_t1)
            if shift.shape != (3,) or not np.isfinite(shift).all():
                raise SceneError(f"translation_t1: expected 3 finite numbers, got {translation_t1!r}")
            t1 = t1 + shift.astype(np.float64)
        return self._replace(positions_t1=np.array(t1, dtype=np.float64))

    def subdivided(self, levels: int = 1) -> "Scene":
        """Each level splits every triangle into four at its edge midpoints (positions at both shutter
        ends, colours, uvs and opacity carried over, the texture kept): 4^levels times the triangles,
        the same surface. A denser workload of the same scene, for benchmarks."""
        if isinstance(levels, bool) or not isinstance(levels, int) or not 0 <= levels <= 4:
            raise SceneError(f"subdivide: expected an integer in 0..4, got {levels!r}")
        out = self
        for _ in range(levels):
            out = out._replace(**_split4(out))
        return out

    def with_camera_hint(self, **keys: Any) -> "Scene":
        """A copy whose camera_hint has these keys set (the other keys are kept)."""
        return self._replace(camera_hint={**self.camera_hint, **keys})

    def with_alpha(self, alpha: Any) -> "Scene":
        """Same geometry with opacity alpha per triangle ((N,) or one number; None: opaque): a render
        then keeps each covered sample with probability alpha (stochastic transparency, [McGuire 2010])."""
        return self._replace(alpha=None if alpha is None else _alpha(alpha, self.n_triangles))

    def with_color(self, color: Any) -> "Scene":
        """Same geometry with every vertex colour set to color (r, g, b), linear."""
        return self._replace(colors=_colors(color, self.n_triangles))

    @staticmethod
    def concat(*scenes: "Scene", name: str | None = None) -> "Scene":
        """Merge scenes in submission order (scene 0's triangles first). Texture lists are appended
        and texture ids remapped. uvs become zeros for scenes without them. The name defaults to the
        names joined with '+', and the camera_hint is the first non-empty one."""
        for i, scene in enumerate(scenes):
            if not isinstance(scene, Scene):
                raise SceneError(f"concat: argument {i} is a {type(scene).__name__}, not a Scene")
        if not scenes:
            return Scene.from_arrays(np.zeros((0, 3, 3)), name=name or "scene")
        any_uvs = any(s.uvs is not None for s in scenes)
        textures: list[np.ndarray] = []
        ids = []
        for scene in scenes:
            offset = len(textures)
            textures.extend(scene.textures)
            ids.append(np.where(scene.texture_ids >= 0, scene.texture_ids + offset, -1))
        uvs = None
        if any_uvs:
            uvs = np.concatenate(
                [s.uvs if s.uvs is not None else np.zeros((s.n_triangles, 3, 2), np.float32) for s in scenes]
            )
        hint = next((dict(s.camera_hint) for s in scenes if s.camera_hint), {})
        alpha = None
        if any(s.alpha is not None for s in scenes):  # opaque where a scene has no alpha
            alpha = np.concatenate([s.alpha if s.alpha is not None else np.ones(s.n_triangles, np.float32)
                                    for s in scenes])
        return Scene(
            positions=np.concatenate([s.positions for s in scenes]),
            positions_t1=np.concatenate([s.positions_t1 for s in scenes]),
            colors=np.concatenate([s.colors for s in scenes]),
            uvs=uvs,
            textures=textures,
            texture_ids=np.concatenate(ids).astype(np.int32),
            name=name or "+".join(s.name for s in scenes),
            camera_hint=hint,
            alpha=alpha,
        )

    def __repr__(self) -> str:
        motion = "static" if self.is_static else "moving"
        return (
            f"Scene(name={self.name!r}, n_triangles={self.n_triangles}, {motion}, "
            f"textures={len(self.textures)}, camera_hint={self.camera_hint})"
        )


def _split4(scene: "Scene") -> dict:
    """Scene fields with every triangle (a, b, c) split into (a, ab, ca), (ab, b, bc), (ca, bc, c) and
    (ab, bc, ca), per-vertex attributes at the midpoints, per-triangle ones repeated."""

    def split(v: np.ndarray) -> np.ndarray:  # (N, 3, k) -> (4N, 3, k), same dtype
        a, b, c = v[:, 0], v[:, 1], v[:, 2]
        ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
        tris = np.stack([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))], axis=1)
        return tris.reshape(-1, 3, v.shape[2]).astype(v.dtype, copy=False)

    return {"positions": split(scene.positions), "positions_t1": split(scene.positions_t1),
            "colors": split(scene.colors), "uvs": None if scene.uvs is None else split(scene.uvs),
            "texture_ids": np.repeat(scene.texture_ids, 4),
            "alpha": None if scene.alpha is None else np.repeat(scene.alpha, 4)}

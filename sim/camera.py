"""The thin-lens, shuttered camera and the world -> clip -> engine transforms.

Conventions (docs/conventions.md):

* View space is right-handed; by default the camera is at the origin looking down -z with +y up
  (``eye``/``target``/``up`` place it elsewhere). Clip space: ``x_c = s_x x_v``, ``y_c = s_y y_v``,
  ``w = -z_v`` (view depth, > 0 in front), with ``s_y = 1 / tan(fov_y / 2)`` and
  ``s_x = s_y / aspect``. Depth stored per sample is ``z = 1 - near / w`` (an infinite far plane).
* Pixel ``(X, Y)`` covers ``[X, X+1) x [Y, Y+1)``; row 0 is the top of the picture.
* Lens ``(u, v)`` in the aperture shape inside ``[-1, 1]^2``: ``u`` along the camera's +x, ``v``
  along +y; the lens sits at ``w = 0`` and the focus plane at ``w = F`` (``focus_distance``).
  Depth of field is the clip-space shear ``x' = x + u k_x (w - F)``, ``y' = y + v k_y (w - F)``
  with ``k_x = R s_x / F`` (``R`` the aperture radius in world units).
* The user-facing blur is ``coc_px``: the CoC radius at infinity in pixels, ``K = k_x W / 2``
  (= ``k_y H / 2``): a point at depth ``w`` is blurred over a disc of radius ``K |1 - F / w|`` px.
* ``shift`` (default (0, 0)) moves the principal point by (shift_x, shift_y) in normalised device
  coordinates: ``x_c = s_x x_v + shift_x w`` (an off-centre viewport, e.g. a reflection map that
  tightly encloses a glossy surface, [Nilsson 2012] §6). The lens shear is unchanged (it is linear in w - F).
* Time: vertices move linearly in world space from ``t = 0`` to ``t = 1``. The shutter interval
  ``[open, close]`` is applied by moving the scene's endpoints to ``open`` and ``close`` before
  projection, so the sample table's ``t`` in ``[0, 1)`` spans the open shutter.

The engine receives *pixel-homogeneous* vertices ``(X_h, Y_h, W)`` with ``X_h = (x_c + w) W_px / 2``
and ``Y_h = (w - y_c) H_px / 2``, so that pixel coordinates are ``X_h / W`` and the shear becomes
``X_h' = X_h + u K (W - F)`` and ``Y_h' = Y_h - v K (W - F)``.
"""
from __future__ import annotations

import math

import numpy as np

from . import lens as _lens
from .errors import ConfigError, check_float, check_int, suggest_keywords

_OWNER = "Camera"


def _vec3(field, value):
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(f"{_OWNER}.{field}: expected 3 numbers, got {value!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ConfigError(f"{_OWNER}.{field}: expected 3 finite numbers, got {value!r}")
    return a


@suggest_keywords
class Camera:
    """A thin-lens camera with a shutter. Give either ``coc_px`` or ``aperture_radius`` (or
    neither: a pinhole). ``lens`` is the aperture shape: "disk" (default), "square", "hexagon"."""

    def __init__(
        self,
        width: int = 256,
        height: int = 256,
        fov_y_deg: float = 45.0,
        focus_distance: float = 5.0,
        coc_px: float | None = None,
        aperture_radius: float | None = None,
        lens: str = "disk",
        eye=None,
        target=None,
        up=None,
        near: float = 0.05,
        shutter=(0.0, 1.0),
        shift=(0.0, 0.0),
    ):
        self.width = check_int(_OWNER, "width", width, 1, 16384)
        self.height = check_int(_OWNER, "height", height, 1, 16384)
        self.fov_y_deg = check_float(_OWNER, "fov_y_deg", fov_y_deg, lo=0.0, hi=180.0, lo_open=True, hi_open=True)
        self.focus_distance = check_float(_OWNER, "focus_distance", focus_distance, lo=0.0, lo_open=True)
        self.near = check_float(_OWNER, "near", near, lo=0.0, lo_open=True)
        if lens not in _lens.LENS_SHAPES:
            raise ConfigError(f"{_OWNER}.lens: unknown shape {lens!r} (known: {', '.join(_lens.LENS_SHAPES)})")
        self.lens = lens
        if coc_px is not None and aperture_radius is not None:
            raise ConfigError(
                f"{_OWNER}: give coc_px or aperture_radius, not both (got coc_px={coc_px!r}, "
                f"aperture_radius={aperture_radius!r})"
            )
        if aperture_radius is not None:
            r = check_float(_OWNER, "aperture_radius", aperture_radius, lo=0.0)
            self._coc_px = r * self._s_x * self.width / (2.0 * self.focus_distance)
        else:
            self._coc_px = 0.0 if coc_px is None else check_float(_OWNER, "coc_px", coc_px, lo=0.0, hi=1e6)
        try:
            s_open, s_close = shutter
        except (TypeError, ValueError):
            raise ConfigError(f"{_OWNER}.shutter: expected (open, close), got {shutter!r}") from None
        s_open = check_float(_OWNER, "shutter", s_open, lo=0.0, hi=1.0)
        s_close = check_float(_OWNER, "shutter", s_close, lo=0.0, hi=1.0)
        if s_close < s_open:
            raise ConfigError(f"{_OWNER}.shutter: expected open <= close, got {shutter!r}")
        self.shutter = (s_open, s_close)
        try:
            sh_x, sh_y = shift
        except (TypeError, ValueError):
            raise ConfigError(f"{_OWNER}.shift: expected (x, y), got {shift!r}") from None
        self.shift = (check_float(_OWNER, "shift", sh_x, lo=-1e6, hi=1e6), check_float(_OWNER, "shift", sh_y, lo=-1e6, hi=1e6))
        self._pose_given = eye is not None or target is not None or up is not None
        self.eye = np.zeros(3) if eye is None else _vec3("eye", eye)
        self.target = np.array([0.0, 0.0, -1.0]) + self.eye if target is None else _vec3("target", target)
        self.up = np.array([0.0, 1.0, 0.0]) if up is None else _vec3("up", up)
        forward = self.target - self.eye
        if np.linalg.norm(forward) == 0:
            raise ConfigError(f"{_OWNER}.target: must differ from eye, got {self.target.tolist()}")
        if np.linalg.norm(np.cross(forward, self.up)) <= 1e-12 * np.linalg.norm(forward) * max(np.linalg.norm(self.up), 1e-300):
            raise ConfigError(f"{_OWNER}.up: must not be parallel to target - eye, got {self.up.tolist()}")

    @classmethod
    def for_scene(cls, scene, **overrides) -> "Camera":
        """The camera a scene asks for, with ``overrides``: the one obvious way to set up a scene's
        camera, and the one the command line and configs use (``rast5d render`` gives the same camera
        for the same keys). ``scene`` is a models.Scene (its ``camera_hint``: pose, field of view,
        focus, size) or a hint dict; every keyword of Camera may override it, e.g.
        ``Camera.for_scene(scene, width=256, height=256, coc_px=10)``. A ``coc_px`` given replaces an
        ``aperture_radius`` in the hint and the other way round; None values are ignored."""
        hint = scene if isinstance(scene, dict) else getattr(scene, "camera_hint", None)
        if hint is not None and not isinstance(hint, dict):
            raise ConfigError(f"{_OWNER}.for_scene: expected a scene with a camera_hint dict or a dict, "
                              f"got {type(hint).__name__}")
        args = dict(hint or {})
        given = {k: v for k, v in overrides.items() if v is not None}
        if "coc_px" in given:  # the blur given replaces any blur in the hint
            args.pop("aperture_radius", None)
        if "aperture_radius" in given:
            args.pop("coc_px", None)
        args.update(given)
        if args.get("shutter") is not None:
            args["shutter"] = tuple(args["shutter"])
        return cls(**args)

    # ---- projection constants ------------------------------------------------------------
    @property
    def aspect(self) -> float:
        return self.width / self.height

    @property
    def _s_y(self) -> float:
        return 1.0 / math.tan(math.radians(self.fov_y_deg) / 2.0)

    @property
    def _s_x(self) -> float:
        return self._s_y / (self.width / self.height)

    @property
    def coc_px(self) -> float:
        """CoC radius at infinity in pixels (K)."""
        return self._coc_px

    @property
    def aperture_radius(self) -> float:
        """Aperture radius R in world units: K = R s_x W / (2 F)."""
        return 2.0 * self.focus_distance * self._coc_px / (self._s_x * self.width)

    def coc_radius_px(self, depth):
        """CoC radius in pixels of a point at view depth ``depth``: ``K |1 - F / depth|``."""
        depth = np.asarray(depth, dtype=np.float64)
        return self._coc_px * np.abs(1.0 - self.focus_distance / depth)

    # ---- transforms ----------------------------------------------------------------------
    def view_matrix(self) -> np.ndarray:
        """4x4 world -> view matrix (identity for the default pose)."""
        if not self._pose_given:
            return np.eye(4)
        f = self.target - self.eye
        f = f / np.linalg.norm(f)
        r = np.cross(f, self.up)
        r = r / np.linalg.norm(r)
        u = np.cross(r, f)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = r, u, -f
        m[:3, 3] = -m[:3, :3] @ self.eye
        return m

    def world_to_clip(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) world points -> (..., 4) clip (x, y, z, w), z = w - near (infinite far)."""
        p = np.asarray(points, dtype=np.float64)
        if not self._pose_given:  # identity view: p @ I + 0 is exactly p + 0.0 (which turns -0.0 into +0.0)
            v = p + 0.0
        else:
            m = self.view_matrix()
            v = p @ m[:3, :3].T + m[:3, 3]
        w = -v[..., 2]
        x, y = self._s_x * v[..., 0], self._s_y * v[..., 1]
        if self.shift != (0.0, 0.0):  # off-centre viewport: the principal point moves by shift (NDC)
            x, y = x + self.shift[0] * w, y + self.shift[1] * w
        return np.stack([x, y, w - self.near, w], axis=-1)

    def clip_to_engine(self, clip: np.ndarray) -> np.ndarray:
        """(..., 4) clip -> (..., 3) pixel-homogeneous (X_h, Y_h, W) in float64."""
        x, y, w = clip[..., 0], clip[..., 1], clip[..., 3]
        return np.stack([(x + w) * (self.width / 2.0), (w - y) * (self.height / 2.0), w], axis=-1)

    def engine_vertices(self, positions: np.ndarray, positions_t1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World (N,3,3) at t=0 and t=1 -> engine (N,3,3) float32 at shutter open and close."""
        p0 = np.asarray(positions, dtype=np.float64)
        p1 = np.asarray(positions_t1, dtype=np.float64)
        s_open, s_close = self.shutter
        if (s_open, s_close) != (0.0, 1.0):
            p0, p1 = p0 + s_open * (p1 - p0), p0 + s_close * (p1 - p0)
        e0 = self.clip_to_engine(self.world_to_clip(p0)).astype(np.float32)
        if positions_t1 is positions or np.array_equal(p0, p1):
            return e0, e0.copy()
        return e0, self.clip_to_engine(self.world_to_clip(p1)).astype(np.float32)

    def engine_params(self) -> dict:
        """Camera part of the engine's RenderParams."""
        return {
            "width": self.width,
            "height": self.height,
            "coc_x_px": self._coc_px,
            "coc_y_px": -self._coc_px,
            "focus_w": self.focus_distance,
            "near_w": self.near,
        }

    def describe(self) -> dict:
        return {
            "width": self.width,
            "height": self.height,
            "fov_y_deg": self.fov_y_deg,
            "focus_distance": self.focus_distance,
            "coc_px": self._coc_px,
            "aperture_radius": self.aperture_radius,
            "lens": self.lens,
            "near": self.near,
            "shutter": list(self.shutter),
            "shift": list(self.shift),
            "eye": self.eye.tolist(),
            "target": self.target.tolist(),
            "up": self.up.tolist(),
        }

    def __repr__(self) -> str:
        return (
            f"Camera({self.width}x{self.height}, fov_y={self.fov_y_deg:g}, F={self.focus_distance:g}, "
            f"coc_px={self._coc_px:g}, lens={self.lens!r})"
        )

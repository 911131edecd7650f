"""Texture images: load as linear float32 (sRGB-decoded) and sample bilinearly at UVs."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .scene import SceneError, srgb_to_linear

if TYPE_CHECKING:  # PIL is imported where an image is read
    from PIL import Image

__all__ = ["load_texture", "image_to_linear", "sample_bilinear", "srgb_to_linear"]


def image_to_linear(image: Image.Image) -> np.ndarray:
    """A PIL image -> (H, W, 3|4) float32 linear in [0, 1]. Colour channels are sRGB-decoded,
    alpha is kept linear; 16-bit greyscale is scaled by 65535."""
    if image.mode in ("I;16", "I;16B", "I;16L", "I"):
        grey = np.asarray(image, dtype=np.float32) / np.float32(65535.0)
        encoded = np.repeat(np.clip(grey, 0.0, 1.0)[..., None], 3, axis=2)
    else:
        has_alpha = image.mode in ("RGBA", "LA", "PA") or (
            image.mode == "P" and "transparency" in image.info
        )
        encoded = np.asarray(image.convert("RGBA" if has_alpha else "RGB"), dtype=np.float32) / np.float32(255.0)
    linear = encoded.copy()
    linear[..., :3] = srgb_to_linear(encoded[..., :3])
    return linear


def load_texture(path: str | Path) -> np.ndarray:
    """Read an image file (PNG, JPEG, ...) as (H, W, 3|4) float32 linear in [0, 1]."""
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    if not path.is_file():
        raise SceneError(f"texture: file not found: {path}")
    try:
        with Image.open(path) as image:
            image.load()
            return image_to_linear(image)
    except (UnidentifiedImageError, OSError, ValueError) as exc:
        raise SceneError(f"texture: cannot read {path}: {exc}") from None


def sample_bilinear(texture: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear lookup with repeat wrapping. uv (..., 2) with v pointing up (OBJ convention: v=0 is
    the bottom row of the image); texel centres sit at half-integer coordinates. Returns (..., C)."""
    height, width = texture.shape[:2]
    uv = np.asarray(uv, dtype=np.float64)
    x = uv[..., 0] * width - 0.5
    y = (1.0 - uv[..., 1]) * height - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    x0 = x0.astype(np.int64)
    y0 = y0.astype(np.int64)
    xa, xb = np.mod(x0, width), np.mod(x0 + 1, width)
    ya, yb = np.mod(y0, height), np.mod(y0 + 1, height)
    top = texture[ya, xa] * (1 - fx) + texture[ya, xb] * fx
    bottom = texture[yb, xa] * (1 - fx) + texture[yb, xb] * fx
    return (top * (1 - fy) + bottom * fy).astype(np.float32)

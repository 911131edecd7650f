"""A dependency-free PNG writer with sRGB encoding (sim may import only numpy)."""
from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np


def linear_to_srgb8(image: np.ndarray) -> np.ndarray:
    """Linear float RGB in [0, 1] (clamped) -> 8-bit sRGB (IEC 61966-2-1 transfer function)."""
    x = np.clip(np.asarray(image, dtype=np.float64), 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def write_png(path, image: np.ndarray) -> Path:
    """Write a linear (H, W, 3) float image as an 8-bit sRGB PNG (with an sRGB chunk)."""
    img = np.asarray(image)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ValueError(f"image: expected shape (H, W, 3), got {img.shape}")
    data = linear_to_srgb8(img)
    h, w, _ = data.shape
    raw = b"".join(b"\x00" + data[y].tobytes() for y in range(h))

    def chunk(kind: bytes, payload: bytes) -> bytes:
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"sRGB", b"\x00")
    png += chunk(b"IDAT", zlib.compress(raw, 6))
    png += chunk(b"IEND", b"")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(png)
    return path

"""What every use shares: the result type, the check of the use figures (declared in sim/figures.py,
merged into sim.counter_docs() and docs/counters.md) and float64 ray geometry that is independent of
the engine (the references and the look-ups of the uses)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError

from ..figures import FIGURES, figure_docs  # noqa: F401 - declared beside the counters


def figures(**values) -> dict:
    """{name: value} with each name checked against FIGURES (written with '__' for '.')."""
    out = {}
    for k, v in values.items():
        name = k.replace("__", ".")
        if name not in FIGURES:
            raise KeyError(f"undeclared use figure {name!r}")
        out[name] = v
    return out


@dataclass
class UseResult:
    """What a use returns: its image (H, W, 3) linear RGB, its flat statistics (the engine counters of
    its main pass and its own figures, sim.uses.FIGURES) and named arrays for inspection."""

    image: np.ndarray
    flat_stats: dict
    arrays: dict = field(default_factory=dict)

    @property
    def stats(self) -> dict:
        from ..derived import nest

        return nest(self.flat_stats)

    def save_png(self, path):
        from ..png import write_png

        return write_png(path, self.image)


def check_options(owner: str, given: dict, allowed: dict) -> dict:
    """given merged over allowed defaults; unknown keys are errors naming the key."""
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        raise ConfigError(f"{owner}: unknown option {unknown[0]!r} (known: {', '.join(sorted(allowed))})")
    return {**allowed, **given}


def ops_all(flat: dict) -> int:
    """Rasterization and per-sample backend operations: ops.total + ops.interp."""
    return int(flat["ops.total"] + flat["ops.interp"])


# ---- engine-independent geometry (float64) -------------------------------------------------------

def tiled_samples(table, camera) -> np.ndarray:
    """(H, W, spp, 5) float64 samples of every pixel, (x, y) made absolute (pixel + offset)."""
    s = np.asarray(table.samples(camera.lens), dtype=np.float64)
    P = s.shape[0]
    ys = np.arange(camera.height) % P
    xs = np.arange(camera.width) % P
    out = s[ys][:, xs].copy()
    out[..., 0] += np.arange(camera.width)[None, :, None]
    out[..., 1] += np.arange(camera.height)[:, None, None]
    return out


def pinhole_rays(camera, sx, sy) -> tuple[np.ndarray, np.ndarray]:
    """World (origin, direction) of the pinhole rays through pixel positions (sx, sy); the direction
    has view-space z = -1, so the ray parameter is the view depth w."""
    s_y = 1.0 / np.tan(np.radians(camera.fov_y_deg) / 2.0)
    s_x = s_y * camera.height / camera.width
    sx, sy = np.broadcast_arrays(np.asarray(sx, np.float64), np.asarray(sy, np.float64))
    d_view = np.stack([(2.0 * sx / camera.width - 1.0) / s_x, (1.0 - 2.0 * sy / camera.height) / s_y,
                       -np.ones_like(sx)], axis=-1)
    m = camera.view_matrix()
    rot = m[:3, :3]
    origin = -rot.T @ m[:3, 3]
    return np.broadcast_to(origin, d_view.shape), d_view @ rot


def view_dirs(camera, sx, sy) -> tuple[np.ndarray, np.ndarray]:
    """View-space direction (dx, dy) of the pinhole ray through pixel positions (sx, sy); the full
    direction is (dx, dy, -1), so a ray parameter is the view depth w."""
    s_y = 1.0 / np.tan(np.radians(camera.fov_y_deg) / 2.0)
    s_x = s_y * camera.height / camera.width
    return (2.0 * np.asarray(sx, np.float64) / camera.width - 1.0) / s_x, \
        (1.0 - 2.0 * np.asarray(sy, np.float64) / camera.height) / s_y


def to_view(camera, points) -> np.ndarray:
    m = camera.view_matrix()
    return np.asarray(points, np.float64) @ m[:3, :3].T + m[:3, 3]


def view_ray_triangle(dx, dy, tri_view) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Moller-Trumbore in view space for rays from the origin along (dx, dy, -1) (arrays) against one
    static view-space triangle (3, 3), written per component: (hit, view depth w, barycentrics)."""
    a, b, c = (np.asarray(v, np.float64) for v in tri_view)
    e1, e2 = b - a, c - a
    # p = d x e2, d = (dx, dy, -1)
    px = dy * e2[2] + e2[1]
    py = -e2[0] - dx * e2[2]
    pz = dx * e2[1] - dy * e2[0]
    det = e1[0] * px + e1[1] * py + e1[2] * pz
    ok = np.abs(det) > 1e-300
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tv = -a  # origin - a
    u = (tv[0] * px + tv[1] * py + tv[2] * pz) * inv
    q = np.cross(tv, e1)  # constant
    v = (dx * q[0] + dy * q[1] - q[2]) * inv
    t = float(e2 @ q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return hit, t, (1.0 - u - v, u, v)


def ray_triangle(origin, direction, tri) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Moller-Trumbore, double-sided, vectorised over rays (..., 3) against one triangle (3, 3) or
    one triangle per ray (..., 3, 3): (hit, ray parameter, barycentrics (..., 3))."""
    tri = np.asarray(tri, np.float64)
    a, b, c = tri[..., 0, :], tri[..., 1, :], tri[..., 2, :]
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.sum(e1 * p, axis=-1)
    ok = np.abs(det) > 1e-300
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tv = origin - a
    u = np.sum(tv * p, axis=-1) * inv
    q = np.cross(tv, e1)
    v = np.sum(direction * q, axis=-1) * inv
    t = np.sum(e2 * q, axis=-1) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    bary = np.stack([1.0 - u - v, u, v], axis=-1)
    return hit, t, bary


def chi2_sf(x: float, dof: int) -> float:
    """P(X >= x) for X ~ chi-square(dof): the regularized upper incomplete gamma Q(dof/2, x/2), by its
    series below a + 1 and its continued fraction above (Numerical Recipes §6.2)."""
    import math

    a, z = 0.5 * dof, 0.5 * float(x)
    if z <= 0:
        return 1.0
    lg = math.lgamma(a)
    if z < a + 1.0:  # series for P
        term = total = 1.0 / a
        ap = a
        for _ in range(10000):
            ap += 1.0
            term *= z / ap
            total += term
            if abs(term) < abs(total) * 1e-15:
                break
        return max(0.0, 1.0 - total * math.exp(-z + a * math.log(z) - lg))
    b = z + 1.0 - a  # continued fraction for Q (modified Lentz)
    c = 1.0 / 1e-300
    d = 1.0 / b
    h = d
    for i in range(1, 10000):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = 1e-300 if abs(d) < 1e-300 else d
        c = b + an / c
        c = 1e-300 if abs(c) < 1e-300 else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < 1e-15:
            break
    return min(1.0, math.exp(-z + a * math.log(z) - lg) * h)


def chi2_uniform(counts: np.ndarray, expected: np.ndarray) -> tuple[float, int]:
    """(p-value, degrees of freedom) of Pearson's chi-square of counts against expected counts (cells
    with expected 0 are left out; their counts must be 0, checked by the caller)."""
    counts = np.asarray(counts, np.float64).ravel()
    expected = np.asarray(expected, np.float64).ravel()
    keep = expected > 0
    stat = float(np.sum((counts[keep] - expected[keep]) ** 2 / expected[keep]))
    dof = int(keep.sum()) - 1
    return chi2_sf(stat, dof), dof


def chi2_stratified(counts: np.ndarray, expected: np.ndarray, variance: np.ndarray) -> tuple[float, int]:
    """(p-value, degrees of freedom) of sum (count - expected)^2 / variance over the cells with a positive
    variance: chi-square with one degree per cell when each count is independent with that mean and
    variance (the counts of pixel-stratified samples, whose total is not fixed)."""
    counts = np.asarray(counts, np.float64).ravel()
    expected = np.asarray(expected, np.float64).ravel()
    variance = np.asarray(variance, np.float64).ravel()
    keep = variance > 0
    stat = float(np.sum((counts[keep] - expected[keep]) ** 2 / variance[keep]))
    dof = int(keep.sum())
    return chi2_sf(stat, dof), dof

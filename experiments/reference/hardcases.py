"""Named hard inputs: vertices behind the camera or the near plane, focus-plane crossings, degenerate
and edge-on triangles, huge blur, gigantic coordinates, with the setup counters they must raise."""
from __future__ import annotations

import numpy as np

import sim

from .raycaster import screen_to_world


def hard_cases():
    """Named hard inputs: {name: (camera kwargs, positions (N,3,3), positions_t1 (N,3,3),
    expected setup counters)}. Positions are built in the default camera's view space (the world)."""
    base = dict(width=32, height=32, fov_y_deg=45.0, focus_distance=5.0, coc_px=8.0, lens="disk", near=0.1)
    cam = sim.Camera(**base)

    def px(sx, sy, w):
        return screen_to_world(cam, sx, sy, w)

    def tri(*verts):
        return np.array(verts, dtype=np.float64)

    F = cam.focus_distance
    cases = {}

    def add(name, p0, p1=None, counters=None, **cam_kw):
        p0 = np.asarray(p0, dtype=np.float64)
        p1 = p0.copy() if p1 is None else np.asarray(p1, dtype=np.float64)
        cases[name] = ({**base, **cam_kw}, p0, p1, counters or {})

    add("vertex_behind_camera",
        [tri(px(6, 7, 3.0), px(25, 12, 4.0), [0.4, -0.3, 2.0]),
         tri(px(20, 25, 6.0), [-0.5, 0.6, 1.0], [0.7, 0.2, 3.0])],
        counters={"setup.near_clipped": 2})
    add("crosses_focus_plane", [tri(px(5, 6, 2.0), px(27, 9, F), px(14, 28, 14.0))])
    add("edge_parallel_to_focus_plane",
        [tri(px(4, 5, 3.0), px(26, 5, 3.0), px(15, 27, 9.0)),
         tri(px(6, 20, F), px(28, 22, F), px(17, 3, 2.0))])
    add("vertex_exactly_at_focus", [tri(px(16, 4, F), px(4, 28, 2.5), px(29, 26, 11.0))])
    add("degenerate_collinear_3d",
        [tri([-0.5, -0.25, -3.0], [0.0, 0.0, -4.0], [0.5, 0.25, -5.0]),
         tri([-0.5, 0.5, -6.0], [-0.5, 0.5, -6.0], [0.5, -0.5, -4.0]),
         tri([0.25, 0.25, -4.0], [0.25, 0.25, -4.0], [0.25, 0.25, -4.0])])
    add("edge_on_to_pinhole", [tri([0.0, -1.0, -3.0], [0.0, 1.0, -3.0], [0.0, 0.25, -9.0])], coc_px=12.0)
    add("huge_blur_tiny_triangles",
        [tri(px(12, 12, 4.5), px(20, 13, 4.5), px(15, 20, 4.5)),
         tri(px(8, 10, 2.5), px(16, 9, 2.5), px(11, 17, 2.5)),
         tri(px(20, 20, 40.0), px(23, 21, 40.0), px(21, 24, 40.0))],
        coc_px=500.0)
    add("tiny_coc", [tri(px(3.3, 4.1, 2.0), px(28.7, 9.2, 7.0), px(12.5, 29.9, 20.0))], coc_px=0.001)
    add("entirely_behind_near_plane",
        [tri(px(4, 4, 0.05), px(28, 4, 0.09), px(16, 28, 0.02)),
         tri([0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 0.5]),
         tri(px(8, 8, 3.0), px(24, 8, 3.0), px(16, 24, 3.0))],
        counters={"setup.culled_near": 2})
    add("moving_through_near_plane",
        [tri(px(6, 6, 3.0), px(26, 8, 3.5), px(15, 27, 4.0)),
         tri(px(8, 20, 0.05), px(25, 22, 0.05), px(16, 5, 0.08))],
        [tri(px(6, 6, 3.0) + [0, 0, 4.0], px(26, 8, 3.5) + [0, 0, 4.0], px(15, 27, 4.0) + [0, 0, 4.0]),
         tri(px(8, 20, 3.0), px(25, 22, 3.0), px(16, 5, 4.0))],
        counters={"setup.bbox_fallback": 2})
    add("vertex_on_lens_plane_and_at_near",  # w = 0 exactly (a point at infinity), w = near exactly
        [tri(px(6, 8, 3.0), px(26, 10, 6.0), [0.3, -0.2, 0.0]),
         tri(px(4, 24, cam.near), px(28, 28, 2.0), px(16, 12, 4.0))],
        counters={"setup.near_clipped": 1})
    add("gigantic_coordinates",  # edges of the 1e6-sized triangles cross the screen
        [tri([-2e5, -1e5, -1e6], [3e5, -1.5e5, -1e6], [0.0, 2e5, -1.1e6]),
         tri([-1e6, 0.3, -10.0], [1e6, -0.5, -10.0], [0.0, -1e6, -9.0]),
         tri([0.2, -1e6, -1e6], [0.9, 1e6, -1e6], [1e6, 0.0, -1e6])])
    add("moving_and_defocused_crossing_focus",
        [tri(px(4, 4, 2.0), px(20, 6, 8.0), px(10, 20, 5.0))],
        [tri(px(12, 10, 9.0), px(28, 12, 2.5), px(18, 28, 5.0))])
    return cases

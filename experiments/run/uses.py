"""Point kinds of the rasterizer's uses (sim.uses): build the point's scene, camera, table and
pipeline, run the use with `point.options`, keep its counters and figures, write its image."""
from __future__ import annotations

import time
from pathlib import Path

from ..config import build


def _use_point(kind: str):
    def run(config, row, image_path, threads):
        from sim import uses

        scene, camera, table, pipeline = build(config)
        if threads is not None and config.pipeline.threads == 0:
            pipeline = pipeline.replace(threads=threads)
        row["scene.triangles"] = scene.n_triangles
        t0 = time.perf_counter()
        r = uses.run_use(kind, scene, camera, table, pipeline, hardware=config.hardware_config(),
                         options=config.point.options)
        row.update({k: v for k, v in r.flat_stats.items() if not k.startswith("timing.")})
        row["time.wall_s"] = time.perf_counter() - t0
        if image_path is not None:
            Path(image_path).parent.mkdir(parents=True, exist_ok=True)
            r.save_png(image_path)
        return r

    run.__name__ = f"_use_{kind}"
    return run


USE_KINDS = {kind: _use_point(kind) for kind in ("transparency", "sampler", "soft_shadows", "caustics", "glossy")}

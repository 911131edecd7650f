"""The timing model's figures with the memory model off: tests/golden/timing_flat.csv (beside this file).

With ``hardware.depth_buffer.enabled`` and ``hardware.color_buffer.enabled`` false every depth read and
write goes to DRAM at 4 bytes, with no colour traffic, and with ``hardware.timing.idle_units:
traverse`` every record passes every unit: the record-level model as it was before the memory model,
the bypass of idle units and the streaming inside the engine. The file holds every ``timing.*``
figure (exact repr) of small renders over scenes, algorithms, both record granularities, several
cores, shading with a texture, HiZ, line samples and a conventional-GPU method, as that model computed
them; tests/test_timing_stream.py renders the same cases and asks for the same figures bit for bit.
`python -m tests.golden.timing_flat` rewrites the file: only on purpose, saying why in the commit.
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

GOLDEN = Path(__file__).resolve().parent / "timing_flat.csv"
HEADER = ("scene", "algorithm", "granularity", "cores", "variant", "figure", "value")
SIZES = {"bunny": (64, 64), "spot": (64, 48), "moving_quads": (48, 48)}
VARIANTS = {"": {}, "msaa_tex": {"shading": "msaa", "texture_count": 1}, "hiz": {"hiz": {"enabled": True, "tile_size": 8}}}
# The parts the record-level model did not have, off: the memory model, and idle units bypassed.
FLAT_MEMORY = {"depth_buffer": {"enabled": False, "compression": "none"}, "color_buffer": {"enabled": False}}


def cases() -> list[tuple[str, str, str, int, str]]:
    out = [(scene, algo, gran, 1, "") for scene in ("bunny", "spot", "moving_quads")
           for algo in ("bruteforce", "tile", "interval", "interleave") for gran in ("visit", "bin")]
    out += [("spot", "tile", "visit", 2, ""), ("spot", "tile", "visit", 1, "msaa_tex"),
            ("spot", "interval", "visit", 1, "msaa_tex"), ("spot", "interleave", "bin", 3, "msaa_tex"),
            ("bunny", "laine", "visit", 1, ""), ("spot", "gpu_hexagon3d", "visit", 1, ""),
            ("spot", "lines", "visit", 1, ""), ("spot", "tile", "visit", 1, "hiz")]
    return out


def compute(case) -> dict[str, float]:
    """Every numeric timing.* figure of one case with the memory model off."""
    import models
    import sim

    scene_name, algo, gran, cores, variant = case
    scene = models.named(scene_name)
    w, h = SIZES[scene_name]
    hint = scene.camera_hint
    cam = sim.Camera(width=w, height=h, fov_y_deg=hint.get("fov_y_deg", 45.0),
                     focus_distance=hint["focus_distance"], coc_px=10)
    if algo in sim.line_algorithms():
        table = sim.SampleTable.lines(n_lines=8, seed=3, wheel=4)  # the wheel the figures were recorded with
    elif algo in sim.interleaved_algorithms():
        table = sim.SampleTable.interleaved(spp=16, n_lens=64, seed=3)
    else:
        table = sim.SampleTable.stratified(spp=16, seed=3)
    cfg = sim.PipelineConfig(algorithm=algo, threads=2, **VARIANTS[variant])
    hw = sim.HardwareConfig.from_dict({"cores": cores, "timing": {"granularity": gran, "idle_units": "traverse"},
                                       **FLAT_MEMORY})
    r = sim.render(scene, cam, table, cfg, hardware=hw)
    return {k: float(v) for k, v in sorted(r.flat_stats.items()) if k.startswith("timing.") and not isinstance(v, str)}


def read(path: Path = GOLDEN) -> dict[tuple, str]:
    with path.open() as f:
        return {(r["scene"], r["algorithm"], r["granularity"], int(r["cores"]), r["variant"], r["figure"]): r["value"]
                for r in csv.DictReader(f)}


def main() -> int:
    rows = [(*case, k, repr(v)) for case in cases() for k, v in compute(case).items()]
    with GOLDEN.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(HEADER)
        w.writerows(rows)
    print(f"{GOLDEN.name}: {len(rows)} figures of {len(cases())} renders")
    return 0


if __name__ == "__main__":
    sys.exit(main())

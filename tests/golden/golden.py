"""Golden operation counts: tests/golden/ops.csv (beside this file).

Rows are (scene, algorithm, table, coc, spp, tile, grid, counter) -> value, one counter per line so
that a change in the model shows up in review as exactly the counters it moved. `make golden`
(`python -m tests.golden.golden`) regenerates the file and prints a summary of the differences;
change the file only on purpose and say why in the commit. tests/test_golden.py compares the key
sets first, then the values.
"""
from __future__ import annotations

import argparse
import csv
import functools
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
GOLDEN = Path(__file__).resolve().parent / "ops.csv"
KEY = ("scene", "algorithm", "table", "coc", "spp", "tile", "grid")

# Small renders of the paper's workloads (and two hard cases) so the whole file recomputes in seconds.
SCENES = {
    "bunny": dict(name="bunny", params={}, size=(96, 96)),
    "spot": dict(name="spot", params={}, size=(96, 96)),
    "modern_hall": dict(name="modern_hall", params={}, size=(128, 72)),
    "mixed_sizes": dict(name="mixed_sizes", params={"n": 2000, "resolution": 96, "max_area_px": 1000.0},
                        size=(96, 96)),
    "focus_crossing": dict(name="focus_crossing", params={}, size=(64, 64)),
    "moving_quads": dict(name="moving_quads", params={}, size=(64, 64)),
}


@functools.cache
def algorithms() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(algorithms for arbitrary tables, algorithms that need an interleaved table), in registry order,
    read from the registry (sim.algorithm_names("points"), sim.interleaved_algorithms())."""
    import sim

    interleaved = set(sim.interleaved_algorithms())
    names = sim.algorithm_names("points")
    return (tuple(n for n in names if n not in interleaved), tuple(n for n in names if n in interleaved))


@functools.cache
def line_algorithms() -> tuple[str, ...]:
    """The line-sample algorithms (sim.line_algorithms()): they render SampleTable.lines tables."""
    import sim

    return tuple(sim.line_algorithms())


# Line-sample cases: static scenes (line samples do not model motion blur) and their CoCs
# (modern_hall's 30k triangles at CoC 50 would take half a minute).
LINE_SCENES = {"spot": (0.0, 10.0, 50.0), "modern_hall": (0.0, 10.0), "focus_crossing": (0.0, 10.0, 50.0)}


# Variants: the scene column reads "<scene>+<variant>" and the variant adds pipeline settings.
VARIANTS = {
    "splits4": {"time_splits": 4},
    "splits16": {"time_splits": 16, "time_strata": 16},
    "strata1": {"time_strata": 1},
    "bounds": {"motion_test": "bounds"},
    "clip": {"clip": {"u": [-0.5, 0.75], "v": [-1.0, 0.5], "t": [0.125, 0.75]}},
    "hiz": {"hiz": {"enabled": True, "tile_size": 8}, "zhat_stats": True},
    "hiz_vertex": {"hiz": {"enabled": True, "tile_size": 4}, "zhat": "vertex", "zhat_stats": True},
    # shading modes, texturing and the texture cache (spot has its own texture)
    "msaa_tex": {"shading": "msaa", "texture_count": 1},
    "per_sample": {"shading": "per_sample"},
    "per_lens_cell": {"shading": "per_lens_cell"},
    "cache_tex": {"shading": "cache", "texture_count": 2, "texture_layout": "morton"},
    # the hardware operation-cost model (fixed-point affine edge functions)
    "hardware": {"cost_model": "hardware"},
    # moving triangles: the H5 planes (with and without the selective oracle), t̂ without lens sets
    "h5": {"halfspace": {"h": True, "H": True, "H5": True}},
    "h5_all_edges": {"halfspace": {"h": True, "H": True, "H5": True}, "selective_H": False},
    "h5_splits4": {"halfspace": {"h": True, "H": True, "H5": True}, "time_splits": 4},
    "no_lens_sets": {"halfspace": {"h": False, "H": True}},
}
# Variants of the line-sample cases only: the tile's h_i lens region clips the lines.
LINE_VARIANTS = {"tile_clip": {"lines": {"tile_clip": True}},
                 # textured segments: a shader lane per segment, texel fetches, the texture cache
                 "per_sample_tex": {"shading": "per_sample", "texture_count": 1}}
# Figures of the timing and memory model kept in the golden file (rounded to whole units), so a change
# to the model or to the work it is fed shows up in review like an operation count.
TIMING_FIGURES = ("timing.cycles", "dram.bytes", "depth.cache.misses")


@dataclass(frozen=True)
class Case:
    scene: str
    algorithm: str
    coc: float
    spp: int = 16
    tile: int = 2
    grid: int = 4

    @property
    def table(self) -> str:
        if self.algorithm in line_algorithms():
            return "lines"  # the spp column holds n_lines
        return "interleaved64" if self.algorithm in algorithms()[1] else "stratified"

    def key(self) -> tuple:
        return (self.scene, self.algorithm, self.table, f"{self.coc:g}", str(self.spp), str(self.tile), str(self.grid))


def cases() -> list[Case]:
    out = []
    arbitrary, interleaved = algorithms()
    for scene in SCENES:
        for algorithm in arbitrary + interleaved:
            for coc in (0.0, 10.0, 50.0):
                out.append(Case(scene, algorithm, coc))
    for tile in (1, 4, 8):  # tile sizes, and the 8x8 grid at 64 spp
        out.append(Case("bunny", "tile", 10.0, tile=tile))
    out.append(Case("bunny", "tile", 20.0, spp=64, grid=8))
    out.append(Case("bunny", "interval", 20.0, spp=64, grid=8))
    for variant in VARIANTS:  # time intervals, clip planes, HiZ on the moving scene
        for coc in (0.0, 10.0):
            out.append(Case(f"moving_quads+{variant}", "tile", coc))
    out.append(Case("moving_quads+clip", "bruteforce", 10.0))
    for variant in ("hiz", "hiz_vertex"):
        out.append(Case(f"spot+{variant}", "tile", 10.0))
    for algorithm in arbitrary + ("interleave",):  # quads, texture fetches, cache misses
        out.append(Case("spot+msaa_tex", algorithm, 10.0))
    for variant in ("per_sample", "per_lens_cell", "cache_tex"):
        out.append(Case(f"spot+{variant}", "tile", 10.0))
    out.append(Case("spot+per_lens_cell", "interval", 10.0))
    for algorithm in arbitrary + interleaved:  # the hardware cost model, every algorithm
        for coc in (0.0, 10.0):
            out.append(Case("bunny+hardware", algorithm, coc))
    out.append(Case("moving_quads+hardware", "tile", 10.0))
    for algorithm in line_algorithms():  # line samples: n_lines x CoC, with and without the tile clip
        for scene, cocs in LINE_SCENES.items():
            for n_lines in (4, 16):
                for coc in cocs:
                    for variant in ("", "+tile_clip"):
                        out.append(Case(scene + variant, algorithm, coc, spp=n_lines))
        for n_lines in (4, 16):  # textured segments (spot's texture) in the shading modes lines support
            for coc in (10.0, 50.0):
                out.append(Case("spot+per_sample_tex", algorithm, coc, spp=n_lines))
        for variant in ("msaa_tex", "cache_tex"):
            out.append(Case(f"spot+{variant}", algorithm, 10.0, spp=16))
    return out


_scene_cache: dict = {}


def compute(case: Case) -> dict[str, int]:
    """The raw counters of one case (documented op costs; equal to exact counting by invariant 4)."""
    import models
    import sim

    scene_name, _, variant = case.scene.partition("+")
    spec = SCENES[scene_name]
    if scene_name not in _scene_cache:
        _scene_cache[scene_name] = models.named(spec["name"], **spec["params"])
    scene = _scene_cache[scene_name]
    hint = scene.camera_hint
    w, h = spec["size"]
    camera = sim.Camera(width=w, height=h, fov_y_deg=hint.get("fov_y_deg", 45.0),
                        focus_distance=hint["focus_distance"], coc_px=case.coc)
    if case.table == "lines":
        table = sim.SampleTable.lines(n_lines=case.spp, seed=7)
    elif case.table == "stratified":
        table = sim.SampleTable.stratified(spp=case.spp, seed=7)
    else:
        table = sim.SampleTable.interleaved(spp=case.spp, n_lens=64, seed=7)
    config = sim.PipelineConfig(algorithm=case.algorithm, tile_size=case.tile, lens_grid=case.grid, threads=2,
                                count_optimal=True, **{**VARIANTS, **LINE_VARIANTS}.get(variant, {}))
    result = sim.render(scene, camera, table, config)
    raw = set(sim._core.counter_docs())
    out = {k: int(v) for k, v in result.flat_stats.items() if k in raw}
    out.update({k: int(round(result.flat_stats[k])) for k in TIMING_FIGURES})
    return out


def compute_all(progress: bool = True) -> dict[tuple, int]:
    rows = {}
    todo = cases()
    it = todo
    if progress:
        from tqdm import tqdm

        it = tqdm(todo, desc="golden", unit="case")
    for case in it:
        for counter, value in compute(case).items():
            rows[case.key() + (counter,)] = value
    return rows


def read(path: Path = GOLDEN) -> dict[tuple, int]:
    with path.open() as f:
        return {tuple(r[k] for k in KEY + ("counter",)): int(r["value"]) for r in csv.DictReader(f)}


def write(rows: dict[tuple, int], path: Path = GOLDEN) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(KEY + ("counter", "value"))
        for key in sorted(rows):
            w.writerow(key + (rows[key],))


def diff(stored: dict[tuple, int], computed: dict[tuple, int]) -> tuple[set, set, list]:
    """(keys only stored, keys only computed, [(key, stored, computed)] for changed values)."""
    removed = set(stored) - set(computed)
    added = set(computed) - set(stored)
    changed = [(k, stored[k], computed[k]) for k in sorted(set(stored) & set(computed)) if stored[k] != computed[k]]
    return removed, added, changed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--check", action="store_true", help="only compare, do not rewrite")
    args = parser.parse_args(argv)
    computed = compute_all()
    stored = read() if GOLDEN.exists() else {}
    removed, added, changed = diff(stored, computed)
    print(f"{GOLDEN.relative_to(REPO)}: {len(computed)} values; {len(added)} added, {len(removed)} removed, "
          f"{len(changed)} changed")
    by_counter: dict[str, list] = {}
    for key, a, b in changed:
        by_counter.setdefault(key[-1], []).append((key, a, b))
    for counter, items in sorted(by_counter.items()):
        worst = max(items, key=lambda x: abs(x[2] - x[1]) / max(abs(x[1]), 1))
        rel = (worst[2] - worst[1]) / max(abs(worst[1]), 1)
        print(f"  {counter}: {len(items)} cases changed, largest {rel:+.2%} at {worst[0][:-1]} ({worst[1]} -> {worst[2]})")
    if not args.check:
        write(computed)
        print("rewritten; review `git diff tests/golden/ops.csv` and explain the change in the commit")
    return 1 if (args.check and (removed or added or changed)) else 0


if __name__ == "__main__":
    sys.exit(main())

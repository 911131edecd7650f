"""Benchmarks of the engine (`make bench`)."""
from __future__ import annotations

import argparse
import os
from pathlib import Path


def scene_camera(scene, w: int, h: int, coc: float):
    """A w x h camera at the scene's camera hint (field of view, focus distance) with CoC coc px."""
    import sim

    hint = scene.camera_hint
    return sim.Camera(width=w, height=h, fov_y_deg=hint.get("fov_y_deg", 45.0),
                      focus_distance=hint["focus_distance"], coc_px=coc)


def write_page(out, name: str, lines: list[str]) -> Path:
    """Write a benchmark page (markdown lines) as out/name, creating out, and say where. A header line that
    gives the load average " at the start." gets the load at the end beside it."""
    end_load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [line.replace(" at the start.", f" at the start, {end_load:.1f} at the end.") if i < 4 else line
             for i, line in enumerate(lines)]
    page = Path(out) / name
    page.parent.mkdir(parents=True, exist_ok=True)
    page.write_text("\n".join(lines) + "\n")
    print(f"\nwrote {page}")
    return page


def bench_parser(doc: str) -> argparse.ArgumentParser:
    """A benchmark's command line: its module docstring's first paragraph, and --out (the folder of its
    page, reports/bench under the working directory by default)."""
    from experiments.paths import reports_dir

    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=reports_dir() / "bench")
    return ap

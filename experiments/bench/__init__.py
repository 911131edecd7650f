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


def machine() -> str:
    """The machine a benchmark ran on, as its page names it: the architecture, the processor's model
    name, the hardware threads and the instruction set of the engine's explicit-SIMD sample tests in
    this build (sim._core.simd_isa: 'avx512', 'avx2' or 'scalar'; its rates and ratios depend on it)."""
    import platform

    import sim

    model = ""
    try:
        with open("/proc/cpuinfo") as f:
            model = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), "")
    except OSError:
        pass
    model = model or platform.processor()
    return (f"{platform.machine()}{f' ({model})' if model else ''}, {os.cpu_count()} hardware threads, "
            f"engine SIMD {sim._core.simd_isa()}")


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

"""One setup from Python and the command line: the README's Python example and the command line it
names render the same point with the same counters (the camera comes from the scene's hint in both:
sim.Camera.for_scene). The old README camera, built without the hint, is shown to differ, so the test
can fail."""
from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.smoke

REPO = Path(__file__).resolve().parents[1]


def readme_example() -> tuple[str, str]:
    """(the README's Python example, the `rast5d render` command it names)."""
    text = (REPO / "README.md").read_text()
    code = next(b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "Camera.for_scene" in b)
    command = re.search(r"^(rast5d render configs/spot_wall\.yaml[^\n`#]*)", text, re.M).group(1).strip()
    return code, command


def counters(flat: dict) -> dict:
    return {k: v for k, v in flat.items() if not k.startswith("time.") and not isinstance(v, str)}


def same(a, b) -> bool:
    if a is None or b is None:
        return (a is None or (isinstance(a, float) and math.isnan(a))) and \
               (b is None or (isinstance(b, float) and math.isnan(b)))
    return float(a) == float(b)


def test_readme_python_and_cli_give_the_same_counters(tmp_path, monkeypatch):
    code, command = readme_example()
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)  # noqa: S102 - the README's own example
    python = counters(scope["result"].flat_stats)
    args = command.split()[2:]
    r = subprocess.run([sys.executable, "-m", "experiments.cli", "render", str(REPO / args[0]), *args[1:],
                        "--stats", str(tmp_path / "s.json")], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    row = json.loads((tmp_path / "s.json").read_text())["row"]
    compared = [k for k in python if k in row]
    assert len(compared) > 100 and "raster.samples_tested" in compared and "ops.total" in compared
    differ = {k: (python[k], row[k]) for k in compared if not same(python[k], row[k])}
    assert not differ, differ


def test_a_camera_without_the_scene_hint_differs():
    """The old README camera (explicit fov and focus, no hint) renders another frame: the check above
    would catch a Python example that drops the scene's camera hint."""
    import models
    import sim

    scene = models.named("spot_wall")
    table, config = sim.SampleTable.stratified(spp=16, seed=1), sim.PipelineConfig(algorithm="tile")
    hinted = sim.render(scene, sim.Camera.for_scene(scene, width=128, height=128, coc_px=10), table, config)
    bare = sim.render(scene, sim.Camera(width=128, height=128, fov_y_deg=45, focus_distance=5.0, coc_px=10),
                      table, config)
    assert hinted.flat_stats["raster.ste"] != bare.flat_stats["raster.ste"]

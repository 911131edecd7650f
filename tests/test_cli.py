"""The rast5d command line: render, run (sweeps keep finished points when one fails), errors."""
import json
import os
import subprocess
import sys

import pandas as pd
import pytest

pytestmark = pytest.mark.smoke

CONFIG = """
name: tiny
scene: {name: quad}
camera: {width: 32, height: 32, coc_px: 4}
samples: {spp: 4, seed: 1}
pipeline: {algorithm: tile}
"""


def rast5d(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "experiments.cli", *args], capture_output=True, text=True, cwd=cwd)


def test_render_writes_image_and_stats(tmp_path):
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(CONFIG)
    out, stats = tmp_path / "out.png", tmp_path / "stats.json"
    r = rast5d("render", str(cfg), "--set", "camera.coc_px=8", "-o", str(out), "--stats", str(stats))
    assert r.returncode == 0, r.stderr
    assert "samples tested" in r.stdout and "STE" in r.stdout and "ops/pixel" in r.stdout
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    payload = json.loads(stats.read_text())
    assert payload["config"]["camera"]["coc_px"] == 8
    for key in ("raster.samples_tested", "raster.samples_hit", "raster.ste", "ops.setup", "ops.tile", "ops.sample",
                "ops.total", "setup.triangles"):
        assert key in payload["row"], key
    assert payload["stats"]["raster"]["samples_tested"] == payload["row"]["raster.samples_tested"]
    assert payload["counter_docs"]["raster.ste"]["unit"] == "ratio"


@pytest.mark.parametrize("override,message", [("camera.cocpx=3", "unknown key 'camera.cocpx'"),
                                              ("samples.spp=0", "spp"),
                                              ("pipeline.algorithm=nope", "algorithm")])
def test_render_errors_exit_cleanly(tmp_path, override, message):
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(CONFIG)
    r = rast5d("render", str(cfg), "--set", override)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr


def test_run_sweep_keeps_finished_points(tmp_path):
    cfg = tmp_path / "sweep.yaml"
    # quad size -1 is rejected when the scene is built: those points fail, the others are kept.
    cfg.write_text(CONFIG + "sweep:\n  scene.params.size: [1.0, -1.0]\n  camera.coc_px: [0, 4]\n")
    env = {**os.environ, "RAST5D_RESULTS": str(tmp_path / "res")}
    r = subprocess.run([sys.executable, "-m", "experiments.cli", "run", str(cfg), "--workers", "2"],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 1, r.stderr
    df = pd.read_parquet(tmp_path / "res" / "tiny.parquet")
    assert len(df) == 4
    assert (df["status"] == "ok").sum() == 2 and (df["status"] == "error").sum() == 2
    assert df[df["status"] == "error"]["error"].str.contains("size").all()
    assert sorted(df[df["status"] == "error"]["scene.params.size"]) == [-1.0, -1.0]
    assert len(list((tmp_path / "res" / "points").glob("*.parquet"))) == 4  # failed points are stored too
    assert "2 failed" in r.stdout


@pytest.mark.parametrize("sweep,message", [
    ("samples.spp: [4, -1]", "sweep point {'samples.spp': -1}"),
    ("pipeline.algorithm: [tile, tilez]", "did you mean 'tile'"),
    ("camera.coc_px: [0, -3]", "coc_px"),
    ("scene: [{name: quad}, {name: bunyn}]", "did you mean 'bunny'"),
    ("pipeline.tile_sise: [2]", "unknown key 'pipeline.tile_sise'; did you mean 'tile_size'"),
])
def test_run_validates_every_point_before_the_first_render(tmp_path, sweep, message, capsys, monkeypatch):
    from experiments.cli import main

    cfg = tmp_path / "sweep.yaml"
    cfg.write_text(CONFIG + "sweep:\n  " + sweep + "\n")
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "res"))
    assert main(["run", str(cfg), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err
    assert f"{cfg}:" in err or "sweep point" in err  # names the file or the point
    assert not list((tmp_path / "res").glob("**/*.parquet"))  # nothing rendered


def test_init_copies_the_configs_the_starter_and_the_notebooks(tmp_path, capsys):
    """`rast5d init DIR`: the shipped configs (each file byte for byte), the starter sweep as my_sweep.yaml
    (a valid config) and the example notebooks; a non-empty DIR is refused unless --force, which copies
    over the shipped files and leaves the user's own."""
    from pathlib import Path

    from experiments.cli import main
    from experiments.config import load_config

    repo = Path(__file__).resolve().parents[1]
    study = tmp_path / "study"
    assert main(["init", str(study)]) == 0
    shipped = sorted(p.relative_to(repo / "configs") for p in (repo / "configs").rglob("*.yaml"))
    copied = sorted(p.relative_to(study / "configs") for p in (study / "configs").rglob("*.yaml"))
    assert copied == [p for p in shipped if p.as_posix() != "starter.yaml"] and len(copied) > 40
    assert all((study / "configs" / p).read_bytes() == (repo / "configs" / p).read_bytes() for p in copied)
    assert (study / "my_sweep.yaml").read_bytes() == (repo / "configs" / "starter.yaml").read_bytes()
    assert load_config(study / "my_sweep.yaml", []).name == "my_sweep"
    notebooks = sorted(p.name for p in (study / "notebooks").glob("*.ipynb"))
    assert notebooks == sorted(p.name for p in (repo / "experiments" / "examples").glob("*.ipynb")) != []
    out = capsys.readouterr().out
    assert f"configs/ ({len(copied)} configs" in out and "notebooks/" in out

    (study / "my_sweep.yaml").write_text("# edited\n")
    (study / "mine.yaml").write_text("# the user's own\n")
    assert main(["init", str(study)]) == 2
    assert "not empty" in capsys.readouterr().err and (study / "my_sweep.yaml").read_text() == "# edited\n"
    assert main(["init", str(study), "--force"]) == 0
    assert (study / "my_sweep.yaml").read_bytes() == (repo / "configs" / "starter.yaml").read_bytes()
    assert (study / "mine.yaml").read_text() == "# the user's own\n"

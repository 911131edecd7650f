"""`rast5d render --heatmaps DIR`, `--pixel X,Y` and the progress bar (Ctrl-C still stops the render)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.test_interrupt import interrupt

from experiments.cli import main

ROOT = Path(__file__).resolve().parents[1]
SMALL = ["--set", "camera.width=48", "--set", "camera.height=40", "--set", "samples.spp=4",
         "--set", "pipeline.algorithm=tile"]


def test_heatmaps_written_with_colour_bars(tmp_path, capsys):
    out = tmp_path / "maps"
    assert main(["render", str(ROOT / "configs/spot_wall.yaml"), *SMALL, "--heatmaps", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "heatmaps ->" in printed
    for name in ("image", "raster.samples_tested", "raster.samples_hit", "ops.total", "tile.cull_reason"):
        f = out / f"{name}.png"
        assert f.exists() and f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name


def test_pixel_trace_cli(capsys):
    assert main(["render", str(ROOT / "configs/spot_wall.yaml"), *SMALL, "--pixel", "24,20"]) == 0
    text = capsys.readouterr().out
    assert "pixel (24, 20)" in text and "samples tested" in text and "verdict" in text
    with pytest.raises(SystemExit):
        main(["render", str(ROOT / "configs/spot_wall.yaml"), "--pixel", "24"])
    assert main(["render", str(ROOT / "configs/spot_wall.yaml"), *SMALL, "--pixel", "480,2"]) == 2
    assert "outside the 48x40 image" in capsys.readouterr().err


def test_progress_bar_estimate():
    from experiments.run.progress import ProgressBar

    class Out:
        text = ""

        def write(self, s):
            self.text += s

        def flush(self):
            pass

    out = Out()
    bar = ProgressBar(delay=0.0, stream=out)
    bar(16, 64)
    assert "25%" in out.text and "16/64 bins" in out.text and "left" in out.text
    quiet = Out()
    ProgressBar(delay=60.0, stream=quiet)(1, 2)  # short renders print nothing
    assert quiet.text == ""


SCRIPT = r"""
import signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)  # as at a terminal (see test_interrupt.py)
from experiments.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_with_progress_bar():
    args = [sys.executable, "-c", SCRIPT, "render", str(ROOT / "configs/spot_wall.yaml"),
            "--set", "camera.width=1024", "--set", "camera.height=1024", "--set", "samples.spp=256",
            "--set", "pipeline.algorithm=bruteforce", "--progress-delay", "0"]
    with subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                          env={**os.environ, "PYTHONUNBUFFERED": "1"}) as proc:
        def ready():
            line = proc.stderr.readline()
            assert "render [" in line and "bins" in line, line

        out, err, waited = interrupt(proc, ready)
    assert proc.returncode == 130, (out, err)
    assert "interrupted" in err
    assert waited < 5.0, f"took {waited:.1f} s to stop"

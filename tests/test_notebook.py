"""experiments/examples/quickstart.ipynb runs top to bottom (render, sweep, pandas, heatmap) in a fresh
kernel, with its own result store; its printed figures agree with a render made here."""
from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

pytestmark = pytest.mark.smoke

NOTEBOOK = Path(__file__).resolve().parents[1] / "experiments" / "examples" / "quickstart.ipynb"


def test_quickstart_notebook_runs(tmp_path, monkeypatch):
    import models
    import sim

    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 2  # the render and the heatmap
    assert "9 points, 9 ok" in text
    assert (tmp_path / "results" / "notebook_quickstart.parquet").exists()
    # the notebook's first render, repeated here
    scene = models.named("spot_wall")
    hint = {k: v for k, v in scene.camera_hint.items() if k not in ("width", "height")}
    result = sim.render(scene, sim.Camera(width=96, height=96, coc_px=10, **hint),
                        sim.SampleTable.stratified(spp=16, seed=1), sim.PipelineConfig(algorithm="tile"))
    tested = int(re.search(r"samples tested ([\d,]+)", text).group(1).replace(",", ""))
    assert tested == result.flat_stats["raster.samples_tested"] > 0
    assert os.environ["RAST5D_RESULTS"] == str(tmp_path / "results")

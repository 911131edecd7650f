"""The notebooks of experiments/examples/ run top to bottom in a fresh kernel (nbclient), each with its
own result store: no cell raises, and every cell that draws (plt/ax/fig calls, imshow, plot) shows a
picture, so a cell that silently draws nothing fails. The quickstart's printed figures agree with a
render made here the way the README shows it."""
from __future__ import annotations

import re
import time
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

pytestmark = pytest.mark.smoke

EXAMPLES = Path(__file__).resolve().parents[1] / "experiments" / "examples"
DRAWS = re.compile(r"\b(plt|ax|fig)\.\w+\(|\bimshow\(|\.plot\(")


def execute(name: str, tmp_path, monkeypatch):
    """The executed notebook and its CPU-free wall time (the kernel is a child process)."""
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    nb = nbformat.read(EXAMPLES / name, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    t0 = time.perf_counter()
    client.execute()
    print(f"{name}: executed in {time.perf_counter() - t0:.1f} s")
    return nb


def drawing_cells_without_pictures(nb) -> list[int]:
    """Indices of the code cells that call a drawing function but show no image."""
    bad = []
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code" or not DRAWS.search(cell.source):
            continue
        if not any("image/png" in o.get("data", {}) for o in cell.get("outputs", [])):
            bad.append(i)
    return bad


def errors(nb) -> list:
    return [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])
            if o.output_type == "error"]


def stream_text(nb) -> str:
    return "".join(o.get("text", "") for cell in nb.cells if cell.cell_type == "code"
                   for o in cell.get("outputs", []) if o.output_type == "stream")


def test_quickstart_notebook_runs_and_every_drawing_cell_draws(tmp_path, monkeypatch):
    import models
    import sim

    nb = execute("quickstart.ipynb", tmp_path, monkeypatch)
    assert not errors(nb)
    assert drawing_cells_without_pictures(nb) == []
    text = stream_text(nb)
    assert "9 points, 9 ok" in text
    assert (tmp_path / "results" / "notebook_quickstart.parquet").exists()
    # the notebook's first render, repeated here as the README shows it
    scene = models.named("spot_wall")
    result = sim.render(scene, sim.Camera.for_scene(scene, width=96, height=96, coc_px=10),
                        sim.SampleTable.stratified(spp=16, seed=1), sim.PipelineConfig(algorithm="tile"))
    tested = int(re.search(r"samples tested ([\d,]+)", text).group(1).replace(",", ""))
    assert tested == result.flat_stats["raster.samples_tested"] > 0


def test_hardware_notebook_retimes_without_rendering_and_draws(tmp_path, monkeypatch):
    nb = execute("hardware.ipynb", tmp_path, monkeypatch)
    assert not errors(nb)
    assert drawing_cells_without_pictures(nb) == []
    assert re.search(r"[\d,]+ work records; [\d,]+ cycles", stream_text(nb))


def test_a_drawing_cell_that_draws_nothing_is_caught(tmp_path, monkeypatch):
    """The check above fails on the old quickstart's mistake: a heatmap cell whose render had no
    per-pixel statistics, so it printed a message and drew nothing."""
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"display_name": "Python 3", "language": "python", "name": "python3"}
    nb.cells = [nbformat.v4.new_code_cell("import matplotlib.pyplot as plt\nstats = None\n"
                                          "if stats:\n    plt.imshow(stats)\nelse:\n    print('not available')")]
    path = tmp_path / "broken.ipynb"
    nbformat.write(nb, path)
    client = nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    assert not errors(nb) and drawing_cells_without_pictures(nb) == [0]

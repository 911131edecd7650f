"""Figures that need no decoding: labels from sim.counter_docs(), legend titles and sections, grid
shapes without empty cells, one colour per algorithm, paper values that cannot be drawn named in a
warning; and the `image` / `heatmap`-with-`map:` plot kinds of a report config."""
from __future__ import annotations

import warnings

import pandas as pd
import pytest

from experiments import config as xc
from experiments.report import figures, heatmaps


def _frame():
    return pd.DataFrame([{"camera.coc_px": x, "pipeline.algorithm": a, "ops.total": k * x * x, "status": "ok"}
                         for a, k in (("tile", 1), ("bruteforce", 2)) for x in (1, 2, 4, 8)])


def test_labels_come_from_counter_docs_and_config_names():
    assert figures.value_label("camera.coc_px") == "CoC radius [px]"
    assert figures.value_label("ops.total").endswith("[ops]") and "ops.total" not in figures.value_label("ops.total")
    assert figures.value_label("raster.ste").startswith("Sample-test efficiency")
    assert figures.value_label("my_derived") == "my_derived"
    assert figures.facet_title("camera.coc_px", 0) == "CoC radius 0 px"


@pytest.mark.parametrize("n, shape", [(1, (1, 1)), (3, (1, 3)), (4, (1, 4)), (6, (2, 3)), (8, (2, 4)), (9, (3, 3)), (10, (5, 2))])
def test_grid_shapes_have_no_empty_cells(n, shape):
    assert figures.grid_shape(n) == shape


def test_one_colour_per_algorithm_on_every_page():
    assert figures.color_for("tile", 0) == figures.color_for("tile", 5) == figures.ALGORITHM_COLORS["tile"]
    assert len(set(figures.ALGORITHM_COLORS.values())) == len(figures.ALGORITHM_COLORS)


def test_legend_has_a_title_and_unmatched_paper_values_warn(tmp_path):
    import matplotlib.pyplot as plt

    spec = xc.PlotSpec(kind="line", x="camera.coc_px", y="ops.total", hue="pipeline.algorithm",
                       paper={"tile": {1: 1.5, 8: 60}, "StoneGiant": {2: 5.0}})
    captured = {}
    real = plt.Figure.savefig

    def spy(fig, *a, **k):
        leg = fig.axes[0].get_legend()
        captured["title"] = leg.get_title().get_text()
        captured["labels"] = [t.get_text() for t in leg.get_texts()]
        return real(fig, *a, **k)

    plt.Figure.savefig = spy
    try:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            figures.render_plot(spec, _frame(), tmp_path / "f")
    finally:
        plt.Figure.savefig = real
    assert captured["title"] == "algorithm"
    assert "measured:" in captured["labels"] and "paper:" in captured["labels"]
    assert "StoneGiant (paper)" in captured["labels"]  # a paper curve with no series of ours is still drawn
    assert not w
    bar = xc.PlotSpec(kind="bar", x="camera.coc_px", y="ops.total", hue="pipeline.algorithm",
                      paper={"StoneGiant": {2: 5.0}})
    with pytest.warns(UserWarning, match="paper values not drawn: StoneGiant"):
        figures.render_plot(bar, _frame(), tmp_path / "b")


def test_image_and_map_specs_validate():
    xc.PlotSpec(kind="image", where={"scene.name": "x"})
    xc.PlotSpec(kind="heatmap", map="tile.cull_reason")
    with pytest.raises(ValueError, match="map: only for heatmap"):
        xc.PlotSpec(kind="line", x="a", y="b", map="ops.total")
    with pytest.raises(ValueError, match="needs y"):
        xc.PlotSpec(kind="line", x="a")


def test_point_pictures_of_a_config(tmp_path):
    cfg = xc.validate({"name": "pics", "scene": {"name": "motion_field", "params": {"motion_px": 4}},
                       "camera": {"width": 48, "height": 40, "coc_px": 4}, "samples": {"kind": "stratified", "spp": 4},
                       "pipeline": {"algorithm": "tile"}, "sweep": {"camera.coc_px": [0, 8]}}, "pics")
    rows = pd.DataFrame([{"camera.coc_px": c, "config_hash": xc.config_hash(pc), "status": "ok"}
                         for (_, pc), c in zip(xc.expand_sweep(cfg), (0, 8))])
    for spec in (xc.PlotSpec(kind="image", facet="camera.coc_px"),
                 xc.PlotSpec(kind="heatmap", map="raster.samples_tested", facet="camera.coc_px"),
                 xc.PlotSpec(kind="heatmap", map="tile.cull_reason", facet="camera.coc_px")):
        res = heatmaps.point_pictures(spec, cfg, rows, tmp_path / spec.kind)
        assert res["files"][0].exists() and len(res["markdown"]) == 4
    from experiments.report.frames import PlotError

    with pytest.raises(PlotError, match="leaves 2 points"):
        heatmaps.point_pictures(xc.PlotSpec(kind="image"), cfg, rows, None)


def test_scatters_of_the_same_rows_share_one_data_table(tmp_path):
    from pathlib import Path

    from experiments.report import pages

    df = _frame().assign(**{"raster.samples_tested": lambda d: d["ops.total"] * 3, "time.wall_s": 1.0})
    plots = [{"kind": "scatter", "x": x, "y": "camera.coc_px", "hue": "pipeline.algorithm"}
             for x in ("ops.total", "raster.samples_tested")]
    cfg = xc.validate({"name": "s", "scene": {"name": "spot_wall"},
                       "outputs": {"page": "s", "plots": plots}}, "s")
    text = "\n".join(pages.section_markdown(cfg, Path("nowhere.yaml"), df, tmp_path, "cmd"))
    assert text.count("<summary>data</summary>") == 1
    assert "Data: the table under figure 1 of this section (column `raster.samples_tested`)" in text
    head = next(line for line in text.splitlines() if line.startswith("| pipeline.algorithm"))
    assert "ops.total" in head and "raster.samples_tested" in head


def test_derived_and_combined_columns_are_labelled():
    assert figures.value_label("quad_ratio", {"quad_ratio": "shade.quad_requests / depth.passes"}) == \
        "quad_ratio = shade.quad_requests / depth.passes"
    assert figures.value_label("samples.kind / samples.n_lens") == "sample table / lens positions"

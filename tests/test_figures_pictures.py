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
    assert figures.value_label("my_derived") == "my derived"  # in words, never the column's code
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


def test_point_pictures_of_a_config(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
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
    # a derived expression is never shown: its name in words, or its declared label (column_labels)
    assert figures.value_label("quad_ratio", {"quad_ratio": "shade.quad_requests / depth.passes"}) == "quad ratio"
    with figures.column_labels({"quad_ratio": "quad requests per depth pass (ratio)"}):
        assert figures.value_label("quad_ratio", {"quad_ratio": "shade.quad_requests / depth.passes"}) == \
            "quad requests per depth pass (ratio)"
    assert figures.value_label("samples.kind / samples.n_lens") == "sample table / lens positions"


def _pictured_config():
    plots = [{"kind": "image", "facet": "camera.coc_px"},
             {"kind": "heatmap", "map": "raster.samples_tested", "where": {"camera.coc_px": 8}},
             {"kind": "heatmap", "map": "tile.cull_reason", "facet": "camera.coc_px"},
             {"kind": "heatmap", "map": "ops.total", "where": {"big": True}},  # a derived column of a result
             {"kind": "line", "x": "camera.coc_px", "y": "ops.total"}]
    return xc.validate({"name": "pics", "scene": {"name": "motion_field", "params": {"motion_px": 4}},
                        "camera": {"width": 48, "height": 40, "coc_px": 4}, "samples": {"kind": "stratified", "spp": 4},
                        "pipeline": {"algorithm": "tile"}, "sweep": {"camera.coc_px": [0, 8]},
                        "outputs": {"page": "pics", "derived": {"big": "ops.total > 0"}, "plots": plots}}, "pics")


def test_stored_pictures_equal_a_fresh_render_and_a_stale_one_is_not_served(tmp_path, monkeypatch):
    """The pictures a page draws are kept by the render of the sweep point (run_point with pictures)
    and read back by the page: equal to sim.render of the same point (pixel_stats=True, another
    thread count); a picture of another engine version, of a changed input or a corrupt file is not
    served, and the page renders the point again."""
    import numpy as np

    import sim
    from experiments.run import points, store
    from experiments.run.runner import hashed_sweep

    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    cfg = _pictured_config()
    swept = [(h, pc) for _, pc, h in hashed_sweep(cfg)]
    (h0, c0), (h8, c8) = swept
    wanted = heatmaps.pictured_points(cfg, swept)
    # the where: on a result column picks nothing before the render
    assert wanted == {h0: {"image", "tile.cull_reason"}, h8: {"image", "tile.cull_reason", "raster.samples_tested"}}
    for h, pc in swept:
        row = points.run_point(pc.model_dump_json(), None, 1, None, tuple(sorted(wanted[h])))
        assert row["status"] == "ok"
        plain = points.run_point(pc.model_dump_json(), None, 1)  # the row does not depend on the pictures
        assert {k: v for k, v in row.items() if k != "time.wall_s"} == \
            {k: v for k, v in plain.items() if k != "time.wall_s"}
    scene, camera, table, pipeline = xc.build(c8)
    fresh = sim.render(scene, camera, table, pipeline.replace(threads=2), hardware=c8.hardware_config(),
                       timing=False, pixel_stats=True)
    kept = store.cached_pictures(h8)
    assert np.array_equal(kept["image"], fresh.image)
    names = {k[4:] for k in kept if k.startswith("map:")}
    assert names == {"raster.samples_tested", *sim.pixel_stats.TILE_VERDICTS}
    for n in names:
        assert kept[f"map:{n}"].dtype == fresh.pixel_stats[n].dtype
        assert np.array_equal(kept[f"map:{n}"], fresh.pixel_stats[n])
    # the page reads them: no render
    rows = pd.DataFrame([{"camera.coc_px": c, "config_hash": h, "status": "ok"} for (h, _), c in zip(swept, (0, 8))])
    renders = []
    real = points.render_point
    monkeypatch.setattr(points, "render_point", lambda *a, **k: renders.append(a) or real(*a, **k))
    import experiments.run as run_pkg

    monkeypatch.setattr(run_pkg, "render_point", points.render_point)
    specs = [xc.PlotSpec(**p) for p in cfg.outputs.model_dump()["plots"][:3]]
    from_store = [heatmaps.point_pictures(sp, cfg, rows if sp.facet else rows[rows["camera.coc_px"] == 8],
                                          tmp_path / f"s{i}")["markdown"] for i, sp in enumerate(specs)]
    assert renders == []
    # stale: another engine version serves nothing; the page renders again and gives the same tables
    monkeypatch.setattr(store, "_ENGINE_ID", "0123456789ab")
    assert store.cached_pictures(h8) is None
    again = [heatmaps.point_pictures(sp, cfg, rows if sp.facet else rows[rows["camera.coc_px"] == 8],
                                     tmp_path / f"r{i}")["markdown"] for i, sp in enumerate(specs)]
    assert len(renders) == 5 and again == from_store
    # a corrupt file is not served (a StoreWarning says so)
    path = store.pictures_path(h8)
    path.write_bytes(path.read_bytes()[:100])
    with pytest.warns(store.StoreWarning, match="unreadable"):
        assert store.cached_pictures(h8) is None


def test_stored_pictures_follow_their_input_files(tmp_path, monkeypatch):
    """A picture is served only while the files its point read are unchanged."""
    import numpy as np

    from experiments.run import store

    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\n")
    from experiments.config.inputs import input_digests
    import json

    store.store_pictures("00aa", {"image": np.ones((2, 2, 3), np.float32)}, json.dumps(input_digests([mesh])))
    assert np.array_equal(store.cached_pictures("00aa")["image"], np.ones((2, 2, 3), np.float32))
    mesh.write_text("v 0 0 1\n")
    assert store.cached_pictures("00aa") is None

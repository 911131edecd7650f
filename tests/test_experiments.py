"""Experiments: config schema errors (file:line), extends, overrides, sweep expansion with and without
zip, the Parquet result store and its cache, failure isolation, Dask == local pool, the point kinds
against direct sim calls, plots (heatmap and image grid included) and the report (--quick on a tiny
config set)."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest

from experiments import config as xc
from experiments.report import figures, frames, pages
from experiments.run import points, runner, store as result_store

pytestmark = pytest.mark.smoke

BASE = """\
scene: {name: quad}
camera: {width: 24, height: 24, coc_px: 4}
samples: {spp: 4, seed: 1}
pipeline: {algorithm: tile}
"""


@pytest.fixture
def store(tmp_path, monkeypatch):
    """A private result store (worker processes inherit the environment)."""
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    return tmp_path / "results"


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


# ---- schema --------------------------------------------------------------------------------------

def test_unknown_key_names_key_file_and_line(tmp_path):
    p = write(tmp_path, "c.yaml", "scene: {name: quad}\ncamera:\n  width: 24\n  heigth: 24\n")
    with pytest.raises(xc.ConfigError, match=r"c\.yaml:4: unknown key 'camera\.heigth'"):
        xc.load_config(p)
    p = write(tmp_path, "d.yaml", "scene: {name: quad}\nhardware:\n  tex_cache:\n    size_bytes: 4096\n    wayz: 2\n")
    with pytest.raises(xc.ConfigError, match=r"d\.yaml:5: unknown key 'hardware\.tex_cache\.wayz'"):
        xc.load_config(p)
    p = write(tmp_path, "e.yaml", "scene: {name: quad}\noutputs:\n  plots:\n    - {kind: line, x: a, y: b}\n"
                                  "    - {kind: line, x: a, y: b, colour: red}\n")
    with pytest.raises(xc.ConfigError, match=r"e\.yaml:5: unknown key 'outputs\.plots\.1\.colour'"):
        xc.load_config(p)
    p = write(tmp_path, "f.yaml", "scene: {name: quad}\nsweeps: {camera.coc_px: [1]}\n")
    with pytest.raises(xc.ConfigError, match=r"f\.yaml:2: unknown key 'sweeps'"):
        xc.load_config(p)


def test_wrong_types_and_values_name_the_field(tmp_path):
    p = write(tmp_path, "c.yaml", BASE.replace("spp: 4", "spp: many"))
    with pytest.raises(xc.ConfigError, match=r"c\.yaml:3: samples\.spp: .*integer.*'many'"):
        xc.load_config(p)
    p = write(tmp_path, "c.yaml", BASE.replace("kind", "x").replace("spp: 4", "kind: halton, spp: 4"))
    with pytest.raises(xc.ConfigError, match=r"samples\.kind.*'halton'"):
        xc.load_config(p)
    p = write(tmp_path, "c.yaml", BASE + "hardware: {tex_cache: {line_bytes: 48}}\n")
    with pytest.raises(xc.ConfigError, match=r"c\.yaml:5: hardware: .*line_bytes.*power of two.*48"):
        xc.load_config(p)
    p = write(tmp_path, "c.yaml", BASE + "executor: {kind: dask}\n")
    with pytest.raises(xc.ConfigError, match="executor.*address"):
        xc.load_config(p)
    with pytest.raises(xc.ConfigError, match=r"--set camera\.coc_px=big: camera\.coc_px"):
        xc.load_config(write(tmp_path, "c.yaml", BASE), ["camera.coc_px=big"])


def test_extends_deep_merges_recursively_and_rejects_cycles_and_missing_bases(tmp_path):
    write(tmp_path, "base.yaml", BASE + "hardware: {tex_cache: {ways: 8}}\n")
    (tmp_path / "sub").mkdir()
    write(tmp_path, "sub/mid.yaml", "extends: ../base.yaml\ncamera: {coc_px: 9}\nhardware: {tex_cache: {count: 2}}\n")
    leaf = write(tmp_path, "sub/leaf.yaml", "extends: mid.yaml\nsamples: {spp: 8}\n")
    c = xc.load_config(leaf, ["hardware.setup.latency_cycles=3"])
    assert c.name == "leaf"  # names are not inherited
    assert (c.camera.width, c.camera.coc_px, c.samples.spp, c.samples.seed) == (24, 9, 8, 1)
    hw = c.hardware_config()
    assert (hw.tex_cache.ways, hw.tex_cache.count, hw.setup.latency_cycles) == (8, 2, 3)
    assert hw.setup.throughput == 1.0  # untouched keys keep sim.HardwareConfig's defaults

    write(tmp_path, "a.yaml", "extends: b.yaml\nscene: {name: quad}\n")
    write(tmp_path, "b.yaml", "extends: a.yaml\n")
    with pytest.raises(xc.ConfigError, match=r"extends: cycle .*a\.yaml -> .*b\.yaml -> .*a\.yaml"):
        xc.load_config(tmp_path / "a.yaml")
    p = write(tmp_path, "m.yaml", "scene: {name: quad}\nextends: nowhere.yaml\n")
    with pytest.raises(xc.ConfigError, match=r"m\.yaml:2: extends: base config 'nowhere\.yaml' not found"):
        xc.load_config(p)
    p = write(tmp_path, "n.yaml", "extends: base.yaml\ncamera: {zoom: 2}\n")
    with pytest.raises(xc.ConfigError, match=r"n\.yaml:2: unknown key 'camera\.zoom'"):
        xc.load_config(p)
    p = write(tmp_path, "o.yaml", "extends: base.yaml\ncamera: {width: wide}\n")
    with pytest.raises(xc.ConfigError, match=r"o\.yaml:2: camera\.width"):
        xc.load_config(p)


# ---- sweeps --------------------------------------------------------------------------------------

def test_sweep_cartesian_product_in_file_order():
    pts = xc.sweep_points({"a": [1, 2], "b": ["x", "y", "z"]})
    assert pts == [{"a": a, "b": b} for a in (1, 2) for b in ("x", "y", "z")]
    assert xc.sweep_points({}) == [{}]


def test_sweep_zip_groups_vary_together():
    sweep = {"a": [1, 2, 3], "k": ["p", "q"], "b": [10, 20, 30], "zip": [["a", "b"]]}
    pts = xc.sweep_points(sweep)
    expected = [{"a": a, "b": b, "k": k} for a, b in ((1, 10), (2, 20), (3, 30)) for k in ("p", "q")]
    assert pts == expected


@pytest.mark.parametrize("sweep,message", [
    ("camera.coc_px: [0, 4]\n  samples.spp: [4]\n  zip: [[camera.coc_px, samples.spp]]", "equal lengths"),
    ("camera.coc_px: [0, 4]\n  zip: [[camera.coc_px, samples.spp]]", "'samples.spp' is not a swept key"),
    ("camera.coc_px: 4", "expected a non-empty list"),
    ("camera.cocpx: [1, 2]", "unknown key 'camera.cocpx'"),
])
def test_bad_sweeps_are_errors(tmp_path, sweep, message):
    p = write(tmp_path, "c.yaml", BASE + "sweep:\n  " + sweep + "\n")
    with pytest.raises(xc.ConfigError, match=message.replace(".", r"\.").replace("[", r"\[")):
        xc.load_config(p)


def test_expand_sweep_sets_whole_sections_and_dotted_keys(tmp_path):
    p = write(tmp_path, "c.yaml", BASE + "sweep:\n  scene: [{name: quad}, {name: single_triangle}]\n"
                                         "  samples.kind: [random, interleaved]\n  samples.n_lens: [null, 64]\n"
                                         "  zip: [[samples.kind, samples.n_lens]]\n")
    pts = xc.expand_sweep(xc.load_config(p))
    got = [(c.scene.name, c.samples.kind, c.samples.n_lens) for _, c in pts]
    assert got == [("quad", "random", None), ("quad", "interleaved", 64),
                   ("single_triangle", "random", None), ("single_triangle", "interleaved", 64)]
    assert len({xc.config_hash(c) for _, c in pts}) == 4


def test_config_hash_ignores_threads_and_presentation_but_not_hardware(tmp_path):
    p = write(tmp_path, "c.yaml", BASE)
    h = xc.config_hash(xc.load_config(p))
    assert xc.config_hash(xc.load_config(p, ["pipeline.threads=1", "outputs.title=x", "name=y"])) == h
    assert xc.config_hash(xc.load_config(p, ["hardware.clock_ghz=2"])) != h
    assert xc.config_hash(xc.load_config(p, ["camera.coc_px=5"])) != h


# ---- store, cache, failures, executors -----------------------------------------------------------

SWEEP = BASE + "sweep:\n  camera.coc_px: [0, 6]\n  pipeline.algorithm: [bruteforce, tile]\n"


def test_second_run_computes_zero_points_and_force_recomputes(tmp_path, store):
    c = xc.load_config(write(tmp_path, "s.yaml", SWEEP))
    df1 = runner.run_sweep(c, workers=2, progress=False)
    assert df1.attrs["summary"]["rendered"] == 4 and (df1["status"] == "ok").all()
    df2 = runner.run_sweep(c, workers=2, progress=False)
    assert df2.attrs["summary"] == {**df2.attrs["summary"], "rendered": 0, "cached": 4}
    assert df2["raster.samples_tested"].tolist() == df1["raster.samples_tested"].tolist()
    loaded = result_store.load("s")
    assert len(loaded) == 4 and list(loaded["pipeline.algorithm"]) == ["bruteforce", "tile"] * 2
    for col in ("camera.coc_px", "camera.width", "samples.kind", "hardware.tex_cache.size_bytes", "ops.total",
                "time.wall_s", "engine.version", "engine.git_rev", "config_hash"):
        assert col in loaded.columns, col
    assert loaded["camera.width"].tolist() == [24] * 4
    # Counters against an independent count: bruteforce tests every sample of every covered pixel's
    # candidates, so it tests at least as many samples as tile (tile is conservative but culls).
    bf = loaded[loaded["pipeline.algorithm"] == "bruteforce"]["raster.samples_tested"].to_numpy()
    tl = loaded[loaded["pipeline.algorithm"] == "tile"]["raster.samples_tested"].to_numpy()
    assert (bf >= tl).all()
    df3 = runner.run_sweep(c, workers=0, force=True, progress=False)
    assert df3.attrs["summary"]["rendered"] == 4
    # A changed point renders alone.
    c2 = xc.load_config(write(tmp_path, "s.yaml", SWEEP.replace("[0, 6]", "[0, 6, 9]")))
    assert runner.run_sweep(c2, workers=0, progress=False).attrs["summary"]["rendered"] == 2


def test_a_failing_point_is_recorded_and_the_others_finish(tmp_path, store):
    # a scene parameter's value is checked only when the scene is built, i.e. at the point's render
    c = xc.load_config(write(tmp_path, "f.yaml", BASE + "sweep:\n  scene.params.size: [1.0, -1.0, 2.0]\n"))
    df = runner.run_sweep(c, workers=2, progress=False)
    assert df["status"].tolist() == ["ok", "error", "ok"]
    assert "size" in df["error"].iloc[1] and df["scene.params.size"].tolist() == [1.0, -1.0, 2.0]
    assert df.attrs["summary"]["failed"] == 1
    # Failed points are stored with their error: a rerun serves them, --retry-failed retries only them.
    assert runner.run_sweep(c, workers=0, progress=False).attrs["summary"]["rendered"] == 0
    assert runner.run_sweep(c, workers=0, progress=False, retry_failed=True).attrs["summary"]["rendered"] == 1


@pytest.mark.filterwarnings("ignore::DeprecationWarning", "ignore::ResourceWarning",
                            "ignore::pytest.PytestUnraisableExceptionWarning")
def test_dask_local_cluster_gives_the_same_rows_as_the_local_pool(tmp_path, store):
    distributed = pytest.importorskip("distributed")
    c = xc.load_config(write(tmp_path, "d.yaml", SWEEP))
    local = runner.run_sweep(c, workers=2, progress=False, force=True)
    # the dashboard on any free port: another cluster on this machine may hold the default 8787
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0") as cl:
        remote = runner.run_sweep(c, scheduler=cl.scheduler_address, progress=False, force=True)
        # The same through the config's executor section.
        via_config = xc.load_config(tmp_path / "d.yaml", ["executor.kind=dask", f"executor.address={cl.scheduler_address}"])
        again = runner.run_sweep(via_config, progress=False, force=True)
    assert remote.attrs["summary"]["rendered"] == 4 and again.attrs["summary"]["rendered"] == 4
    counters = [k for k in local.columns if k.split(".")[0] in ("raster", "ops", "tile", "setup", "bin")]
    assert len(counters) > 10
    pd.testing.assert_frame_equal(local[counters + ["config_hash"]], remote[counters + ["config_hash"]])
    pd.testing.assert_frame_equal(local[counters + ["config_hash"]], again[counters + ["config_hash"]])


def test_ctrl_c_stops_and_keeps_the_finished_points(tmp_path):
    env = {**os.environ, "RAST5D_RESULTS": str(tmp_path / "results")}
    cfg = write(tmp_path, "slow.yaml", BASE.replace("width: 24, height: 24", "width: 256, height: 256")
                + "sweep:\n  samples.spp: [1, 2, 4096, 4096, 4096, 4096]\n  samples.seed: [1, 2]\n")
    # SIGINT as at a terminal: a suite started in the background by a non-interactive shell hands its
    # children SIGINT ignored, and the sweep would then run to its end (see test_interrupt.py).
    proc = subprocess.Popen([sys.executable, "-m", "experiments.cli", "run", str(cfg), "--workers", "1"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    points = tmp_path / "results" / "points"
    # Generous waits: on a loaded machine the interpreter start and the first two points can take
    # minutes; what is tested is the state after the signal, not how fast it comes.
    deadline = time.time() + 600
    while time.time() < deadline and len(list(points.glob("*.parquet"))) < 2 and proc.poll() is None:
        time.sleep(0.1)
    assert proc.poll() is None, f"the sweep ended before the signal: {proc.communicate()}"
    assert len(list(points.glob("*.parquet"))) >= 2, "no two points finished within 600 s"
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 130, err
    df = pd.read_parquet(tmp_path / "results" / "slow.parquet")
    assert 2 <= len(df) < 12 and (df["status"] == "ok").all()
    assert "Traceback" not in err


# ---- plots ---------------------------------------------------------------------------------------

def _frame():
    rows = []
    for algo, k in (("a", 1.0), ("b", 2.0)):
        for x in (1, 2, 4, 8):
            rows.append({"pipeline.algorithm": algo, "camera.coc_px": float(x), "ops.total": k * x ** 2,
                         "raster.samples_hit": 2.0 * x, "scene.name": "s", "status": "ok"})
    return pd.DataFrame(rows)


def test_derived_columns_accept_dotted_names():
    df = frames.apply_derived(_frame(), {"per_hit": "ops.total / raster.samples_hit", "twice": "2 * per_hit"})
    np.testing.assert_allclose(df["twice"], 2 * df["ops.total"] / df["raster.samples_hit"])
    with pytest.raises(frames.PlotError, match="derived 'bad'.*no_such"):
        frames.apply_derived(_frame(), {"bad": "no_such.column + 1"})


def test_plot_kinds_write_png_pdf_and_tables_with_paper_values(tmp_path):
    df = _frame()
    spec = xc.PlotSpec(kind="line", x="camera.coc_px", y="ops.total", hue="pipeline.algorithm", logy=True,
                       paper={"b": {1: 2.5, 8: "130"}})
    res = figures.render_plot(spec, df, tmp_path / "line")
    assert [p.suffix for p in res["files"]] == [".png", ".pdf"]
    assert res["files"][0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and res["files"][1].read_bytes()[:4] == b"%PDF"
    table = "\n".join(res["markdown"])
    assert "| camera.coc_px | a | b | b (paper) |" in table
    assert "| 8 | 64 | 128 | 130 |" in table and "| 1 | 1 | 2 | 2.5 |" in table
    for kind in ("bar", "scatter"):
        spec = xc.PlotSpec(kind=kind, x="camera.coc_px", y="ops.total", hue="pipeline.algorithm", pareto=kind == "scatter")
        assert figures.render_plot(spec, df, tmp_path / kind)["files"][0].exists()
    spec = xc.PlotSpec(kind="bar", x="pipeline.algorithm", y=["ops.total", "raster.samples_hit"], stacked=True,
                       where={"camera.coc_px": 2})
    assert figures.render_plot(spec, df, tmp_path / "stacked")["files"]
    spec = xc.PlotSpec(kind="table", x="camera.coc_px", y="ops.total", where={"pipeline.algorithm": ["b"]})
    assert "| 4 | 32 |" in "\n".join(figures.render_plot(spec, df, None)["markdown"])
    with pytest.raises(frames.PlotError, match="unknown column 'ops.totl'"):
        figures.render_plot(xc.PlotSpec(kind="line", x="camera.coc_px", y="ops.totl"), df, None)


def test_pareto_front_against_brute_force():
    rng = np.random.default_rng(3)
    x, y = rng.random(60), rng.random(60)
    front = set(frames.pareto_front(x, y).tolist())
    brute = {i for i in range(60) if not any((x[j] <= x[i] and y[j] < y[i]) or (x[j] < x[i] and y[j] <= y[i])
                                             for j in range(60))}
    assert front == brute


def test_powerlaw_fit_recovers_known_exponents():
    rows = [{"samples.spp": s, "metric.rmse": 0.3 * s ** -a, "samples.kind": k}
            for k, a in (("random", 0.5), ("sobol", 0.75)) for s in (1, 2, 4, 8, 16)]
    spec = xc.PlotSpec(kind="table", x="samples.spp", y="metric.rmse", hue="samples.kind", fit="powerlaw")
    res = figures.render_plot(spec, pd.DataFrame(rows), None)
    alphas = {f["hue"]: f["alpha"] for f in res["fits"]}
    assert alphas["random"] == pytest.approx(0.5) and alphas["sobol"] == pytest.approx(0.75)


def test_heatmap_cells_and_table_match_the_frame(tmp_path):
    df = _frame()
    spec = xc.PlotSpec(kind="heatmap", x="camera.coc_px", row="pipeline.algorithm", y="ops.total", format="{:g}")
    res = figures.render_plot(spec, df, tmp_path / "heat")
    assert [p.suffix for p in res["files"]] == [".png", ".pdf"]
    table = "\n".join(res["markdown"])
    # independent pivot: ops.total = k x^2 with k = 1 (a), 2 (b)
    assert "| pipeline.algorithm \\ camera.coc_px | 1 | 2 | 4 | 8 |" in table
    assert "| a | 1 | 4 | 16 | 64 |" in table and "| b | 2 | 8 | 32 | 128 |" in table
    with pytest.raises(ValueError, match="needs x and row"):
        xc.PlotSpec(kind="heatmap", x="camera.coc_px", y="ops.total")


def test_image_grid_places_each_points_image(tmp_path):
    from PIL import Image

    rows = []
    for spp in (1, 4):
        for coc in (0.0, 5.0):
            path = tmp_path / f"img_{spp}_{coc:g}.png"
            Image.new("RGB", (8, 8), (int(40 * spp), int(10 * coc), 0)).save(path)
            rows.append({"samples.spp": spp, "camera.coc_px": coc, "metric.rmse": spp * 0.01 + coc,
                         "image.path": str(path), "status": "ok"})
    spec = xc.PlotSpec(kind="image_grid", x="camera.coc_px", row="samples.spp", y="metric.rmse", format="{:.2f}")
    res = figures.render_plot(spec, pd.DataFrame(rows), tmp_path / "grid")
    assert res["files"][0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "| 4 | 0.04 | 5.04 |" in "\n".join(res["markdown"])
    with pytest.raises(frames.PlotError, match="outputs.images"):
        figures.render_plot(spec, pd.DataFrame(rows).drop(columns=["image.path"]), None)


# ---- point kinds ---------------------------------------------------------------------------------

def test_occlusion_query_point_is_sim_occlusion_query(tmp_path, store):
    import models
    import sim

    text = ("scene: {name: quad, params: {size: 8, depth: 2}}\ncamera: {width: 24, height: 24, coc_px: 3}\n"
            "samples: {spp: 4, seed: 1}\npipeline: {algorithm: tile}\n"
            "point: {kind: occlusion_query, query: {name: quad, params: {size: 1, depth: 5}}}\n"
            "sweep:\n  point.mode: [samples, intervals]\n  point.query:\n"
            "    - {name: quad, params: {size: 1, depth: 5}}\n    - {name: quad, params: {size: 1, depth: 1}}\n")
    df = runner.run_sweep(xc.load_config(write(tmp_path, "o.yaml", text)), workers=0, progress=False)
    assert (df["status"] == "ok").all(), df["error"].tolist()
    occ = models.named("quad", size=8, depth=2)
    cam = sim.Camera(width=24, height=24, fov_y_deg=45.0, focus_distance=2.0, coc_px=3)
    table = sim.SampleTable.create("stratified", spp=4, seed=1)
    for _, row in df.iterrows():
        q = models.named("quad", size=1, depth=row["point.query.params.depth"])
        r = sim.occlusion_query(occ, q, cam, table, sim.PipelineConfig(algorithm="tile"), mode=row["point.mode"])
        assert bool(row["query.visible"]) == r.visible
        assert row["query.visible"] == (row["point.query.params.depth"] == 1)  # behind the occluder: hidden
        for k in ("raster.samples_tested", "occlusion.pairs_tested", "depth.bytes_read"):
            assert row[k] == r.work[k], k


def test_conservative_point_is_sim_conservative_raster(tmp_path, store):
    import models
    import sim

    text = BASE + "point: {kind: conservative}\n"
    df = runner.run_sweep(xc.load_config(write(tmp_path, "c.yaml", text)), workers=0, progress=False)
    assert (df["status"] == "ok").all(), df["error"].tolist()
    scene = models.named("quad")
    hint = scene.camera_hint
    cam = sim.Camera(width=24, height=24, fov_y_deg=hint["fov_y_deg"], focus_distance=hint["focus_distance"],
                     coc_px=4)
    r = sim.conservative_raster(scene, cam, sim.PipelineConfig(algorithm="tile"), reduce="tz_box")
    assert df["conservative.pixels_covered"].iloc[0] == int((r.count > 0).sum()) > 0
    for k, v in r.flat_stats.items():
        if isinstance(v, int) and not isinstance(v, bool):
            assert df[k].iloc[0] == v, k


def test_retime_point_is_timing_estimate_on_one_stored_render(tmp_path, store):
    import models
    import sim

    text = (BASE.replace("quad}", "quad, params: {translation_t1: [0.2, 0, 0]}}") + "point: {kind: retime}\n"
            "sweep:\n  point.hardware: [{}, {dram: {bytes_per_clock: 4}}, {sample_test: {throughput: 1}}]\n")
    df = runner.run_sweep(xc.load_config(write(tmp_path, "r.yaml", text)), workers=2, progress=False)
    assert (df["status"] == "ok").all(), df["error"].tolist()
    assert len(list((store / "records").glob("*.npz"))) == 1  # one render for the three variants
    scene = models.named("quad", translation_t1=[0.2, 0, 0])
    hint = scene.camera_hint
    cam = sim.Camera(width=24, height=24, fov_y_deg=hint["fov_y_deg"], focus_distance=hint["focus_distance"],
                     coc_px=4)
    res = sim.render(scene, cam, sim.SampleTable.create("stratified", spp=4, seed=1),
                     sim.PipelineConfig(algorithm="tile"), keep_timing_records=True)
    variants = [sim.HardwareConfig(), sim.HardwareConfig(dram={"bytes_per_clock": 4.0}),
                sim.HardwareConfig.from_dict({"sample_test": {"throughput": 1.0}})]
    expected = [sim.timing.estimate(res.timing_records, hw)["timing.cycles"] for hw in variants]
    assert df["timing.cycles"].tolist() == pytest.approx(expected)
    assert expected[0] == pytest.approx(res.flat_stats["timing.cycles"])  # re-timing changes nothing by itself
    assert expected[1] > expected[0] and expected[2] > expected[0]
    assert df["raster.samples_tested"].tolist() == [res.flat_stats["raster.samples_tested"]] * 3
    with pytest.raises(xc.ConfigError, match="point.hardware: only for kind 'retime'"):
        xc.load_config(write(tmp_path, "bad.yaml", BASE + "point: {hardware: {cores: 2}}\n"))


def test_retime_points_read_their_records_file_once_per_process(tmp_path, store, monkeypatch):
    """Re-timing one render at several hardware points in one process reads its records file once (the
    process keeps what it read while the file keeps its identity); a file rewritten since is read again,
    and a damaged one is a StoreWarning and a render again, not the kept records."""
    import numpy as np

    from experiments.run import store as result_store

    text = (BASE.replace("quad}", "quad, params: {translation_t1: [0.2, 0, 0]}}") + "point: {kind: retime}\n"
            "sweep:\n  point.hardware: [{}, {dram: {bytes_per_clock: 4}}, {sample_test: {throughput: 1}}, "
            "{cores: 2}]\n")
    cfg = xc.load_config(write(tmp_path, "r.yaml", text))
    loads = []
    real_load = np.load
    monkeypatch.setattr(np, "load", lambda *a, **k: loads.append(a[0].name) or real_load(*a, **k))
    first = runner.run_sweep(cfg, workers=0, progress=False)
    assert (first["status"] == "ok").all(), first["error"].tolist()
    assert loads == []  # the render that stored them handed its records on
    result_store._RECORDS.clear()
    again = runner.run_sweep(cfg, workers=0, progress=False, force=True)
    (records,) = list((store / "records").glob("*.npz"))
    assert again["timing.cycles"].tolist() == first["timing.cycles"].tolist()
    assert loads == [str(records)]  # four points re-timed, one read
    h = records.name.split("-")[0]
    for _ in range(3):
        assert result_store.cached_records(h) is not None
    assert len(loads) == 1
    records.write_bytes(records.read_bytes()[:-100])  # damaged: another size, read again and refused
    with pytest.warns(result_store.StoreWarning, match="unreadable"):
        assert result_store.cached_records(h) is None
    assert len(loads) == 2


def test_retime_of_a_render_time_key_renders_that_hardware(tmp_path, store):
    """A retime variant of a cache size (a render-time key: sim.timing.split_hardware) is its own render:
    its row equals a render with that cache, not the re-timed records of the default cache (which kept
    the default cache's misses and DRAM bytes). Variants of timing keys only share one render."""
    import models
    import sim

    text = (BASE.replace("quad}", "quad, params: {translation_t1: [0.2, 0, 0]}}") + "point: {kind: retime}\n"
            "sweep:\n  point.hardware: [{}, {dram: {bytes_per_clock: 8}}, {depth_buffer: {cache_bytes: 4096, "
            "line_bytes: 1024}, dram: {bytes_per_clock: 8}}]\n")
    df = runner.run_sweep(xc.load_config(write(tmp_path, "r.yaml", text)), workers=0, progress=False)
    assert (df["status"] == "ok").all(), df["error"].tolist()
    assert len(list((store / "records").glob("*.npz"))) == 2  # the default render and the small-cache one
    scene = models.named("quad", translation_t1=[0.2, 0, 0])
    hint = scene.camera_hint
    cam = sim.Camera(width=24, height=24, fov_y_deg=hint["fov_y_deg"], focus_distance=hint["focus_distance"],
                     coc_px=4)
    table = sim.SampleTable.create("stratified", spp=4, seed=1)
    small = sim.HardwareConfig.from_dict({"depth_buffer": {"cache_bytes": 4096}, "dram": {"bytes_per_clock": 8.0}})
    own = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile"), hardware=small).flat_stats
    base = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile"), keep_timing_records=True)
    for k in ("timing.cycles", "dram.bytes", "depth.cache.misses"):
        assert df[k].iloc[2] == pytest.approx(own[k]), k
    assert df["depth.cache.misses"].iloc[2] > df["depth.cache.misses"].iloc[1] == base.flat_stats["depth.cache.misses"]
    # re-timing the default render's records onto the small cache (what a retime of a render-time key must
    # not do) keeps the default cache's traffic:
    wrong = sim.timing.estimate(base.timing_records, small)
    assert wrong["dram.bytes"] != pytest.approx(df["dram.bytes"].iloc[2])
    assert sim.timing.split_hardware({"depth_buffer": {"cache_bytes": 4096}, "tex_cache": {"size_bytes": 8192,
                                      "miss_latency_cycles": 9}, "sample_test": {"throughput": 8}, "cores": 2}) == (
        {"depth_buffer": {"cache_bytes": 4096}, "tex_cache": {"size_bytes": 8192}},
        {"tex_cache": {"miss_latency_cycles": 9}, "sample_test": {"throughput": 8}, "cores": 2})


def test_retime_reads_the_records_its_render_point_kept(tmp_path, store, monkeypatch):
    """A render point named in keep_records (rast5d report: the renders its retime sections re-time)
    stores its timing records; the retime point then re-times them without rendering again, and its
    row equals the one it computes from a render of its own."""
    from experiments.config import config_hash, expand_sweep
    from experiments.report.pages import _retimed_renders
    from experiments.run import points

    moving = BASE.replace("quad}", "quad, params: {translation_t1: [0.2, 0, 0]}}")
    render_cfg = xc.load_config(write(tmp_path, "r.yaml", moving))
    retime_cfg = xc.load_config(write(tmp_path, "t.yaml", moving + "point: {kind: retime, hardware: {cores: 2}}\n"))
    keep = _retimed_renders([(tmp_path / "t.yaml", retime_cfg, [], None)])
    assert keep == {config_hash(cfg) for _, cfg in expand_sweep(render_cfg)}
    assert (runner.run_sweep(render_cfg, workers=0, progress=False, keep_records=keep)["status"] == "ok").all()
    assert len(list((store / "records").glob("*.npz"))) == 1

    def no_render(*a, **k):
        raise AssertionError("the retime point rendered again")

    monkeypatch.setattr(points, "_rendered", no_render)
    kept = runner.run_sweep(retime_cfg, workers=0, progress=False)
    assert (kept["status"] == "ok").all(), kept["error"].tolist()
    monkeypatch.undo()
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "fresh"))
    own = runner.run_sweep(retime_cfg, workers=0, progress=False)
    for k in ("timing.cycles", "timing.records", "raster.samples_tested", "resolved.lens_grid"):
        assert kept[k].iloc[0] == own[k].iloc[0], k


def test_page_points_skip_the_timing_model_only_when_no_output_reads_it(tmp_path, store):
    """A report page whose outputs never mention timing renders without the timing model, under a
    hash of its own; the same page with a timing plot runs it (and so does a config without a page)."""
    from experiments.config import config_hash, timing_needed

    page = BASE + "outputs:\n  page: p\n  plots:\n    - {kind: table, y: [raster.samples_tested]}\n"
    timed = BASE + "outputs:\n  page: p\n  plots:\n    - {kind: table, y: [timing.cycles]}\n"
    a, b = (xc.load_config(write(tmp_path, n, t)) for n, t in (("a.yaml", page), ("b.yaml", timed)))
    assert not timing_needed(a) and timing_needed(b) and timing_needed(xc.load_config(write(tmp_path, "c.yaml", BASE)))
    assert config_hash(a) != config_hash(b)
    da = runner.run_sweep(a, workers=0, progress=False)
    db = runner.run_sweep(b, workers=0, progress=False)
    assert "timing.cycles" not in da.columns and db["timing.cycles"].iloc[0] > 0
    assert da["raster.samples_tested"].iloc[0] == db["raster.samples_tested"].iloc[0]


@pytest.mark.parametrize("outputs, reads", [
    ({"text": "The timing model is not read here; its timing.cycles neither."}, False),  # prose reads nothing
    ({"plots": [{"kind": "table", "y": ["ops.total"], "title": "timing.cycles"}]}, False),  # a title is no column
    ({"plots": [{"kind": "table", "y": ["ops.total"], "where": {"timing.bottleneck": "setup"}}]}, True),
    ({"plots": [{"kind": "line", "x": "camera.coc_px", "y": "ops.total", "hue": ["timing.bottleneck"]}]}, True),
    ({"derived": {"mc": "timing.cycles / 1e6"}}, True),
    ({"derived": {"x": "hardware.timing.granularity == 'visit'"}}, False),  # a config column, not a figure
    ({"text": "{timing.cycles[pipeline.algorithm=tile]:.3g} cycles"}, True),  # a prose placeholder reads it
    ({"summary": "{timing.cycles[pipeline.algorithm=tile]:.3g} cycles"}, True),
    # the config layer knows no page table: a named table that reads timing is checked where it is placed
    # (tests/test_prose.py::test_named_tables_that_read_timing_sit_on_pages_that_read_it)
    ({"text": "{{table:gpu_vs_tile}}"}, False),
    ({"text": "{{table:table2_culling}}"}, False),
])
def test_a_page_reads_the_timing_model_when_a_column_or_table_of_it_is_named(outputs, reads):
    from experiments.config.sweep import reads_timing

    assert reads_timing(xc.OutputsSpec(page="p", **outputs)) is reads


def test_textured_square_workload_covers_its_edge_squared(tmp_path, store):
    text = ("scene: {name: textured_square, params: {edge_px: 20, width: 64, height: 64}}\n"
            "camera: {coc_px: 0}\nsamples: {spp: 4, seed: 1}\npipeline: {algorithm: tile}\n")
    df = runner.run_sweep(xc.load_config(write(tmp_path, "t.yaml", text)), workers=0, progress=False)
    covered = df["raster.samples_hit"].iloc[0] / 4  # pixels (in focus: a pixel's samples all hit or miss)
    assert covered == pytest.approx(20 * 20, rel=0.1)


# ---- report --------------------------------------------------------------------------------------

PAGE = BASE + """\
sweep:
  camera.coc_px: [0, 6]
  pipeline.algorithm: [bruteforce, tile]
outputs:
  page: tiny
  title: "Tiny: samples tested against CoC"
  text: "What and how."
  derived: {tested_per_hit: "raster.samples_tested / raster.samples_hit"}
  plots:
    - {kind: line, x: camera.coc_px, y: tested_per_hit, hue: pipeline.algorithm, paper: {tile: {0: 1.5}}}
    - {kind: table, x: camera.coc_px, y: ops.total, hue: pipeline.algorithm}
"""


def test_report_quick_writes_pages_figures_and_index(tmp_path, store):
    cdir = tmp_path / "configs"
    cdir.mkdir()
    write(cdir, "tiny.yaml", PAGE.replace("width: 24, height: 24", "width: 200, height: 100"))
    write(cdir, "tiny2.yaml", "extends: _base.yaml\noutputs: {page: tiny, title: Second, order: -1, "
                              "plots: [{kind: bar, x: pipeline.algorithm, y: ops.total}]}\n")
    write(cdir, "_base.yaml", PAGE)
    rc = pages.main(configs_dir=cdir, reports_dir=tmp_path / "reports", quick=True, workers=2)
    assert rc == 0
    page = (tmp_path / "reports" / "quick" / "paper" / "tiny.md").read_text()
    assert page.index("## Second") < page.index("## Tiny: samples tested against CoC")  # order
    assert "![" in page and "(paper)" in page and "rast5d report --only tiny --quick" in page
    assert "--set camera.width=64 --set camera.height=32" in page  # quick keeps the aspect ratio
    assert (tmp_path / "reports" / "quick" / "paper" / "tiny_1.png").exists()
    assert (tmp_path / "reports" / "quick" / "paper" / "tiny2.pdf").exists()
    index = (tmp_path / "reports" / "quick" / "README.md").read_text()
    assert "[tiny](paper/tiny.md)" in index and "Second" in index
    assert (store / "quick" / "tiny.parquet").exists() and not (store / "tiny.parquet").exists()
    df = pd.read_parquet(store / "quick" / "tiny.parquet")
    assert df["camera.width"].tolist() == [64] * 4
    # --only one config of a shared page rewrites the whole page (the other section from the store)
    (tmp_path / "reports" / "quick" / "paper" / "tiny.md").unlink()
    assert pages.main(only=["tiny2"], configs_dir=cdir, reports_dir=tmp_path / "reports", quick=True, workers=0) == 0
    again = (tmp_path / "reports" / "quick" / "paper" / "tiny.md").read_text()
    assert "## Second" in again and "## Tiny: samples tested against CoC" in again



def test_report_pool_computes_each_point_once_and_writes_the_pages_of_the_sequential_path(tmp_path, monkeypatch,
                                                                                          capsys):
    """rast5d report's one pool over all configs (experiments/run/schedule.py): a point shared by two
    configs and the renders a retime section re-times are computed once, and the page equals the one the
    in-process path (workers=0: one sweep after the other, no pool) writes into a store of its own."""
    cdir = tmp_path / "configs"
    cdir.mkdir()
    write(cdir, "a.yaml", PAGE.replace("text: \"What and how.\"", "text: \"What and how; timing.cycles.\""))
    # b shares a's tile points (same scene, camera, table, pipeline, timing read) and adds one
    write(cdir, "b.yaml", "extends: a.yaml\nname: b\nsweep: {camera.coc_px: [0, 6, 9], pipeline.algorithm: [tile]}\n"
                          "outputs: {page: tiny, title: Second, order: 1}\n")
    write(cdir, "c.yaml", "extends: a.yaml\nname: c\npoint: {kind: retime, hardware: {cores: 2}}\n"
                          "outputs: {page: tiny, title: Retimed, order: 2, plots: [{kind: table, x: camera.coc_px, "
                          "y: timing.cycles, hue: pipeline.algorithm}]}\n")
    pages_out = {}
    for workers in (2, 0):
        monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / f"results{workers}"))
        assert pages.main(configs_dir=cdir, reports_dir=tmp_path / f"reports{workers}", workers=workers) == 0
        captured = capsys.readouterr()
        out = captured.out + captured.err
        pages_out[workers] = [line for line in (tmp_path / f"reports{workers}" / "paper" / "tiny.md").read_text()
                              .splitlines() if not line.startswith("Made by")]
        if workers:
            # 4 points of a + 1 of b (its other 2 are a's) + 4 retimes, each computed once, by the pool:
            # the bar names the configs, and the pool's points count as rendered by this run
            assert "report: a, b, c" in out and "b: 3/3 points (3 rendered" in out
            assert "computed by another run" not in out
        assert "(9 points rendered, 2 from the result store)" in out
    assert pages_out[2] == pages_out[0]


def test_report_writes_a_section_as_soon_as_its_points_are_in(monkeypatch):
    """The report writes the section of the first config whose pooled points are all stored, not the
    first in config order (the pool runs the largest points first); once the pool has ended, the next
    in order (its sweep computes what is left)."""
    import threading

    from experiments.run import schedule

    run = schedule.PoolRun({}, [], {}, {"a1", "a2", "b1"}, 2, False, 0,
                           by_config={"A": {"a1", "a2"}, "B": {"b1"}, "C": {"c1"}})  # c1: stored before
    gate = threading.Event()
    run._thread = threading.Thread(target=gate.wait)
    run._thread.start()
    try:
        assert run.wait_ready(["A", "B", "C"]) == 2  # C has nothing pooled
        order = []

        def store(h):
            with run._stored:
                run.claimed.discard(h)
                run._stored.notify_all()

        waiter = threading.Thread(target=lambda: order.append(run.wait_ready(["A", "B"])))
        waiter.start()
        store("a1")
        waiter.join(0.3)
        assert waiter.is_alive()  # A still waits for a2, B for b1
        store("b1")
        waiter.join(5)
        assert order == [1]
    finally:
        gate.set()
        run._thread.join()
    assert run.wait_ready(["A"]) == 0  # the pool ended with a2 unstored: A's sweep computes it


def test_rast5d_run_writes_the_config_page(tmp_path, store):
    p = write(tmp_path, "tiny.yaml", PAGE)
    r = subprocess.run([sys.executable, "-m", "experiments.cli", "run", str(p), "--workers", "0",
                        "--set", "camera.coc_px=3"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    page = (store / "pages" / "tiny" / "tiny.md").read_text()
    assert "rast5d run" in page and "--set camera.coc_px=3" in page and "| camera.coc_px |" in page


def test_experiments_load_names_known_tables(store):
    import experiments

    with pytest.raises(FileNotFoundError, match="no results for 'nothing'"):
        experiments.load("nothing")


def test_every_report_config_is_valid():
    paths = pages.report_configs()
    assert paths
    for p in paths:
        c = xc.load_config(p)
        assert c.outputs.page and (c.outputs.plots or "{{table:" in (c.outputs.text or "")), f"{p.name}: no report spec"
        data, _ = xc.load_dict(p, pages.quick_overrides(xc.load_dict(p)[0]))
        xc.expand_sweep(xc.validate(data, str(p)))


@pytest.mark.slow
def test_full_quick_report(tmp_path):
    """`rast5d report --quick` over every report config (about 9 minutes on 2 busy cores)."""
    env = {**os.environ, "RAST5D_RESULTS": str(tmp_path / "results")}
    r = subprocess.run([sys.executable, "-m", "experiments.cli", "report", "--quick", "--reports",
                        str(tmp_path / "reports")], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr[-2000:]
    REPORTS = tmp_path / "reports"
    index = (REPORTS / "quick" / "README.md").read_text()
    for p in pages.report_configs():
        outputs = xc.load_config(p).outputs
        if outputs.folder == "paper":
            assert f"[{outputs.page}](paper/{outputs.page}.md)" in index
        else:
            assert (REPORTS / "quick" / outputs.folder / f"{outputs.page}.md").exists()


def test_the_documented_spec_example_is_valid():
    """docs/reports.md's format example passes the schema (the other engineers copy it)."""
    import re

    import yaml

    text = (xc.REPO / "docs" / "reports.md").read_text()
    block = re.search(r"```yaml\n(.*?)```", text, flags=re.S).group(1)
    data = yaml.safe_load(block.replace("<name>", "example").replace("<page name>", "example"))
    config = xc.validate(data, "docs/reports.md")
    assert [p.kind for p in config.outputs.plots] == ["line"] and config.outputs.plots[0].paper["tile"][50] == 0.09
    assert len(xc.sweep_points(config.sweep)) == 10


def test_a_point_that_kills_its_worker_fails_alone(tmp_path, store, monkeypatch):
    """A crash in native code takes the worker process down; only that point is an error."""
    real = points.render_point

    def crashing(config, *args, **kwargs):
        if config.samples.spp == 8:
            os._exit(3)  # as a segfault would: no exception, the process is gone
        return real(config, *args, **kwargs)

    monkeypatch.setattr(points, "render_point", crashing)  # inherited by the forked workers
    c = xc.load_config(write(tmp_path, "k.yaml", BASE + "sweep:\n  samples.spp: [4, 8, 16, 2]\n"))
    df = runner.run_sweep(c, workers=2, progress=False)
    assert df["status"].tolist() == ["ok", "error", "ok", "ok"]
    assert "worker process died" in df["error"].iloc[1]

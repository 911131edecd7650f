"""A cached `rast5d run` stays lean: served from the store, it imports no library that only a render, a
mesh file, a plot or a new table needs (the heavy ones cost seconds of start-up), and the caches that
make that possible (a scene's inputs remembered on disk, the sweep table left as it is when its rows
did not change) give the same table as a run without them."""
import importlib
import os

import pytest

# The sweep and the probe the start-up benchmark measures: `rast5d run` in a new process, its exit code
# and which of the heavy libraries (bench_overhead.HEAVY) it imported.
from experiments.bench.bench_overhead import SWEEP
from experiments.bench.bench_overhead import probe_run as _run

pytestmark = pytest.mark.smoke


@pytest.fixture
def sweep(tmp_path):
    path = tmp_path / "lean.yaml"
    path.write_text(SWEEP)
    env = {**os.environ, "RAST5D_RESULTS": str(tmp_path / "results")}
    return path, env, tmp_path / "results"


def test_a_cached_run_imports_no_heavy_library(sweep):
    path, env, results = sweep
    first = _run(path, env)
    # The probe sees these imports: the rendering run reads spot's mesh (trimesh), writes the table
    # (pandas) and starts the pool.
    assert first["rc"] == 0 and {"trimesh", "pandas"} <= set(first["loaded"]), first
    second = _run(path, env)
    assert second == {"rc": 0, "loaded": []}, second


def test_the_table_of_a_cached_run_is_the_rendered_one(sweep):
    """The cached run leaves the table file alone (same rows); a table deleted or damaged is written
    again from the store, equal to the first one."""
    import pandas as pd

    path, env, results = sweep
    _run(path, env)
    table = results / "lean.parquet"
    first = pd.read_parquet(table)
    stamp = table.stat().st_mtime_ns
    _run(path, env)
    assert table.stat().st_mtime_ns == stamp  # not rewritten
    table.write_bytes(b"not parquet")
    _run(path, env)
    pd.testing.assert_frame_equal(pd.read_parquet(table), first)
    table.unlink()
    _run(path, env)
    pd.testing.assert_frame_equal(pd.read_parquet(table), first)


def test_scene_inputs_remembered_only_for_package_files(tmp_path, monkeypatch):
    """A named scene that reads only the package's assets is remembered on disk (no file to watch);
    a scene from a file outside the package is built again and its file's digest is its input."""
    from experiments.config import inputs
    from experiments.config.schema import SceneSpec

    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    inputs._scene_memo.clear()  # earlier tests of this process may have built spot_wall's entry
    spec = SceneSpec(name="spot_wall")
    assert inputs.scene_inputs(spec) == {}
    memo = list((tmp_path / "results" / "inputs").glob("*.json"))
    assert len(memo) == 1
    inputs._scene_memo.clear()
    build = importlib.import_module("experiments.config.build")
    monkeypatch.setattr(build, "build_scene", lambda s: (_ for _ in ()).throw(AssertionError("built again")))
    assert inputs.scene_inputs(spec) == {}  # from the disk memo, not built
    monkeypatch.undo()
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    obj = tmp_path / "tri.obj"
    obj.write_text("v 0 0 -2\nv 1 0 -2\nv 0 1 -2\nf 1 2 3\n")
    got = inputs.scene_inputs(SceneSpec(path=str(obj)))
    assert list(got) == [str(obj.resolve())]
    assert len(list((tmp_path / "results" / "inputs").glob("*.json"))) == 1  # nothing remembered for it

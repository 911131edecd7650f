"""The result store under edits and faults: a point's key covers every file it reads (scene YAML,
mesh, texture, sample arrays) and the installed package; a truncated or corrupted point file is
recomputed with a warning; a failed point keeps its error and traceback until --retry-failed; two
`rast5d run` processes sharing a store compute each point once and leave it readable."""
import json
import os
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest

from experiments import config as xc
from experiments.run import runner, store as result_store

pytestmark = pytest.mark.smoke

OBJ = """\
v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 1/1 2/2 3/3
f 1/1 3/3 4/4
"""

SCENE = """\
objects:
  - mesh: quad.obj
    transform: {scale: 2, translate: [0, 0, -4]}
camera_hint: {fov_y_deg: 60}
"""


@pytest.fixture
def store(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    return tmp_path / "results"


def _texture(path, value):
    from PIL import Image

    Image.fromarray(np.full((8, 8, 3), value, dtype=np.uint8)).save(path)


def _scene_dir(tmp_path):
    d = tmp_path / "scene"
    d.mkdir()
    (d / "quad.obj").write_text(OBJ)
    _texture(d / "quad_texture.png", 200)
    (d / "s.yaml").write_text(SCENE)
    return d


def _config(tmp_path, scene_path):
    p = tmp_path / "c.yaml"
    p.write_text(f"scene: {{path: {scene_path}}}\ncamera: {{width: 16, height: 16, coc_px: 2}}\n"
                 "samples: {spp: 2}\npipeline: {algorithm: tile}\n")
    return xc.load_config(p)


def _rendered(config, **kw):
    return runner.run_sweep(config, workers=0, progress=False, **kw).attrs["summary"]["rendered"]


def test_editing_any_file_a_point_reads_recomputes_it(tmp_path, store):
    d = _scene_dir(tmp_path)
    config = _config(tmp_path, d / "s.yaml")
    assert _rendered(config) == 1
    assert _rendered(config) == 0
    inputs = json.loads(pd.read_parquet(next((store / "points").glob("*.parquet")))["inputs.files"].iloc[0])
    assert {os.path.basename(p) for p in inputs} == {"s.yaml", "quad.obj", "quad_texture.png"}
    # the scene YAML
    (d / "s.yaml").write_text(SCENE.replace("scale: 2", "scale: 3"))
    assert _rendered(config) == 1 and _rendered(config) == 0
    # the mesh
    (d / "quad.obj").write_text(OBJ.replace("v 1 1 0", "v 1 1.5 0"))
    assert _rendered(config) == 1 and _rendered(config) == 0
    # the texture
    _texture(d / "quad_texture.png", 90)
    assert _rendered(config) == 1 and _rendered(config) == 0
    # a comment-only edit changes the contents too: contents, not meaning, are the key
    (d / "s.yaml").write_text("# note\n" + SCENE)
    assert _rendered(config) == 1


def test_editing_a_sample_array_file_recomputes_the_point(tmp_path, store, monkeypatch):
    """Any file read while the point is computed (here a sample array loaded by the table) is
    recorded in the row (inputs.files) and the row is served only while it is unchanged."""
    import sim

    arrays = tmp_path / "samples.npy"
    np.save(arrays, np.random.default_rng(0).random((32, 32, 2, 5)).astype(np.float32))
    real_create = sim.SampleTable.create

    def create(name, **params):
        table = real_create(name, **params)
        np.load(arrays)  # as a table built from a user's array file would read it
        return table

    monkeypatch.setattr(sim.SampleTable, "create", staticmethod(create))
    config = _config(tmp_path, _scene_dir(tmp_path) / "s.yaml")
    assert _rendered(config) == 1 and _rendered(config) == 0
    np.save(arrays, np.zeros((32, 32, 2, 5), dtype=np.float32))
    assert _rendered(config) == 1 and _rendered(config) == 0


def test_the_engine_version_covers_the_whole_package(monkeypatch):
    import sim

    files = {p.relative_to(xc.REPO).as_posix() for p in result_store.package_files() if p.is_relative_to(xc.REPO)}
    for must in ("sim/render.py", "sim/params.py", "models/loader.py", "experiments/run/points.py",
                 "experiments/config/schema.py", "experiments/config/build.py"):
        assert must in files, must
    assert any(f.startswith("models/assets/") for f in files)
    assert not any(f.startswith("experiments/report/") or "__pycache__" in f for f in files)
    assert any(os.path.samefile(p, sim._core.__file__) for p in result_store.package_files())
    # one changed byte in any of them changes the version
    before = result_store.engine_id()
    target = xc.REPO / "models" / "loader.py"
    real = type(target).read_bytes

    def edited(self):
        data = real(self)
        return data + b"\n" if self == target else data

    monkeypatch.setattr(result_store, "_ENGINE_ID", None)
    monkeypatch.setattr(type(target), "read_bytes", edited)
    assert result_store.engine_id() != before


@pytest.mark.parametrize("damage", ["truncate", "flip_bytes", "garbage"])
def test_a_damaged_point_file_is_recomputed_with_a_warning(tmp_path, store, damage):
    config = _config(tmp_path, _scene_dir(tmp_path) / "s.yaml")
    first = runner.run_sweep(config, workers=0, progress=False)
    (path,) = (store / "points").glob("*.parquet")
    data = bytearray(path.read_bytes())
    if damage == "truncate":
        data = data[: len(data) // 2]
    elif damage == "flip_bytes":  # the last bytes of the largest column chunk: its last data page's values
        import pyarrow.parquet as pq

        with pq.ParquetFile(path) as f:
            rg = f.metadata.row_group(0)
            c = max((rg.column(i) for i in range(rg.num_columns)), key=lambda c: c.total_compressed_size)
            end = min(o for o in (c.dictionary_page_offset, c.data_page_offset) if o) + c.total_compressed_size
        for i in range(end - 16, end):
            data[i] ^= 0x55
    else:
        data = bytearray(b"not parquet at all")
    st = path.stat()
    path.write_bytes(bytes(data))
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns))  # damaged in place within one mtime tick
    with pytest.warns(result_store.StoreWarning, match=r"the point is recomputed"):
        again = runner.run_sweep(config, workers=0, progress=False)
    assert again.attrs["summary"]["rendered"] == 1
    assert again["raster.samples_tested"].tolist() == first["raster.samples_tested"].tolist()
    assert result_store.cached_row(first["config_hash"].iloc[0]) is not None  # rewritten whole


def test_every_byte_of_a_point_file_is_covered(tmp_path, store):
    """Flip each byte of a stored point in turn: the file either still gives the identical row
    (a byte no value depends on) or fails its read check; never a silently different row."""
    config = _config(tmp_path, _scene_dir(tmp_path) / "s.yaml")
    runner.run_sweep(config, workers=0, progress=False)
    (path,) = (store / "points").glob("*.parquet")
    good = path.read_bytes()
    row = result_store.read_point_file(path)
    bad = tmp_path / "bad.parquet"
    detected = same = 0
    for i in range(0, len(good), max(1, len(good) // 400)):
        data = bytearray(good)
        data[i] ^= 0xFF
        bad.write_bytes(bytes(data))
        try:
            got = result_store.read_point_file(bad)
        except ValueError:
            detected += 1
            continue
        assert json.dumps(got, sort_keys=True, default=repr) == json.dumps(row, sort_keys=True, default=repr), i
        same += 1
    assert detected > 0


def test_a_failed_point_keeps_its_error_and_is_retried_on_request(tmp_path, store):
    d = _scene_dir(tmp_path)
    p = tmp_path / "f.yaml"
    # the memory limit is checked when the point renders (a valid config, a failing render)
    p.write_text(f"scene: {{path: {d / 's.yaml'}}}\ncamera: {{width: 256, height: 256}}\nsamples: {{spp: 2}}\n"
                 "sweep:\n  pipeline.memory_limit_bytes: [4294967296, 1048576]\n")
    config = xc.load_config(p)
    df = runner.run_sweep(config, workers=0, progress=False)
    assert df["status"].tolist() == ["ok", "error"] and "memory" in df["error"].iloc[1]
    stored = [result_store.read_point_file(f) for f in (store / "points").glob("*.parquet")]
    failed = [r for r in stored if r["status"] == "error"]
    assert len(failed) == 1 and "memory" in failed[0]["error"] and "Traceback (most recent call last)" in failed[0][
        "traceback"] and "render.py" in failed[0]["traceback"]
    # served from the store, error and all
    again = runner.run_sweep(config, workers=0, progress=False)
    assert again.attrs["summary"]["rendered"] == 0 and again.attrs["summary"]["failed_cached"] == 1
    assert again["error"].iloc[1] == df["error"].iloc[1]
    # retried on request: only the failed point
    retried = runner.run_sweep(config, workers=0, progress=False, retry_failed=True)
    assert retried.attrs["summary"]["rendered"] == 1


def test_a_dead_runs_lock_is_taken_over(tmp_path, store):
    config = _config(tmp_path, _scene_dir(tmp_path) / "s.yaml")
    h = xc.config_hash(config)
    lock = result_store.lock_path(h)
    lock.parent.mkdir(parents=True)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    import socket

    lock.write_text(f"{socket.gethostname()} {dead.pid} {time.time()}")
    t0 = time.perf_counter()
    assert _rendered(config) == 1 and time.perf_counter() - t0 < 60
    assert not lock.exists()


def test_a_live_runs_lock_is_waited_for(tmp_path, store):
    """A point another live process has locked is not computed: its row is read once the lock goes."""
    import threading

    from experiments.run import points

    config = _config(tmp_path, _scene_dir(tmp_path) / "s.yaml")
    h = xc.config_hash(config)
    assert result_store.claim(h)  # the "other run" (this process: alive) holds the point

    def other_run_finishes():
        time.sleep(1.0)
        result_store.store_point(points.run_point(config.model_dump_json()))
        result_store.release(h)

    t = threading.Thread(target=other_run_finishes)
    t.start()
    try:
        df = runner.run_sweep(config, workers=0, progress=False, wait_poll_s=0.1)
    finally:
        t.join()
    assert df["status"].tolist() == ["ok"]
    assert df.attrs["summary"]["rendered"] == 0 and df.attrs["summary"]["from_other_run"] == 1


RUN_CONFIG = """\
scene: {name: quad}
camera: {width: 48, height: 48, coc_px: 6}
samples: {spp: 16}
pipeline: {algorithm: bruteforce}
sweep:
  camera.coc_px: [0, 2, 4, 6, 8, 10]
  samples.seed: [0, 1]
"""


def test_two_runs_sharing_a_store_compute_each_point_once(tmp_path, store):
    cfg = tmp_path / "two.yaml"
    cfg.write_text(RUN_CONFIG)
    env = {**os.environ, "RAST5D_RESULTS": str(store)}
    cmd = [sys.executable, "-m", "experiments.cli", "run", str(cfg), "--workers", "1", "--no-report"]
    procs = [subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], outs
    import re

    rendered = [int(re.search(r"\((\d+) rendered", o).group(1)) for o, _ in outs]
    assert sum(rendered) == 12, outs  # every point computed exactly once between the two runs
    files = sorted((store / "points").glob("*"))
    assert len(files) == 12 and all(f.suffix == ".parquet" for f in files)  # no locks, no temporaries left
    rows = [result_store.read_point_file(f) for f in files]
    assert all(r["status"] == "ok" for r in rows)
    table = pd.read_parquet(store / "two.parquet")
    assert len(table) == 12 and (table["status"] == "ok").all()


def test_a_row_is_stored_with_the_column_types_of_its_dataframe_and_read_back_as_pandas_reads_it(tmp_path, store):
    """Point files are written from the row's columns (no one-row DataFrame) and read without building
    one: the same arrow types as pyarrow's DataFrame conversion, and the values DataFrame.iloc[0] gives."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    row = {"config_hash": "00ff", "status": "ok", "camera.coc_px": 10, "ops.total": 1.5e9, "flag": True,
           "missing": None, "nan": float("nan"), "n64": np.int64(7), "u64": np.uint64(2 ** 63 + 5),
           "f32": np.float32(0.25), "b": np.bool_(False), "list": "[1, 2]"}
    path = tmp_path / "p.parquet"
    result_store.write_point_file(dict(row), path)
    got = pq.read_table(path)
    via_pandas = pa.Table.from_pandas(result_store.to_frame([row]), preserve_index=False)
    assert got.schema.names == via_pandas.schema.names and got.schema.types == via_pandas.schema.types
    expect = got.to_pandas().iloc[0].to_dict()  # pandas' reading of the file
    read = result_store.read_point_file(path)
    assert list(read) == list(expect)
    for k in expect:
        assert type(read[k]) is type(expect[k]) and (read[k] == expect[k] or (read[k] is None and expect[k] is None)), k


def test_the_row_checksum_is_json_of_each_column_as_documented(tmp_path, store):
    """A point file's checksum (its Parquet metadata) is sha256 over json.dumps([name, type, values],
    default=repr) column after column, computed here with json itself: every value kind a row holds
    (floats with their infinities, NaN stored as missing, ints past 2**53, text with quotes and
    non-ASCII, numpy scalars) gives the bytes json gives, so stores written before keep their checksums."""
    import hashlib

    import pyarrow.parquet as pq

    row = {"config_hash": "00ff", "status": "ok", "x": 0.1, "big": 2 ** 62 + 1, "neg": -3, "tiny": 5e-324,
           "inf": float("inf"), "ninf": -float("inf"), "nan": float("nan"), "flag": False, "none": None,
           "text": 'quote " back \\ tab\t \u00e9 \u2207 \U0001F600', "f32": np.float32(1.1), "n64": np.int64(-9),
           "b": np.bool_(True), "exp": 1e300}
    path = tmp_path / "p.parquet"
    result_store.write_point_file(dict(row), path)
    table = pq.ParquetFile(path).read()
    h = hashlib.sha256()
    for name, col in zip(table.column_names, table.columns):
        h.update(json.dumps([name, str(col.type), col.to_pylist()], default=repr).encode())
    assert table.schema.metadata[b"rast5d.sha256"].decode() == h.hexdigest()


def test_a_row_read_again_is_served_from_memory_until_its_file_is_replaced(tmp_path, store, monkeypatch):
    h = "00aa11bb22cc33dd"
    result_store.store_point({"config_hash": h, "status": "ok", "x": 1.0})
    calls = []
    real = result_store.read_point_file
    monkeypatch.setattr(result_store, "read_point_file", lambda p: calls.append(p) or real(p))
    assert result_store.cached_row(h)["x"] == 1.0 and calls == []  # this process wrote it
    # another process replaces the file: read again
    import pyarrow as pa

    table = pa.table({"config_hash": [h], "status": ["ok"], "x": [2.0]})
    other = tmp_path / "other.parquet"
    result_store.write_point_file({"config_hash": h, "status": "ok", "x": 2.0}, other)
    result_store._ROWS.pop(str(other), None)
    os.replace(other, result_store.point_path(h))
    assert result_store.cached_row(h)["x"] == 2.0 and len(calls) == 1 and table.num_rows == 1
    assert result_store.cached_row(h)["x"] == 2.0 and len(calls) == 1

"""The result store under the faults of a real disk and of sharing: a disk that fills during a sweep,
a store that turns read-only, several `rast5d run` processes writing one store at once (with the
point locks, and with them dropped), a file system whose locks do not work, a point that hangs.

In each: the sweep stops with a clear error or completes; no partial file is left where a read would
find it; every point stored before stays readable; a rerun completes the sweep; rows equal a clean
run's (every column but the point's wall time). The disk faults run twice: by fault injection around
the writer (every machine), and on a real small tmpfs in a private mount namespace (`unshare`, where
the test runs as root; skipped elsewhere)."""
import errno
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import threading
import time
import warnings

import pandas as pd
import pytest

from experiments import config as xc
from experiments.run import runner, store as result_store
from tests.faults_kit import alive, clean_rows, fault_env, same_row, started, sweep_config, wait_until

pytestmark = pytest.mark.smoke

def store_state(store) -> tuple[dict, list]:
    """({hash: row} of every point file, [names of anything else in points/])."""
    rows, other = {}, []
    for f in sorted((store / "points").iterdir()):
        if f.suffix == ".parquet" and ".tmp-" not in f.name:
            row = result_store.read_point_file(f)  # raises if truncated or corrupted
            rows[row["config_hash"]] = row
        else:
            other.append(f.name)
    return rows, other


# ---- disk faults by injection around the writer ----------------------------------------------------------

class FailingDisk:
    """pyarrow.parquet.write_table (the store's row and table writer) that, from its ``after``-th call on,
    writes half of what it was given and then fails with ``code``: a disk that fills, or turns read-only,
    in the middle of a write. ``heal()`` makes it write again."""

    def __init__(self, monkeypatch, after: int, code: int):
        import pyarrow.parquet as pq

        self.calls, self.after, self.code, self.failed = 0, after, code, 0
        real = pq.write_table

        def write_table(table, where, *args, **kwargs):
            self.calls += 1
            if self.after is not None and self.calls > self.after:
                self.failed += 1
                if self.code == errno.ENOSPC and isinstance(where, (str, os.PathLike)):
                    # some bytes made it to the disk before it filled (pandas passes its own open file: empty)
                    real(table, where, *args, **kwargs)
                    with open(where, "r+b") as f:
                        f.truncate(os.path.getsize(where) // 2)
                raise OSError(self.code, os.strerror(self.code), str(where))
            return real(table, where, *args, **kwargs)

        monkeypatch.setattr(pq, "write_table", write_table)

    def heal(self):
        self.after = None


@pytest.mark.parametrize("code, why", [(errno.ENOSPC, "the disk is full"),
                                       (errno.EROFS, "the file system is read-only")])
def test_a_disk_fault_mid_sweep_stops_with_a_clear_error_and_leaves_nothing_half_written(tmp_path, monkeypatch,
                                                                                          code, why):
    cfg = sweep_config(tmp_path, range(1, 7))
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    store = tmp_path / "results"
    monkeypatch.setenv("RAST5D_RESULTS", str(store))
    disk = FailingDisk(monkeypatch, after=3, code=code)
    with pytest.raises(result_store.StoreError) as info:
        runner.run_sweep(xc.load_config(cfg), workers=0, progress=False)
    message = str(info.value)
    assert f"result store: cannot write {store / 'points'}" in message and why in message, message
    assert "every point finished before is stored and readable" in message and "rerun" in message
    assert disk.failed >= 1
    rows, other = store_state(store)
    assert len(rows) == 3 and not other, other  # the three stored points read back whole; no temporary, no lock
    assert all(same_row(rows[h], clean[h]) for h in rows)
    assert not (store / "faults.parquet").exists()  # the table could not be written either: none, not half of one
    disk.heal()
    df = runner.run_sweep(xc.load_config(cfg), workers=0, progress=False)
    assert df.attrs["summary"]["rendered"] == 3 and df.attrs["summary"]["cached"] == 3
    rows, other = store_state(store)
    assert set(rows) == set(clean) and all(same_row(rows[h], clean[h]) for h in clean) and not other


def test_a_full_disk_under_a_pool_worker_stops_the_run_and_terminates_the_pool(tmp_path, monkeypatch):
    """The pool's worker processes render; the parent stores: a full disk at the third row stops the
    run at once (the workers are terminated, not left computing) with the store's error."""
    cfg = sweep_config(tmp_path, range(1, 9))
    store = tmp_path / "results"
    monkeypatch.setenv("RAST5D_RESULTS", str(store))
    FailingDisk(monkeypatch, after=2, code=errno.ENOSPC)
    t0 = time.monotonic()
    with pytest.raises(result_store.StoreError, match="the disk is full"):
        runner.run_sweep(xc.load_config(cfg), workers=2, progress=False)
    assert time.monotonic() - t0 < 120
    rows, other = store_state(store)
    assert len(rows) == 2 and not other, other


def test_the_command_line_names_the_disk_fault_and_exits_3(tmp_path):
    """`rast5d run` in a process whose file-size limit (ulimit -f, 64 KiB) is below a point file's size:
    the kernel refuses the write (EFBIG) at the first point. 'error: result store: ...' names the file
    and the cause, exit code 3 (a fault of the machinery; bad input is 2), no traceback, no file left
    half-written."""
    import resource

    cfg = sweep_config(tmp_path, [1, 2])
    store = tmp_path / "results"

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (64 << 10, 64 << 10))

    r = subprocess.run([sys.executable, "-m", "experiments.cli", "run", str(cfg), "--workers", "0", "--no-report"],
                       capture_output=True, text=True, timeout=300, preexec_fn=small_files,
                       env={**os.environ, "RAST5D_RESULTS": str(store)})
    assert r.returncode == 3, r
    assert re.search(r"^error: result store: cannot write .*/points/\w+-\w+\.parquet: the file is larger than this "
                     r"process may write \(ulimit -f\)", r.stderr, flags=re.M), r.stderr
    assert "Traceback" not in r.stderr
    rows, other = store_state(store)
    assert not rows and not other, other


# ---- disk faults on a real tmpfs --------------------------------------------------------------------------

def _can_mount_tmpfs(tmp_path) -> bool:
    if not shutil.which("unshare") or os.geteuid() != 0:
        return False
    d = tmp_path / "probe"
    d.mkdir()
    r = subprocess.run(["unshare", "--mount", "--propagation", "private", "sh", "-c",
                        f"mount -t tmpfs -o size=64k tmpfs {d} && touch {d}/x"], capture_output=True)
    return r.returncode == 0 and not (d / "x").exists()


# Runs inside a private mount namespace (unshare): mounts a small tmpfs as the store, runs the sweep,
# makes the fault once two points are stored, copies what the store then holds out of the namespace,
# clears the fault and runs the sweep again.
DRIVER = textwrap.dedent("""\
    import json, os, shutil, subprocess, sys, time
    store, out, cfg, fault = sys.argv[1:5]
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=8m", "tmpfs", store], check=True)
    cmd = [sys.executable, "-m", "experiments.cli", "run", cfg, "--workers", "1", "--no-report", "--quiet"]
    run = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    points = os.path.join(store, "points")
    deadline = time.time() + 300
    while time.time() < deadline and run.poll() is None and (
            not os.path.isdir(points) or sum(f.endswith(".parquet") for f in os.listdir(points)) < 2):
        time.sleep(0.02)
    if fault == "full":  # another program fills the disk
        with open(os.path.join(store, "filler"), "wb") as f:
            try:
                while True:
                    f.write(b"\\0" * 65536)
            except OSError:
                pass
    else:  # the store turns read-only (tmpfs refuses while a file is open for writing: retry)
        for _ in range(500):
            if subprocess.run(["mount", "-o", "remount,ro", store], capture_output=True).returncode == 0:
                break
            time.sleep(0.01)
    o, e = run.communicate(timeout=300)
    shutil.copytree(store, os.path.join(out, "after_fault"), ignore=shutil.ignore_patterns("filler"))
    if fault == "full":
        os.unlink(os.path.join(store, "filler"))
    else:
        subprocess.run(["mount", "-o", "remount,rw", store], check=True)
    again = subprocess.run(cmd[:-1], capture_output=True, text=True, timeout=300)  # with its summary line
    shutil.copytree(store, os.path.join(out, "after_rerun"))
    json.dump({"rc": run.returncode, "stderr": e, "rerun_rc": again.returncode, "rerun_stdout": again.stdout,
               "rerun_stderr": again.stderr}, open(os.path.join(out, "result.json"), "w"))
""")


@pytest.mark.slow
@pytest.mark.parametrize("fault, why", [("full", "the disk is full"), ("readonly", "the file system is read-only")])
def test_a_real_disk_that_fills_or_turns_read_only_mid_sweep(tmp_path, monkeypatch, fault, why):
    if not _can_mount_tmpfs(tmp_path):
        pytest.skip("needs root and unshare to mount a private tmpfs (the injected faults above run everywhere)")
    cfg = sweep_config(tmp_path, range(1, 13))
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    store, out = tmp_path / "store", tmp_path / "out"
    store.mkdir()
    out.mkdir()
    env = {**fault_env(None, {"*": "sleep:0.3"}), "RAST5D_RESULTS": str(store)}
    r = subprocess.run(["unshare", "--mount", "--propagation", "private", sys.executable, "-c", DRIVER, str(store),
                        str(out), str(cfg), fault], env=env, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    result = json.loads((out / "result.json").read_text())
    assert result["rc"] == 3, result
    assert why in result["stderr"] and "Traceback" not in result["stderr"], result["stderr"]
    rows, other = store_state(out / "after_fault")
    assert 2 <= len(rows) < 12 and all(same_row(rows[h], clean[h]) for h in rows)
    assert not [n for n in other if ".tmp-" in n], other  # no temporary file left
    table = out / "after_fault" / "faults.parquet"
    if table.exists():  # a table, if one was written, is whole
        assert len(pd.read_parquet(table)) >= 2
    assert result["rerun_rc"] == 0, result["rerun_stderr"]
    assert f"({12 - len(rows)} rendered, {len(rows)} cached" in result["rerun_stdout"], result  # only the missing
    rows, other = store_state(out / "after_rerun")
    assert set(rows) == set(clean) and all(same_row(rows[h], clean[h]) for h in clean) and not other, other


# ---- concurrent sweeps on one store ----------------------------------------------------------------------

class Reader:
    """Reads every point file and table of a store over and over while runs write it; counts the reads
    that found a torn or corrupted file (none may)."""

    def __init__(self, store):
        self.store, self.reads, self.torn, self.stop = store, 0, [], False
        self.thread = threading.Thread(target=self.loop, daemon=True)
        self.thread.start()

    def loop(self):
        while not self.stop:
            for f in list((self.store / "points").glob("*.parquet")) if (self.store / "points").is_dir() else []:
                try:
                    result_store.read_point_file(f)
                    self.reads += 1
                except FileNotFoundError:
                    pass
                except ValueError as e:
                    self.torn.append(f"{f.name}: {e}")
            for f in self.store.glob("*.parquet"):
                try:
                    pd.read_parquet(f)
                    self.reads += 1
                except FileNotFoundError:
                    pass
                except Exception as e:  # noqa: BLE001 - a torn table
                    self.torn.append(f"{f.name}: {e}")
            time.sleep(0.01)

    def finish(self):
        self.stop = True
        self.thread.join()


def _run_all(tmp_path, commands, env):
    procs = [subprocess.Popen(c, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for c in commands]
    outs = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0] * len(procs), outs
    return [o for o, _ in outs]


def _count(pattern, text):
    m = re.search(pattern, text)
    return int(m.group(1)) if m else 0


@pytest.mark.slow  # the fast tier has two locked runs: test_store.py::test_two_runs_sharing_a_store_compute_each_point_once
def test_concurrent_runs_with_locks_compute_each_point_once(tmp_path):
    """Three `rast5d run` processes on one store, over overlapping sweeps (seeds 1-8, 5-12, 1-12): the
    locks give each of the 12 points to one run; the others take its row. A reader meanwhile never
    finds a torn file."""
    store = tmp_path / "results"
    log = tmp_path / "log"
    log.mkdir()
    env = {**fault_env(log, {"*": "sleep:0.3"}), "RAST5D_RESULTS": str(store)}
    cfgs = [sweep_config(tmp_path, s, name=n) for s, n in ((range(1, 9), "a"), (range(5, 13), "b"),
                                                           (range(1, 13), "c"))]
    reader = Reader(store)
    outs = _run_all(tmp_path, [[sys.executable, "-m", "experiments.cli", "run", str(c), "--workers", "1",
                                "--no-report"] for c in cfgs], env)
    reader.finish()
    rendered = [_count(r"\((\d+) rendered", o) for o in outs]
    assert sum(rendered) == 12, outs  # every point computed by exactly one run
    assert len(started(log)) == 12
    rows, other = store_state(store)
    assert len(rows) == 12 and not other, other
    tables = {n: pd.read_parquet(store / f"{n}.parquet") for n in "abc"}
    for df in tables.values():
        for r in df.to_dict("records"):
            assert same_row(r, rows[r["config_hash"]]) and r["time.wall_s"] == rows[r["config_hash"]]["time.wall_s"]
    assert reader.reads > 0 and not reader.torn, reader.torn


def test_a_point_computed_twice_without_locks_keeps_one_row_and_no_reader_sees_a_torn_one(tmp_path):
    """The second of two runs over the same points takes and honours no lock (`--no-lock`, as on a
    file system that drops locks): points are computed twice, yet the store keeps the row stored first
    and both runs' tables hold that same row, wall time included; a reader never finds a torn file."""
    store = tmp_path / "results"
    log = tmp_path / "log"
    log.mkdir()
    env = {**fault_env(log, {"*": "sleep:0.4"}), "RAST5D_RESULTS": str(store)}
    a, b = sweep_config(tmp_path, range(1, 7), name="a"), sweep_config(tmp_path, range(1, 7), name="b")
    reader = Reader(store)
    outs = _run_all(tmp_path, [[sys.executable, "-m", "experiments.cli", "run", str(a), "--workers", "1", "--no-report"],
                               [sys.executable, "-m", "experiments.cli", "run", str(b), "--workers", "1", "--no-report",
                                "--no-lock"]], env)
    reader.finish()
    rendered = [_count(r"\((\d+) rendered", o) for o in outs]
    kept = [_count(r"(\d+) also computed by another run", o) for o in outs]
    twice = len(started(log)) - 6
    assert twice > 0 and sum(rendered) == 6 + twice, outs  # some points were computed by both runs
    assert sum(kept) == twice, outs  # ... and each time the later one kept the row stored first
    rows, other = store_state(store)
    assert len(rows) == 6 and not other, other
    ta, tb = (pd.read_parquet(store / f"{n}.parquet") for n in "ab")
    for r in [*ta.to_dict("records"), *tb.to_dict("records")]:
        stored = rows[r["config_hash"]]
        assert same_row(r, stored) and r["time.wall_s"] == stored["time.wall_s"]  # the very same row
    assert reader.reads > 0 and not reader.torn, reader.torn


# ---- a file system where locking fails ---------------------------------------------------------------------

@pytest.mark.parametrize("mode", ["ignored", "unsupported"])
def test_a_store_whose_locks_fail_warns_and_runs_without_them(tmp_path, monkeypatch, mode):
    """An exclusive create that the file system ignores (a second one succeeds, as on NFSv2) or refuses
    (ENOTSUP, as on some FUSE mounts): a StoreWarning says what it means; the sweep still completes."""
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    monkeypatch.setattr(result_store, "_LOCKS_CHECKED", {})
    real = os.open

    def fake_open(path, flags, *args, **kwargs):
        if flags & os.O_EXCL:
            if mode == "unsupported":
                raise OSError(errno.ENOTSUP, os.strerror(errno.ENOTSUP), str(path))
            flags &= ~os.O_EXCL
        return real(path, flags, *args, **kwargs)

    class StoreOs:  # the os module as the store sees it (the results-directory check keeps the real one)
        open = staticmethod(fake_open)

        def __getattr__(self, name):
            return getattr(os, name)

    monkeypatch.setattr(result_store, "os", StoreOs())
    cfg = sweep_config(tmp_path, [1, 2])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        df = runner.run_sweep(xc.load_config(cfg), workers=0, progress=False)
    messages = [str(w.message) for w in caught if issubclass(w.category, result_store.StoreWarning)]
    assert len(messages) == 1, messages
    assert "point locks do not work on this file system" in messages[0]
    assert ("a second exclusive create" if mode == "ignored" else "fails") in messages[0]
    assert "may compute the same point again" in messages[0] and "the first row stored is kept" in messages[0]
    assert (df["status"] == "ok").all() and not list((tmp_path / "results" / "points").glob("*.lock"))


def test_a_store_whose_locks_work_gives_no_warning(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    monkeypatch.setattr(result_store, "_LOCKS_CHECKED", {})
    assert result_store.check_locks() is True  # filterwarnings=error: a warning would fail here


# ---- a point that hangs: executor.point_timeout_s ------------------------------------------------------------

def test_a_hanging_point_is_stopped_at_its_timeout_in_the_local_pool(tmp_path, monkeypatch):
    cfg = sweep_config(tmp_path, [1, 2, 3], extra="executor: {point_timeout_s: 3}\n")
    clean = clean_rows(tmp_path, sweep_config(tmp_path, [1, 2, 3], name="plain"), monkeypatch)  # same points
    log = tmp_path / "log"
    log.mkdir()
    for k, v in fault_env(log, {3: "hang"}).items():
        monkeypatch.setenv(k, v)  # the points' child processes inherit the hooks
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    t0 = time.monotonic()
    df = runner.run_sweep(xc.load_config(cfg), workers=0, progress=False)
    assert time.monotonic() - t0 < 120
    assert df["status"].tolist() == ["ok", "ok", "error"], df[["status", "error"]]
    assert df["error"].iloc[2].startswith("executor.point_timeout_s = 3: the point ran longer than 3 s")
    hung = [p for s, p, _ in started(log) if s == 3]
    assert len(hung) == 1
    wait_until(lambda: not alive(hung[0]), 10, "the hung point's process is gone")
    ok = df[df["status"] == "ok"].to_dict("records")
    assert len(ok) == 2 and all(same_row(r, clean[r["config_hash"]]) for r in ok)


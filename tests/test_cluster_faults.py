"""Sweeps on a real Dask cluster under faults: a scheduler and workers started as separate processes
on 127.0.0.1 (tests/faults_kit.py), killed as an operator or the machine would kill them. In each case
the sweep completes, or stops with an error naming the fault and a rerun completes it; every
finished point stays in the store; no point file is written twice with different contents; and
every row equals a clean in-process run's (all columns but the point's wall time).

Test-only hooks (tests/faults/sitecustomize.py, switched on by RAST5D_TEST_FAULTS in the processes
these tests start) make a point slow, hang or allocate memory. The soak (a few hundred points with
workers killed at random for at least ten minutes) is in the slow tier: `pytest -m slow -k soak`."""
import os
import random
import re
import subprocess
import sys
import threading
import time

import pandas as pd
import pytest

from experiments import config as xc
from experiments.run import runner, store as result_store
from tests.faults_kit import (ProcessCluster, alive, clean_rows, fault_env, free_port, same_row, started,
                              sweep_config, wait_until)

pytestmark = [pytest.mark.smoke,
              pytest.mark.filterwarnings("ignore::DeprecationWarning", "ignore::ResourceWarning",
                                         "ignore::pytest.PytestUnraisableExceptionWarning")]

class Writes:
    """Every point file the store puts in place (by hash), to check none is written twice."""

    def __init__(self, monkeypatch):
        self.rows: dict[str, list] = {}
        real = result_store.write_point_file

        def recording(df, path, keep=None):
            installed = real(df, path, keep=keep)
            if installed:
                self.rows.setdefault(path.name, []).append(dict(df) if isinstance(df, dict) else df)
            return installed

        monkeypatch.setattr(result_store, "write_point_file", recording)

    def twice(self) -> dict:
        return {k: v for k, v in self.rows.items() if len(v) > 1}


def in_thread(fn):
    """Run fn() in a thread; returns (thread, box) where box gets 'result' or 'error'."""
    box: dict = {}

    def target():
        try:
            box["result"] = fn()
        except BaseException as e:  # noqa: BLE001 - handed to the test
            box["error"] = e

    t = threading.Thread(target=target, daemon=True)
    t.start()
    return t, box


def stored_rows(store) -> dict:
    return {r["config_hash"]: r for r in (result_store.read_point_file(f) for f in (store / "points").glob("*.parquet"))}


# ---- a worker SIGKILLed in the middle of a point ----------------------------------------------------

def test_a_worker_killed_in_the_middle_of_a_point_loses_nothing(tmp_path, monkeypatch):
    """The worker process running a point is SIGKILLed mid-point; Dask runs the point again on a live
    worker (its nanny restarts the dead one) and the sweep completes with every row equal to a clean
    run's, each point file written once."""
    seeds = range(1, 7)
    cfg = sweep_config(tmp_path, seeds)
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "results"
    monkeypatch.setenv("RAST5D_RESULTS", str(store))
    writes = Writes(monkeypatch)
    with ProcessCluster(tmp_path / "cluster", 2, env=fault_env(log, {"*": "sleep:2.5"})) as cluster:
        cluster.wait_for_workers(2)
        thread, box = in_thread(lambda: runner.run_sweep(xc.load_config(cfg), scheduler=cluster.address,
                                                         progress=False))
        # the third point to start: kill its worker process 0.3 s into its 2.5 s
        seed, pid, _ = wait_until(lambda: started(log)[2] if len(started(log)) >= 3 else None, 180,
                                  "three points started")
        time.sleep(0.3)
        cluster.kill(pid)
        thread.join(300)
        assert not thread.is_alive(), cluster.logs()
    assert "error" not in box, box.get("error")
    df = box["result"]
    assert len(df) == 6 and (df["status"] == "ok").all(), df[["status", "error"]]
    runs = [s for s, _, _ in started(log)]
    assert runs.count(seed) == 2, f"the killed point ran {runs.count(seed)} times: {runs}"  # killed mid-point, re-run
    assert not writes.twice(), writes.twice()
    rows = stored_rows(store)
    assert set(rows) == set(clean) and all(same_row(rows[h], clean[h]) for h in clean)


# ---- a point that hangs, with executor.point_timeout_s ---------------------------------------------

@pytest.mark.slow
def test_with_a_point_timeout_a_hanging_point_and_one_over_the_memory_limit_are_error_rows(tmp_path, monkeypatch):
    """executor.point_timeout_s: each point runs in a child process of its worker; the one that hangs is
    killed at the timeout, the one that outgrows the worker's memory_limit when it does (the nanny
    watches the worker process only): both error rows, stored, each point started once."""
    cfg = sweep_config(tmp_path, [1, 2, 3, 4, 5], extra="executor: {point_timeout_s: 12}\n")
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "results"
    monkeypatch.setenv("RAST5D_RESULTS", str(store))
    with ProcessCluster(tmp_path / "cluster", 2, memory_limit="1GiB",
                        env=fault_env(log, {3: "hang", 4: "alloc:3"})) as cluster:
        cluster.wait_for_workers(2)
        t0 = time.monotonic()
        df = runner.run_sweep(xc.load_config(cfg), scheduler=cluster.address, progress=False)
        took = time.monotonic() - t0
    assert df["status"].tolist() == ["ok", "ok", "error", "error", "ok"], df[["status", "error"]]
    assert df["error"].iloc[2].startswith("executor.point_timeout_s = 12: the point ran longer than 12 s") and took < 120
    assert re.match(r"out of memory: the point's process grew to \d\.\d\d GiB resident, over 95% of the Dask worker's "
                    r"memory_limit \(1\.00 GiB\)", df["error"].iloc[3]), df["error"].iloc[3]
    runs = started(log)
    for seed in (3, 4):
        pids = [p for s, p, _ in runs if s == seed]
        assert len(pids) == 1  # stopped once, not retried
        wait_until(lambda: not alive(pids[0]), 10, f"point {seed}'s process is gone")
    rows = stored_rows(store)
    ok = [h for h in clean if rows[h]["status"] == "ok"]
    assert len(ok) == 3 and all(same_row(rows[h], clean[h]) for h in ok)
    for i in (2, 3):  # stored: a rerun serves them as failed
        assert rows[df["config_hash"].iloc[i]]["error"] == df["error"].iloc[i]


# ---- a point over the worker's memory_limit ------------------------------------------------------------

@pytest.mark.slow
def test_a_point_over_the_workers_memory_limit_is_an_error_row_naming_the_memory(tmp_path, monkeypatch):
    """The point allocates 3 GiB on workers of 1 GiB: each worker it runs on is restarted by its nanny;
    after the scheduler's allowed-failures (1 here) the point is an error row naming the memory, stored,
    so a rerun serves it as failed instead of killing workers again."""
    cfg = sweep_config(tmp_path, [1, 2, 3, 4])
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "results"
    monkeypatch.setenv("RAST5D_RESULTS", str(store))
    env = fault_env(log, {2: "alloc:3"})
    with ProcessCluster(tmp_path / "cluster", 2, memory_limit="1GiB", env=env,
                        scheduler_env={"DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "1"}) as cluster:
        cluster.wait_for_workers(2)
        df = runner.run_sweep(xc.load_config(cfg), scheduler=cluster.address, progress=False)
        assert df["status"].tolist() == ["ok", "error", "ok", "ok"], df[["status", "error"]]
        error = df["error"].iloc[1]
        assert "out of memory" in error and "memory_limit of 1.00 GiB" in error and "2 attempts" in error, error
        assert [s for s, _, _ in started(log)].count(2) == 2  # allowed-failures + 1 attempts, then no more
        again = runner.run_sweep(xc.load_config(cfg), scheduler=cluster.address, progress=False)
    assert again.attrs["summary"]["rendered"] == 0 and again.attrs["summary"]["failed_cached"] == 1
    assert [s for s, _, _ in started(log)].count(2) == 2  # the rerun did not run it again
    rows = stored_rows(store)
    assert all(same_row(rows[h], clean[h]) for h in clean if rows[h]["status"] == "ok")


# ---- the scheduler killed, then restarted ----------------------------------------------------------------

@pytest.mark.slow
def test_a_lost_scheduler_stops_the_run_naming_it_and_a_rerun_completes(tmp_path, monkeypatch):
    seeds = list(range(1, 13))
    cfg = sweep_config(tmp_path, seeds)
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "results"
    env = {**fault_env(log, {"*": "sleep:1"}), "RAST5D_RESULTS": str(store)}
    cmd = [sys.executable, "-m", "experiments.cli", "run", str(cfg), "--no-report", "--quiet"]
    with ProcessCluster(tmp_path / "cluster", 2, env=env) as cluster:
        cluster.wait_for_workers(2)
        run = subprocess.Popen(cmd + ["--scheduler", cluster.address], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        wait_until(lambda: len(list((store / "points").glob("*.parquet"))) >= 3 or run.poll() is not None, 300,
                   "three points stored")
        before = {f.name: f.read_bytes() for f in (store / "points").glob("*.parquet")}
        cluster.kill_scheduler()
        t0 = time.monotonic()
        out, err = run.communicate(timeout=120)
        stopped_after = time.monotonic() - t0
        assert run.returncode == 3, (out, err)
        assert f"lost the Dask scheduler at {cluster.address}" in err and "Traceback" not in err, err
        assert stopped_after < 30, stopped_after
        # the operator restarts the cluster (the workers left when their scheduler went)
        cluster.start_scheduler()
        for w in list(cluster.workers):
            cluster.kill(w)
        cluster.workers.clear()
        cluster.start_worker()
        cluster.start_worker()
        cluster.wait_for_workers(2)
        rerun = subprocess.run(cmd + ["--scheduler", cluster.address], env=env, capture_output=True, text=True,
                               timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    rows = stored_rows(store)
    assert set(rows) == set(clean) and all(same_row(rows[h], clean[h]) for h in clean)
    after = {f.name: f.read_bytes() for f in (store / "points").glob("*.parquet")}
    assert all(after[k] == v for k, v in before.items())  # the points stored before the fault were not rewritten
    table = pd.read_parquet(store / "faults.parquet")
    assert len(table) == 12 and (table["status"] == "ok").all()


# ---- a scheduler that does not answer ------------------------------------------------------------------

def test_a_scheduler_that_does_not_answer_is_a_clear_error_within_the_connect_timeout(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    address = f"tcp://127.0.0.1:{free_port()}"  # nothing listens there
    cfg = sweep_config(tmp_path, [1, 2], extra="executor: {connect_timeout_s: 2}\n")
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "experiments.cli", "run", str(cfg), "--scheduler", address,
                        "--no-report"], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "RAST5D_RESULTS": str(tmp_path / "results")})
    assert r.returncode == 3, r
    assert re.search(rf"error: executor: the Dask scheduler at {address} did not answer within 2 s", r.stderr), r.stderr
    assert "Traceback" not in r.stderr and time.monotonic() - t0 < 60
    assert not list((tmp_path / "results" / "points").glob("*"))  # no lock or row left behind


# ---- the soak --------------------------------------------------------------------------------------------

SOAK_POINTS = int(os.environ.get("RAST5D_SOAK_POINTS", 300))
SOAK_MIN_S = float(os.environ.get("RAST5D_SOAK_MIN_S", 600))


@pytest.mark.slow
def test_soak_a_long_sweep_with_workers_killed_at_random_equals_a_clean_run(tmp_path, monkeypatch):
    """A few hundred small points on a 2-worker cluster for at least ten minutes, while a worker
    process (its nanny restarts it) or a whole worker (nanny and all: the test starts a new one) is
    SIGKILLed every 10-40 s at random, sometimes both workers at once. Each point sleeps 3-5 s in the
    test hook before it renders, so the sweep is long without loading the machine. The sweep
    completes; every point is present and equal to a clean in-process run's row, and no point file is
    written twice. Prints its figures (points, faults, wall time, rows equal)."""
    rng = random.Random(2024)
    seeds = list(range(1000, 1000 + SOAK_POINTS))
    pace = SOAK_MIN_S * 2 / SOAK_POINTS  # seconds per point on 2 workers
    actions = {s: f"sleep:{pace * rng.uniform(0.8, 1.2):.2f}" for s in seeds}
    cfg = sweep_config(tmp_path, seeds, name="soak")
    t_clean = time.monotonic()
    clean = clean_rows(tmp_path, cfg, monkeypatch)
    t_clean = time.monotonic() - t_clean
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "results"
    monkeypatch.setenv("RAST5D_RESULTS", str(store))
    writes = Writes(monkeypatch)
    faults = {"worker process": 0, "whole worker": 0, "both workers": 0}
    with ProcessCluster(tmp_path / "cluster", 2, env=fault_env(log, actions),
                        scheduler_env={"DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "20"}) as cluster:
        cluster.wait_for_workers(2)
        t0 = time.monotonic()
        thread, box = in_thread(lambda: runner.run_sweep(xc.load_config(cfg), scheduler=cluster.address,
                                                         progress=False))
        while thread.is_alive():
            thread.join(rng.uniform(10, 40))
            if not thread.is_alive():
                break
            running = {}
            for seed, pid, _ in started(log):
                running[pid] = seed  # the latest point of each process
            live = [pid for pid in running if alive(pid)]
            choice = rng.random()
            if choice < 0.6 and live:  # the worker process in the middle of a point; its nanny restarts it
                cluster.kill(rng.choice(live))
                faults["worker process"] += 1
            elif choice < 0.85:  # a whole worker (nanny and process); a new one joins 5 s later
                up = [w for w in cluster.workers if w.poll() is None]
                if up:
                    cluster.kill(rng.choice(up))
                    faults["whole worker"] += 1
                    time.sleep(5)
                    cluster.start_worker()
            else:  # both worker processes at once
                for pid in live:
                    cluster.kill(pid)
                faults["both workers"] += 1 if live else 0
        wall = time.monotonic() - t0
    assert "error" not in box, box.get("error")
    df = box["result"]
    rows = stored_rows(store)
    equal = sum(1 for h in clean if h in rows and same_row(rows[h], clean[h]))
    starts = len(started(log))
    print(f"\nsoak: {len(seeds)} points, {sum(faults.values())} faults injected {faults}, {starts} point starts "
          f"({starts - len(seeds)} re-runs), wall {wall:.0f} s (clean in-process run {t_clean:.0f} s), "
          f"{equal}/{len(clean)} rows equal to the clean run, {len(writes.twice())} point files written twice")
    assert len(df) == len(seeds) and (df["status"] == "ok").all(), df[df["status"] != "ok"][["error"]]
    differ = {k for h in clean if h in rows for k in set(rows[h]) | set(clean[h])
              if k != "time.wall_s" and not same_row({k: rows[h].get(k)}, {k: clean[h].get(k)})}
    assert equal == len(clean) == len(seeds), f"columns that differ: {sorted(differ)}"
    assert not writes.twice()
    assert wall >= SOAK_MIN_S * 0.9 and sum(faults.values()) >= SOAK_MIN_S / 60


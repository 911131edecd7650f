"""What the fault tests (tests/test_cluster_faults.py, tests/test_store_faults.py) share: a small sweep
and its clean in-process run to compare rows with; the test-only fault hooks' environment and log; and
a real Dask cluster, a scheduler and workers (each a nanny and its worker process) started as separate
processes on 127.0.0.1 from the `dask` command-line modules of the venv, as an operator starts them,
killed and restarted by the tests, and torn down by their process ids (each in its own session).

The test-only fault hooks (tests/faults/sitecustomize.py) reach every process started with
``fault_env`` through PYTHONPATH and RAST5D_TEST_FAULTS."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

HOOKS = Path(__file__).resolve().parent / "faults"

SWEEP = """\
name: {name}
scene: {{name: quad}}
camera: {{width: 32, height: 32, coc_px: 4}}
samples: {{spp: 4}}
pipeline: {{algorithm: tile}}
sweep:
  samples.seed: {seeds}
"""


def sweep_config(folder: Path, seeds, name: str = "faults", extra: str = "") -> Path:
    """A small sweep over samples.seed (the fault hooks pick points by seed), written to folder/<name>.yaml."""
    p = Path(folder) / f"{name}.yaml"
    p.write_text(SWEEP.format(name=name, seeds=list(seeds)) + extra)
    return p


def clean_rows(folder: Path, config_path: Path, monkeypatch) -> dict:
    """{config_hash: row} of the sweep run in-process into its own store (folder/clean), without hooks
    or faults: the reference every faulted run's rows are compared with."""
    from experiments import config as xc
    from experiments.run import runner

    monkeypatch.setenv("RAST5D_RESULTS", str(Path(folder) / "clean"))
    df = runner.run_sweep(xc.load_config(config_path), workers=0, progress=False)
    return {r["config_hash"]: r for r in df.to_dict("records")}


def same_row(a: dict, b: dict) -> bool:
    """Rows equal in every column but the point's own wall time (missing equal to missing)."""
    import pandas as pd

    keys = (set(a) | set(b)) - {"time.wall_s"}
    return all(a.get(k) == b.get(k) or (pd.isna(a.get(k)) and pd.isna(b.get(k))) for k in keys)


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
        return True
    except ProcessLookupError:
        return False


def fault_env(log: Path | None = None, points: dict | None = None, base: dict | None = None) -> dict:
    """An environment with the test-only fault hooks on: ``points`` {seed: action} (see
    tests/faults/sitecustomize.py), each started point logged under ``log``."""
    env = dict(os.environ if base is None else base)
    env["PYTHONPATH"] = os.pathsep.join([str(HOOKS)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env["RAST5D_TEST_FAULTS"] = json.dumps({"log": str(log) if log else None,
                                           "points": {str(k): v for k, v in (points or {}).items()}})
    return env


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def started(log: Path) -> list[tuple[int, int, int]]:
    """(seed, pid, start time in ns) of every point started so far, in start order (the hooks' log)."""
    out = []
    for f in log.iterdir():
        seed, pid, ns = f.name.split("-")
        out.append((int(seed), int(pid), int(ns)))
    return sorted(out, key=lambda t: t[2])


class ProcessCluster:
    """A scheduler and ``n_workers`` workers, one thread each, as separate processes on loopback."""

    def __init__(self, folder: Path, n_workers: int = 2, memory_limit: str = "2GiB", env: dict | None = None,
                 scheduler_env: dict | None = None):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.env = dict(env or os.environ)
        self.scheduler_env = {**self.env, **(scheduler_env or {})}
        self.memory_limit = memory_limit
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.scheduler: subprocess.Popen | None = None
        self.workers: list[subprocess.Popen] = []
        self._n = 0
        self.start_scheduler()
        for _ in range(n_workers):
            self.start_worker()

    def _spawn(self, args: list[str], name: str, env: dict) -> subprocess.Popen:
        log = open(self.folder / f"{name}.log", "ab")
        try:
            return subprocess.Popen([sys.executable, "-m", *args], env=env, stdout=log, stderr=subprocess.STDOUT,
                                    start_new_session=True, cwd=self.folder)
        finally:
            log.close()

    def start_scheduler(self) -> None:
        # its HTTP server (health, metrics) runs even without the dashboard: on a free port, never 8787,
        # which another cluster on the machine (a LocalCluster test) may want
        self.scheduler = self._spawn(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
                                      str(self.port), "--no-dashboard", "--dashboard-address", "127.0.0.1:0"],
                                     "scheduler", self.scheduler_env)

    def start_worker(self) -> subprocess.Popen:
        self._n += 1
        proc = self._spawn(["distributed.cli.dask_worker", self.address, "--nthreads", "1", "--nworkers", "1",
                            "--memory-limit", self.memory_limit, "--no-dashboard", "--dashboard-address",
                            "127.0.0.1:0", "--name", f"w{self._n}",
                            "--local-directory", str(self.folder / "scratch")], f"worker{self._n}", self.env)
        self.workers.append(proc)
        return proc

    def n_workers(self, timeout_s: float = 10.0) -> int:
        from distributed import Client

        with Client(self.address, timeout=f"{timeout_s}s", set_as_default=False) as c:
            return len(c.scheduler_info()["workers"])

    def wait_for_workers(self, n: int, timeout_s: float = 180.0) -> None:
        """Until the scheduler has ``n`` workers (a loaded machine starts a worker in several seconds)."""
        from distributed import Client

        with Client(self.address, timeout=f"{timeout_s}s", set_as_default=False) as c:
            c.wait_for_workers(n, timeout=timeout_s)

    def kill(self, proc_or_pid) -> None:
        """SIGKILL one process this cluster started (a Popen: its whole session) or a worker process by pid."""
        if isinstance(proc_or_pid, subprocess.Popen):
            try:
                os.killpg(proc_or_pid.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            proc_or_pid.wait()
        else:  # only a process of a session this cluster started (never a pid reused by another program)
            ours = {p.pid for p in [*self.workers, self.scheduler] if p is not None}
            try:
                if os.getpgid(proc_or_pid) in ours:
                    os.kill(proc_or_pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def kill_scheduler(self) -> None:
        self.kill(self.scheduler)

    def close(self) -> None:
        for proc in [*self.workers, self.scheduler]:
            if proc is not None and proc.poll() is None:
                self.kill(proc)
        # a worker's session may outlive its nanny (killed alone): end what is left of each session we started
        for proc in [*self.workers, self.scheduler]:
            if proc is not None:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    pass

    def logs(self) -> str:
        return "\n".join(f"--- {f.name}\n{f.read_text(errors='replace')[-3000:]}" for f in sorted(self.folder.glob("*.log")))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def wait_until(predicate, timeout_s: float, what: str, poll_s: float = 0.1):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(poll_s)
    raise AssertionError(f"not within {timeout_s:g} s: {what}")

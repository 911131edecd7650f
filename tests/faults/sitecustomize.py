"""Test-only fault hooks for the cluster and store fault tests (tests/test_cluster_faults.py,
tests/test_store_faults.py); never part of the installed package or of a user's run.

The tests put this folder on PYTHONPATH of the processes they start (Dask scheduler and workers,
`rast5d run`, the point child processes of executor.point_timeout_s all inherit it) and describe the
faults in RAST5D_TEST_FAULTS (JSON). Without that variable this module does nothing but hand over to
the next sitecustomize on the path (tests/sanitize's under `make sanitize`).

RAST5D_TEST_FAULTS = {"log": DIR, "points": {SEED: ACTION, ..., "*": ACTION}}: a render point whose
samples.seed is SEED (or any other point, for "*") first writes DIR/<seed>-<pid>-<ns> (so a test knows
which process runs which point, and when it started), then does ACTION before it renders:
- "sleep:S": sleep S seconds (a long point whose worker can be killed in the middle of it);
- "hang": never return (a point for executor.point_timeout_s);
- "alloc:G": allocate and touch G GiB in 64 MiB blocks, then wait (a point over a memory_limit);
- "exit": end the process at once with status 3, as a crash in native code would.
"""
import importlib.abc
import importlib.machinery
import importlib.util
import json
import os
import sys
import time

_SPEC = os.environ.get("RAST5D_TEST_FAULTS")


def _act(action: str) -> None:
    kind, _, arg = action.partition(":")
    if kind == "sleep":
        time.sleep(float(arg))
    elif kind == "hang":
        while True:
            time.sleep(3600)
    elif kind == "alloc":
        import numpy as np

        blocks, block = [], 64 << 20
        for _ in range(int(float(arg) * (1 << 30)) // block):
            blocks.append(np.ones(block, dtype=np.uint8))  # touched: resident
            time.sleep(0.02)  # the nanny's memory monitor polls every 100 ms
        while True:
            time.sleep(3600)
    elif kind == "exit":
        os._exit(3)
    elif kind:
        raise ValueError(f"RAST5D_TEST_FAULTS: unknown action {action!r}")


def _wrap(points_module) -> None:
    spec = json.loads(_SPEC)
    actions, log = spec.get("points", {}), spec.get("log")
    render = points_module.POINT_KINDS["render"]

    def faulty_render(config, *args, **kwargs):
        seed = str(config.samples.seed)
        if log:
            with open(os.path.join(log, f"{seed}-{os.getpid()}-{time.time_ns()}"), "w") as f:
                f.write(str(os.getpid()))
        _act(actions.get(seed, actions.get("*", "")))
        return render(config, *args, **kwargs)

    points_module.POINT_KINDS["render"] = faulty_render


class _Hook(importlib.abc.MetaPathFinder):
    """Wraps experiments.run.points' render point kind as soon as that module is imported."""

    def find_spec(self, name, path=None, target=None):
        if name != "experiments.run.points":
            return None
        sys.meta_path.remove(self)
        try:
            spec = importlib.util.find_spec(name)
        finally:
            sys.meta_path.insert(0, self)
        if spec is None:
            return None
        real_exec = spec.loader.exec_module

        def exec_module(module):
            real_exec(module)
            _wrap(module)

        spec.loader.exec_module = exec_module
        return spec


if _SPEC:
    sys.meta_path.insert(0, _Hook())


def _next_sitecustomize() -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    rest = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    spec = importlib.machinery.PathFinder.find_spec("sitecustomize", rest)
    if spec is not None and spec.origin and os.path.abspath(spec.origin) != os.path.abspath(__file__):
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)


_next_sitecustomize()

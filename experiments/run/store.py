"""The result store (results/, git-ignored; RAST5D_RESULTS moves it):

- ``results/points/<config hash>-<engine version>.parquet``: one finished point (one row), written
  as soon as the point finishes (so Ctrl-C or a crash keeps every finished point). This is the
  cache: a rerun renders only the points whose file is missing; ``force=True`` re-renders.
- ``results/<name>.parquet``: the sweep's table (one row per point of the current sweep, failed
  points included with ``status = "error"`` and their message), written when the sweep ends or is
  interrupted; ``experiments.load(name)`` reads it.
- ``results/records/<hash>-<engine version>.npz``: the timing work records and counters of a
  render, read by `retime` points (experiments/run/points.py).
- ``results/references/``: reference images of the image-error metrics (experiments/run/references.py).

A row is the flattened resolved config (``camera.coc_px``, ``samples.kind``, ``pipeline.algorithm``,
``hardware.setup.throughput``, ...; camera fields the scene's hint filled in are resolved), every
counter and derived figure of ``Result.flat_stats``, ``time.wall_s``, ``engine.version``,
``engine.git_rev``, ``config_hash``, ``status``, ``error`` (and ``metric.*`` with outputs.metrics).
"""
from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

from ..config import REPO

RESULTS = Path(os.environ.get("RAST5D_RESULTS", REPO / "results"))
_ENGINE_ID = None
_GIT_REV = None


def results_dir() -> Path:
    return Path(os.environ.get("RAST5D_RESULTS", RESULTS))


def engine_id() -> str:
    """The engine version: a fingerprint of the compiled engine and of the Python that drives it
    (sim/, models/). Cached points are only reused by the same engine."""
    global _ENGINE_ID
    if _ENGINE_ID is None:
        import hashlib

        import sim

        h = hashlib.sha256(Path(sim._core.__file__).read_bytes())
        for folder in ("sim", "sim/uses", "models"):
            for f in sorted((REPO / folder).glob("*.py")):
                h.update(f.read_bytes())
        _ENGINE_ID = h.hexdigest()[:12]
    return _ENGINE_ID


def git_rev() -> str:
    global _GIT_REV
    if _GIT_REV is None:
        try:
            rev = subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, text=True,
                                          stderr=subprocess.DEVNULL).strip()
            dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", "sim", "models", "experiments"],
                                   cwd=REPO, stderr=subprocess.DEVNULL).returncode
            _GIT_REV = rev + ("-dirty" if dirty else "")
        except Exception:  # noqa: BLE001 - not a git checkout
            _GIT_REV = "unknown"
    return _GIT_REV


def point_path(h: str) -> Path:
    return results_dir() / "points" / f"{h}-{engine_id()}.parquet"


def to_frame(rows: list[dict]):
    import pandas as pd

    df = pd.DataFrame([{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in r.items()}
                       for r in rows])
    for col in df.columns:  # Parquet needs one type per column: mixed columns become text
        if df[col].dtype == object:
            types = {type(v) for v in df[col] if v is not None}
            if len(types) > 1 and not types <= {int, float}:
                df[col] = [None if v is None else str(v) for v in df[col]]
            elif types <= {int, float} and types:
                df[col] = df[col].astype(float)
    return df


def atomic_write(path: Path, write, suffix: str = "") -> None:
    """``write(tmp)`` to a temporary file beside ``path`` (named ``<name>.tmp<pid><suffix>``, so no
    store glob matches it; ``suffix`` for writers that append their own), then rename it over
    ``path``: a reader (another worker, a later run) never sees half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.tmp{os.getpid()}{suffix}")
    write(tmp)
    os.replace(tmp, path)


def write_parquet(df, path: Path):
    atomic_write(path, lambda tmp: df.to_parquet(tmp, index=False, engine="pyarrow"))


def store_point(row: dict):
    if row.get("status") == "ok":
        write_parquet(to_frame([row]), point_path(row["config_hash"]))


def cached_row(h: str) -> dict | None:
    import pandas as pd

    p = point_path(h)
    if not p.exists():
        return None
    try:
        return pd.read_parquet(p).iloc[0].to_dict()
    except Exception:  # noqa: BLE001 - a corrupt cache file is recomputed
        return None


def images_dir(name: str) -> Path:
    """Where a sweep with outputs.images keeps the images of its points (one PNG per config hash)."""
    return results_dir() / "images" / name


def table_path(name: str) -> Path:
    return results_dir() / f"{name}.parquet"


def load(name: str):
    """The result table of experiment ``name`` (results/<name>.parquet) as a pandas DataFrame."""
    import pandas as pd

    p = table_path(name)
    if not p.exists():
        known = sorted(q.stem for q in results_dir().glob("*.parquet"))
        raise FileNotFoundError(f"no results for {name!r} ({p}); run `rast5d run` first (known: {known})")
    return pd.read_parquet(p)


def records_path(h: str) -> Path:
    return results_dir() / "records" / f"{h}-{engine_id()}.npz"


def store_records(h: str, records, stats: dict) -> None:
    """The timing records and flat counters of one render, for retime points."""
    import json

    import numpy as np

    atomic_write(records_path(h),
                 lambda tmp: np.savez(tmp, records=records, stats=np.array(json.dumps(stats, default=str))),
                 suffix=".npz")


def cached_records(h: str):
    """(records, flat counters) of a stored render, or None."""
    import json

    import numpy as np

    p = records_path(h)
    if not p.exists():
        return None
    try:
        with np.load(p) as f:
            return f["records"], json.loads(str(f["stats"]))
    except Exception:  # noqa: BLE001 - a corrupt file is recomputed
        return None

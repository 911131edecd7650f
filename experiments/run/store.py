"""The result store (./results under the working directory; ``--results DIR`` or RAST5D_RESULTS
moves it, experiments/paths.py):

- ``results/points/<config hash>-<engine version>.parquet``: one finished point (one row), written
  as soon as the point finishes (so Ctrl-C or a crash keeps every finished point). This is the
  cache: a rerun renders only the points whose file is missing; ``force=True`` re-renders. The
  config hash covers the contents of every file the point's scenes read (experiments/config/inputs.py)
  and the engine version covers the installed package, so an edited scene, mesh, texture or module
  gives new keys. A failed point is stored too, with its error and traceback, and is served as
  failed until a run with ``retry_failed=True`` (``rast5d run --retry-failed``) re-renders it.
  Each file carries a checksum of its row (Parquet metadata ``rast5d.sha256``) and Parquet page
  checksums: a truncated or corrupted file is detected when read and recomputed with a
  ``StoreWarning``. A row also lists the files read while it was computed (``inputs.files``); it is
  served only while they are unchanged.
- ``results/points/<config hash>-<engine version>.lock``: a point being computed by a running
  ``rast5d run`` (host and pid inside). Another run sharing the store waits for that point instead of
  computing it again; a lock whose process is gone (same host) or older than
  ``RAST5D_LOCK_TIMEOUT`` seconds (default one day) is taken over. Every file is written to a
  temporary name unique to its host and process and renamed into place, so a reader never sees half
  a file. A point file is put in place only if no other run stored that point first (a hard link,
  which fails on an existing name): a point computed twice (a file system without working locks,
  ``rast5d run --no-lock``) keeps the first row stored, and both runs serve that one.
- A write that fails (a full disk, a read-only store) raises StoreError: the run stops, the temporary
  file is removed, and every point stored before stays readable. docs/store.md states what the store
  promises under each fault.
- ``results/<name>.parquet``: the sweep's table (one row per point of the current sweep, failed
  points included with ``status = "error"`` and their message), written when the sweep ends or is
  interrupted; ``experiments.load(name)`` reads it.
- ``results/records/<hash>-<engine version>.npz``: the timing work records and counters of a
  render, read by `retime` points (experiments/run/points.py).
- ``results/pictures/<hash>-<engine version>.npz``: the image and per-pixel statistics maps of a
  point that a report page pictures (``kind: image``, ``kind: heatmap`` with ``map:``), kept by the
  render of its sweep point and read by the page (experiments/report/heatmaps.py); served only while
  the files the point read are unchanged.
- ``results/references/``: reference images of the image-error metrics (experiments/run/references.py).

A row is the flattened resolved config (``camera.coc_px``, ``samples.kind``, ``pipeline.algorithm``,
``hardware.setup.throughput``, ...; camera fields the scene's hint filled in are resolved), every
counter and derived figure of ``Result.flat_stats``, ``time.wall_s``, ``engine.version``,
``engine.git_rev``, ``config_hash``, ``status``, ``error`` (and ``metric.*`` with outputs.metrics).
"""
from __future__ import annotations

import errno
import math
import os
import subprocess
from pathlib import Path

from ..paths import PACKAGE_ROOT as REPO  # the checkout (or site-packages)

_ENGINE_ID = None
_GIT_REV = None


def results_dir() -> Path:
    """The result store: $RAST5D_RESULTS, else ./results (experiments/paths.py)."""
    from ..paths import results_dir as _results_dir

    return _results_dir()


class StoreWarning(UserWarning):
    """A stored file could not be used (truncated, corrupted, unreadable) and is recomputed; or the
    store's file system cannot lock points (check_locks)."""


class RunStopped(RuntimeError):
    """A sweep stopped on a fault of the machinery it runs on (the result store's disk, the Dask
    cluster), not of its input: the points finished before are stored, a rerun computes the rest."""


class StoreError(RunStopped):
    """The result store cannot be written (a full disk or quota, a read-only file system, no
    permission): the run stops; nothing half-written is left where a read would find it."""


# Why a write failed, by errno, and what the user does about it.
_WRITE_FAULTS = {
    errno.ENOSPC: ("the disk is full", "free some space"),
    errno.EDQUOT: ("the disk quota is exceeded", "free some space or raise the quota"),
    errno.EROFS: ("the file system is read-only", "make the store writable or give another --results DIR"),
    errno.EACCES: ("permission denied", "make the store writable or give another --results DIR"),
    errno.EPERM: ("operation not permitted", "make the store writable or give another --results DIR"),
    errno.EIO: ("an input/output error of the disk", "check the disk"),
    errno.EFBIG: ("the file is larger than this process may write (ulimit -f)", "raise the limit"),
}


def _errno_of(e: BaseException) -> int | None:
    """The errno of an OSError, also when a library (pyarrow) gives it only in the message."""
    if getattr(e, "errno", None):
        return e.errno
    import re

    m = re.search(r"\[errno (\d+)\]", str(e), flags=re.I)
    return int(m.group(1)) if m else None


# A write error that is the disk's, wherever it happens (a point's image, records, row): not the point's.
DISK_FAULTS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS}


def disk_fault(e: BaseException) -> StoreError | None:
    """The StoreError of ``e`` if it is a fault of the disk (full, over quota, read-only), else None."""
    if isinstance(e, StoreError):
        return e
    if isinstance(e, OSError) and _errno_of(e) in DISK_FAULTS:
        return store_error(Path(e.filename) if getattr(e, "filename", None) else results_dir(), e)
    return None


def store_error(path: Path, e: BaseException) -> StoreError:
    """The StoreError of a failed write of ``path``, saying why (by errno) and what to do."""
    code = _errno_of(e)
    why, todo = _WRITE_FAULTS.get(code, (f"{type(e).__name__}: {e}", "fix the store"))
    detail = f" ({os.strerror(code)})" if code in _WRITE_FAULTS else ""
    return StoreError(f"result store: cannot write {path}: {why}{detail}. The run stops here; every point "
                      f"finished before is stored and readable, and no partial file is left. {todo[0].upper()}"
                      f"{todo[1:]} and rerun: only the missing points are computed.")


# Folders of the installed package whose files do not enter a result row (the report pages only read
# rows): editing a figure does not invalidate the store.
_NOT_IN_ROWS = ("experiments/report/",)


def package_files() -> list[Path]:
    """Every file of the installed package that a result row depends on: the compiled engine and the
    files under sim/, models/ (assets included) and experiments/ (except _NOT_IN_ROWS), without
    caches and build trees."""
    import sim

    root = Path(sim.__file__).resolve().parent.parent
    files = {Path(sim._core.__file__).resolve()}
    for folder in ("sim", "models", "experiments"):
        for f in (root / folder).rglob("*"):
            rel = f.relative_to(root).as_posix()
            if (not f.is_file() or "__pycache__" in f.parts or f.suffix in (".pyc", ".so")
                    or rel.startswith(_NOT_IN_ROWS)):
                continue
            files.add(f)
    return sorted(files)


def engine_id() -> str:
    """The engine version: a fingerprint of the whole installed package (package_files: the compiled
    engine, every module and asset). Cached points are only reused by the same package."""
    global _ENGINE_ID
    if _ENGINE_ID is None:
        import hashlib

        root = Path(__import__("sim").__file__).resolve().parent.parent
        h = hashlib.sha256()
        for f in package_files():
            h.update(str(f.relative_to(root) if f.is_relative_to(root) else f.name).encode() + b"\0")
            h.update(f.read_bytes())
        _ENGINE_ID = h.hexdigest()[:12]
    return _ENGINE_ID


def git_rev() -> str:
    global _GIT_REV
    if _GIT_REV is None:
        from ..paths import CHECKOUT

        try:
            if not CHECKOUT:  # an installed wheel: no revision (its folder may sit in some other repository)
                raise FileNotFoundError
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


def table_columns(rows: list[dict]) -> dict[str, list]:
    """{column: values} of a sweep's rows with the types to_frame gives them, without pandas: every
    column of any row (a row without it: missing), NaN as missing, a column of mixed types as text, of
    ints and floats (or ints with a missing value) as floats with NaN for missing, else None."""
    names: dict[str, None] = {}
    for r in rows:
        names.update(dict.fromkeys(r))
    out = {}
    for c in names:
        vals = [r.get(c) for r in rows]
        vals = [None if isinstance(v, float) and math.isnan(v) else v for v in vals]
        types = {type(v) for v in vals if v is not None}
        if len(types) > 1 and not types <= {int, float}:
            vals = [None if v is None else str(v) for v in vals]
        elif types and types <= {int, float} and (float in types or None in vals):
            vals = [math.nan if v is None else float(v) for v in vals]
        out[c] = vals
    return out


class SweepRows(list):
    """A sweep's rows (dicts, in sweep order) and the run's ``summary``: what run_sweep(frame=False)
    returns instead of a DataFrame."""

    summary: dict = {}


# Errors of os.link on a file system without hard links (some FUSE and SMB mounts): the point is then
# put in place by a rename after a check that no other run stored it (a narrow race, see store_point).
_NO_LINKS = {errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.ENOSYS, errno.EMLINK, errno.EXDEV}


def temporary_name(path: Path, suffix: str = "") -> Path:
    """A temporary name beside ``path``, unique to this host, process and call
    (``<name>.tmp-<host>-<pid>-<random><suffix>``): no store glob matches it, and two machines sharing
    the store never write the same temporary file."""
    import secrets
    import socket

    return path.with_name(f"{path.name}.tmp-{socket.gethostname()}-{os.getpid()}-{secrets.token_hex(4)}{suffix}")


def atomic_write(path: Path, write, suffix: str = "", keep=None) -> bool:
    """``write(tmp)`` to a temporary file beside ``path`` (temporary_name; ``suffix`` for writers that
    append their own), then put it in place: a reader (another worker, a later run) never sees half a
    file. Without ``keep`` it is renamed over ``path``. With ``keep`` (a function of the path) it is
    linked to ``path`` only if no file is there; if one is and ``keep(path)`` is true, that file stays
    and this write is dropped. Returns whether this write was put in place. A failing write (a full
    disk, a read-only store) removes the temporary file and raises StoreError."""
    tmp = temporary_name(path, suffix)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write(tmp)
        if keep is None:
            os.replace(tmp, path)
            return True
        try:
            os.link(tmp, path)
            installed = True
        except FileExistsError:
            installed = False
        except OSError as e:
            if e.errno not in _NO_LINKS:
                raise
            installed = None  # no hard links here: check, then rename
        if installed is None:
            installed = not (path.exists() and keep(path))
            if installed:
                os.replace(tmp, path)
        elif not installed and not keep(path):
            os.replace(tmp, path)
            installed = True
        return installed
    except OSError as e:
        raise store_error(path, e) from e
    finally:
        try:
            os.unlink(tmp)
        except OSError:
            pass


_ROWS_KEY = b"rast5d.rows"


def rows_digest(rows: list[dict]) -> str:
    import hashlib
    import json

    def plain(v):  # numpy scalars (a row just computed) as the Python values a stored row reads back as
        return v.item() if hasattr(v, "item") else repr(v)

    rows = [{k: None if isinstance(v, float) and math.isnan(v) else v for k, v in r.items()} for r in rows]
    return hashlib.sha256(json.dumps(rows, default=plain).encode()).hexdigest()


def write_table(rows: list[dict], path: Path) -> bool:
    """A sweep's table (results/<name>.parquet, to_frame(rows) as pandas writes it) with a digest of
    its rows in the file's metadata; a file that already holds these rows is left as it is (a rerun
    served from the store writes nothing, and imports no pandas). Returns whether it was written."""
    import pyarrow.parquet as pq

    digest = rows_digest(rows).encode()
    try:
        if (pq.read_schema(path).metadata or {}).get(_ROWS_KEY) == digest:
            return False
    except Exception:  # noqa: BLE001 - no file, or one that cannot be read: written anew
        pass
    import pyarrow as pa

    table = pa.Table.from_pandas(to_frame(rows), preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), _ROWS_KEY: digest})
    atomic_write(path, lambda tmp: pq.write_table(table, tmp))
    return True


_CHECKSUM_KEY = b"rast5d.sha256"


def _table_digest(table, values: list | None = None) -> str:
    """sha256 of a pyarrow table's column names, types and values (not of its file bytes: the same
    row read back gives the same digest). ``values``: the columns' to_pylist(), when already made.
    The hashed text is, column after column, json.dumps([name, str(type), values], default=repr);
    _json_value writes the common values as json does, without a call into json per column."""
    import hashlib
    import json

    encode = json.JSONEncoder(default=repr).encode
    types = [encode(str(t)) for t in table.schema.types]
    if values is None:
        values = [col.to_pylist() for col in table.columns]
    text = "".join(f"[{encode(name)}, {types[i]}, [{', '.join(_json_value(v, encode) for v in values[i])}]]"
                   for i, name in enumerate(table.column_names))
    return hashlib.sha256(text.encode()).hexdigest()


def _json_value(v, encode) -> str:
    """json.dumps(v, default=repr) for one value."""
    t = type(v)
    if v is None:
        return "null"
    if t is bool:
        return "true" if v else "false"
    if t is int:
        return int.__repr__(v)
    if t is float:
        if v != v:
            return "NaN"
        if v in (math.inf, -math.inf):
            return "Infinity" if v > 0 else "-Infinity"
        return float.__repr__(v)
    return encode(v)


def _row_columns(row: dict):
    """(the one-row pyarrow table of a result row, its columns' to_pylist()), or None for a row with a
    value of another type (it takes the DataFrame path). The table has the column types that pandas
    gives the row (to_frame([row]) through pyarrow: float64, int64, bool, string, null for a missing
    value; NaN is stored as missing) without building a DataFrame (a row has hundreds of columns). The
    Python values of one type share one arrow array, sliced per column (one array per value costs ten
    times as long); a numpy scalar keeps its own array (its dtype: float32 stays float32)."""
    import pyarrow as pa

    names, arrays, values, groups = [], [], [], {}
    for k, v in row.items():
        if isinstance(v, float) and math.isnan(v):
            v = None
        t = type(v)
        if v is not None and t not in (bool, int, float, str):
            if not isinstance(v, np_scalar_types()):
                return None
            arrays.append(pa.array([v]))
            v = v.item()
        else:
            arrays.append(None)
            if v is not None:
                groups.setdefault(t, []).append(len(names))
        names.append(k)
        values.append([v])
    for t, where in groups.items():
        shared = pa.array([values[i][0] for i in where], type=_text_type() if t is str else None)
        for j, i in enumerate(where):
            arrays[i] = shared.slice(j, 1)
    arrays = [pa.nulls(1) if a is None else a for a in arrays]
    return pa.Table.from_arrays(arrays, names=names), values


_TEXT_TYPE = []


def _text_type():
    """The arrow type pandas gives a text column (string, or large_string with pandas' arrow strings)."""
    if not _TEXT_TYPE:
        import pandas as pd
        import pyarrow as pa

        _TEXT_TYPE.append(pa.Table.from_pandas(pd.DataFrame({"a": ["x"]}), preserve_index=False).schema.types[0])
    return _TEXT_TYPE[0]


def np_scalar_types() -> tuple:
    import numpy as np

    return (np.bool_, np.integer, np.floating)


def write_point_file(df, path: Path, keep=None) -> bool:
    """One point's row (a one-row DataFrame, or the row's dict) with its checksum (Parquet metadata)
    and Parquet page checksums, atomically. ``keep``: as for atomic_write (a file already there that
    ``keep`` accepts stays). Returns whether this row was put in place."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    made = _row_columns(df) if isinstance(df, dict) else None
    if made is None:
        table = pa.Table.from_pandas(to_frame([df]) if isinstance(df, dict) else df, preserve_index=False)
        values = [col.to_pylist() for col in table.columns]
    else:
        table, values = made
    meta = dict(table.schema.metadata or {})
    meta[_CHECKSUM_KEY] = _table_digest(table, values).encode()
    table = table.replace_schema_metadata(meta)
    # One row of a few hundred columns: no compression and no dictionary pages write it in about half
    # the time (the column chunks are a few bytes each; the file is as small).
    installed = atomic_write(path, lambda tmp: pq.write_table(table, tmp, write_page_checksum=True, compression="none",
                                                              use_dictionary=False), keep=keep)
    if installed:
        _remember(path, _table_row(table, values))
    return installed


# The rows this process wrote or read, by point file and the file's identity (mtime, size, inode and
# a digest of its bytes): `rast5d report` reads back every row its pool just stored. A file replaced
# or modified since (another run, a rewrite, damage in place within one mtime tick) has another
# identity and is read, and checked, again.
_ROWS: dict = {}


def _stat_identity(path: Path) -> tuple:
    """(mtime, size, inode) of a file; OSError if it is not there."""
    st = os.stat(path)
    return st.st_mtime_ns, st.st_size, st.st_ino


def _identity(path: Path):
    import hashlib

    return (*_stat_identity(path), hashlib.blake2b(path.read_bytes(), digest_size=16).digest())


def _remember(path: Path, row: dict) -> None:
    try:
        _ROWS[str(path)] = (_identity(path), row)
    except OSError:
        pass


def _table_row(table, values: list) -> dict:
    """The row of a one-row table (values: its columns' to_pylist())."""
    if all(pa_numeric(t) for t in table.schema.types):  # one numeric dtype: pandas would cast it
        return table.to_pandas().iloc[0].to_dict()
    # A one-row table of mixed column types: DataFrame.iloc[0].to_dict() gives each value as a Python
    # scalar, as to_pylist does, without building the DataFrame.
    return {name: v[0] for name, v in zip(table.column_names, values)}


def read_point_file(path: Path) -> dict:
    """The row of a point file; raises ValueError if the file is truncated, corrupted or has no checksum."""
    import pyarrow.parquet as pq

    try:  # ParquetFile reads the one file directly (read_table would import pyarrow.dataset: 0.2 s)
        table = pq.ParquetFile(path, page_checksum_verification=True).read()
    except Exception as e:  # noqa: BLE001 - any read failure means the file cannot be trusted
        raise ValueError(f"unreadable ({type(e).__name__}: {e})") from None
    stored = (table.schema.metadata or {}).get(_CHECKSUM_KEY)
    if stored is None:
        raise ValueError("no checksum")
    values = [col.to_pylist() for col in table.columns]
    if stored.decode() != _table_digest(table, values):
        raise ValueError("checksum mismatch (the file was modified or corrupted)")
    if table.num_rows != 1:
        raise ValueError(f"expected one row, found {table.num_rows}")
    return _table_row(table, values)


def pa_numeric(t) -> bool:
    import pyarrow as pa

    return pa.types.is_integer(t) or pa.types.is_floating(t) or pa.types.is_boolean(t)


def store_point(row: dict, replace: bool = False, replace_failed: bool = False) -> dict:
    """Store a finished point (failed ones too, with their error and traceback), unless the row is
    marked transient (a lost Dask worker: nothing about the point itself); returns the row the store
    holds for the point. If another run stored the point first (it computed it too: a store without
    working locks, ``--no-lock``), its row is kept and returned, so every run serves the same row;
    unless that row cannot be served (damaged, an input changed since), or it failed and this one did
    not or ``replace_failed`` (``--retry-failed``), or ``replace`` (``--force``). Raises StoreError if
    the store cannot be written."""
    if row.pop("_transient", False):
        return row
    h = row["config_hash"]
    kept: list = []

    def keep(path: Path) -> bool:
        if replace:
            return False
        stored = cached_row(h)
        if stored is None or (stored.get("status") != "ok" and (row.get("status") == "ok" or replace_failed)):
            return False
        kept.append(stored)
        return True

    write_point_file(row, point_path(h), keep=keep)
    return kept[0] if kept else row


def cached_row(h: str, retry_failed: bool = False) -> dict | None:
    """The stored row of point ``h``, or None when it must be computed: no file, a failed point with
    ``retry_failed``, a file that fails its read check (a StoreWarning says so), or an input file
    that changed since the row was computed."""
    import json
    import warnings

    from ..config.inputs import unchanged

    p = point_path(h)
    try:
        ident = _identity(p)
    except OSError:
        return None
    hit = _ROWS.get(str(p))
    try:
        if hit is not None and hit[0] == ident:
            row = dict(hit[1])
        else:
            row = read_point_file(p)
            if _identity(p) == ident:
                _ROWS[str(p)] = (ident, dict(row))
    except (FileNotFoundError, OSError):
        return None
    except ValueError as e:
        warnings.warn(f"{p}: {e}; the point is recomputed", StoreWarning, stacklevel=2)
        return None
    if retry_failed and row.get("status") != "ok":
        return None
    files = row.get("inputs.files")
    if isinstance(files, str) and files:
        try:
            if unchanged(json.loads(files)) is not None:
                return None
        except ValueError:
            return None
    return row


# ---- locks: one run computes a point, the others wait for it -----------------------------------------

def lock_path(h: str) -> Path:
    return point_path(h).with_suffix(".lock")


def _lock_owner(path: Path) -> tuple[str, int, float] | None:
    try:
        host, pid, t = path.read_text().split()
        return host, int(pid), float(t)
    except (OSError, ValueError):
        return None


def _alive(host: str, pid: int) -> bool:
    import socket

    if host != socket.gethostname():
        return True  # cannot tell: trusted until it times out
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def lock_is_stale(path: Path) -> bool:
    import time

    owner = _lock_owner(path)
    if owner is None:
        try:  # being written right now, or garbage: stale only when old
            return time.time() - path.stat().st_mtime > 60
        except FileNotFoundError:
            return False
    host, pid, t = owner
    timeout = float(os.environ.get("RAST5D_LOCK_TIMEOUT", 86400))
    return not _alive(host, pid) or time.time() - t > timeout


# errnos of an exclusive create on a file system that cannot do it (not a full or read-only one)
_NO_EXCL = {errno.ENOTSUP, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL, errno.ENOLCK}
_LOCKS_CHECKED: dict[str, bool] = {}


def check_locks(directory: Path | None = None) -> bool:
    """Whether point locks work in the store ``directory`` (default: results_dir()): an exclusive create
    (O_EXCL) of a probe file succeeds once and fails the second time. Checked once per directory and
    process; if it does not, a StoreWarning says what that means and the run computes without locks."""
    import secrets
    import socket

    d = (Path(directory) if directory is not None else results_dir()) / "points"
    if str(d) in _LOCKS_CHECKED:
        return _LOCKS_CHECKED[str(d)]
    probe = d / f".lockprobe-{socket.gethostname()}-{os.getpid()}-{secrets.token_hex(4)}"
    why = None
    try:
        d.mkdir(parents=True, exist_ok=True)
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644))
        try:
            os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644))
            why = "a second exclusive create (O_EXCL) of one file succeeded"
        except FileExistsError:
            pass
    except OSError as e:
        if e.errno not in _NO_EXCL:
            raise store_error(probe, e) from e
        why = f"an exclusive create (O_EXCL) fails: {e.strerror or e}"
    finally:
        try:
            os.unlink(probe)
        except OSError:
            pass
    _LOCKS_CHECKED[str(d)] = why is None
    if why is not None:
        _warn_no_locks(d, why)
    return why is None


def _warn_no_locks(d: Path, why: str) -> None:
    import warnings

    _LOCKS_CHECKED[str(d)] = False
    warnings.warn(f"result store {d.parent}: point locks do not work on this file system ({why}). This run "
                  "computes its points without locks: a run sharing this store may compute the same point "
                  "again (the first row stored is kept and both runs serve it, so rows stay identical; no "
                  "reader sees a torn file). To compute each point once, run one sweep at a time on this store, "
                  "or give each concurrent sweep its own --results DIR.", StoreWarning, stacklevel=3)


def claim(h: str, locks: bool = True) -> bool:
    """Take the lock of point ``h`` for this process; False if another live process holds it.
    ``locks=False`` (``rast5d run --no-lock``, or a store whose file system cannot lock: check_locks)
    takes and honours no lock: always True. Raises StoreError if the store cannot be written."""
    import socket
    import time

    if not locks or not _LOCKS_CHECKED.get(str(results_dir() / "points"), True):
        return True
    path = lock_path(h)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise store_error(path.parent, e) from e
    for _ in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            if lock_is_stale(path):
                # take over: rename the stale lock away first (only one taker wins the rename)
                try:
                    os.replace(path, path.with_name(f"{path.name}.stale{os.getpid()}"))
                    os.unlink(path.with_name(f"{path.name}.stale{os.getpid()}"))
                except FileNotFoundError:
                    pass
                continue
            return False
        except OSError as e:
            if e.errno in _NO_EXCL:  # the file system cannot lock: warn and go on without
                _warn_no_locks(path.parent, f"an exclusive create (O_EXCL) fails: {e.strerror or e}")
                return True
            raise store_error(path, e) from e
        try:
            with os.fdopen(fd, "w") as f:
                f.write(f"{socket.gethostname()} {os.getpid()} {time.time()}")
        except OSError as e:
            try:
                path.unlink()
            except OSError:
                pass
            raise store_error(path, e) from e
        return True
    return False


def release(h: str) -> None:
    """Drop this process's lock of point ``h`` (if it holds it). A lock that cannot be removed (a store
    turned read-only) is left: its process is gone once the run ends, so the next run takes it over."""
    import socket

    path = lock_path(h)
    owner = _lock_owner(path)
    if owner is not None and owner[:2] == (socket.gethostname(), os.getpid()):
        try:
            path.unlink()
        except OSError:
            pass


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


# The timing records this process stored or read last, by file (a retime sweep re-times one render's
# records at many hardware points: each worker reads the file once, not once per point), while their
# file keeps its identity (mtime, size, inode), within _RECORDS_BUDGET bytes, least recently used out.
_RECORDS: dict = {}
_RECORDS_BUDGET = 256 * 2 ** 20


def _remember_records(path: Path, identity: tuple, records, stats: dict) -> None:
    records.setflags(write=False)  # shared by every point that re-times them
    _RECORDS.pop(str(path), None)
    _RECORDS[str(path)] = (identity, records, stats)
    while sum(r.nbytes for _, r, _ in _RECORDS.values()) > _RECORDS_BUDGET and len(_RECORDS) > 1:
        del _RECORDS[next(iter(_RECORDS))]


def store_records(h: str, records, stats: dict) -> None:
    """The timing records and flat counters of one render, for retime points."""
    import json

    import numpy as np

    path, text = records_path(h), json.dumps(stats, default=str)
    atomic_write(path, lambda tmp: np.savez(tmp, records=records, stats=np.array(text)), suffix=".npz")
    try:
        _remember_records(path, _stat_identity(path), records, json.loads(text))  # as a reader gets them
    except OSError:
        pass


def cached_records(h: str):
    """(records, flat counters) of a stored render, or None (a corrupt file is recomputed with a
    StoreWarning)."""
    import json
    import warnings

    import numpy as np

    from ..config.inputs import unchanged

    p = records_path(h)
    try:
        identity = _stat_identity(p)
    except OSError:
        return None
    kept = _RECORDS.get(str(p))
    if kept is not None and kept[0] == identity:
        _RECORDS[str(p)] = _RECORDS.pop(str(p))  # most recently used
        records, stats = kept[1], kept[2]
    else:
        try:
            with open(p, "rb") as fh, np.load(fh) as f:  # an npz member carries a CRC-32, checked on read
                records, stats = f["records"], json.loads(str(f["stats"]))
        except Exception as e:  # noqa: BLE001 - a corrupt file is recomputed
            warnings.warn(f"{p}: unreadable ({type(e).__name__}: {e}); the render is recomputed", StoreWarning,
                          stacklevel=2)
            return None
        _remember_records(p, identity, records, stats)
    files = stats.get("inputs.files")
    if isinstance(files, str) and files and unchanged(json.loads(files)) is not None:
        return None
    return records, stats


# ---- pictures: the arrays a report page draws of a point (experiments/report/heatmaps.py) -----------

def pictures_path(h: str) -> Path:
    return results_dir() / "pictures" / f"{h}-{engine_id()}.npz"


def store_pictures(h: str, arrays: dict, inputs_files: str) -> None:
    """The image and pixel-statistics maps of point ``h`` that a page pictures ({'image': ...,
    'map:<counter>': ...}), with the files the point read (``inputs.files``, JSON)."""
    import numpy as np

    atomic_write(pictures_path(h), lambda tmp: np.savez(tmp, inputs=np.array(inputs_files), **arrays),
                 suffix=".npz")


def cached_pictures(h: str) -> dict | None:
    """The stored picture arrays of point ``h`` (see store_pictures), or None: none stored for this
    engine version, an input file changed since, or an unreadable file (a StoreWarning says so)."""
    import json
    import warnings

    import numpy as np

    from ..config.inputs import unchanged

    p = pictures_path(h)
    if not p.exists():
        return None
    try:
        with open(p, "rb") as fh, np.load(fh) as f:  # an npz member carries a CRC-32, checked on read
            arrays = {k: f[k] for k in f.files}
        files = json.loads(str(arrays.pop("inputs")))
    except Exception as e:  # noqa: BLE001 - a corrupt file is rendered again
        warnings.warn(f"{p}: unreadable ({type(e).__name__}: {e}); the point is rendered again", StoreWarning,
                      stacklevel=2)
        return None
    if files and unchanged(files) is not None:
        return None
    return arrays

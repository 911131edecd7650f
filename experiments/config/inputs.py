"""The input files of a point: every file read while its scenes are built (a scene YAML, the meshes,
materials and textures it names, arrays a scene module loads), by content.

A point's identity in the result store (``config_hash``) covers the contents of these files, so
editing a scene file, a mesh or a texture that a config names gives the point a new key and it is
recomputed. The files are found by watching what the build opens (Python's ``open`` audit event),
not by parsing the scene formats, so every importer is covered without being listed here. Files of
the installed package itself (``sim``, ``models``, ``experiments``) and of the Python installation
are left out: the package is covered by the engine version (experiments/run/store.py).
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import stat
import sys
import threading
from pathlib import Path

_PACKAGE_DIRS = tuple(str(Path(__file__).resolve().parents[2] / d) + os.sep for d in ("sim", "models", "experiments"))
_SKIP_SUFFIXES = (".py", ".pyc", ".so", ".pth", ".pyi")
_lock = threading.Lock()
_active: list[set] = []
_hook_installed = False
_digests: dict[str, tuple[tuple, str]] = {}  # path -> ((mtime_ns, size, inode), sha256)
_scene_memo: dict[str, dict[str, str]] = {}  # scene spec JSON -> {path: sha256}


def _audit(event: str, args) -> None:
    if event != "open" or not _active:
        return
    path, mode, flags = args
    if not isinstance(path, (str, bytes, os.PathLike)):
        return  # a file descriptor
    if mode is not None:
        if any(c in mode for c in "wax+"):
            return
    elif flags is not None and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
        return
    with _lock:
        for reads in _active:
            reads.add(os.fsdecode(path))


@contextlib.contextmanager
def tracking_reads():
    """Collect the paths of the files opened for reading inside the block (a set, filled on exit too)."""
    global _hook_installed
    if not _hook_installed:
        sys.addaudithook(_audit)  # process-wide and permanent; does nothing while no block is active
        _hook_installed = True
    reads: set = set()
    with _lock:
        _active.append(reads)
    try:
        yield reads
    finally:
        with _lock:  # by identity: two sets with the same paths are equal
            del _active[next(i for i, r in enumerate(_active) if r is reads)]


def _excluded_roots() -> tuple[str, ...]:
    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix, "/proc", "/sys", "/dev"}
    from ..paths import results_dir

    roots.add(str(results_dir()))
    return tuple(str(Path(r).resolve()) + os.sep for r in roots) + _PACKAGE_DIRS


def file_digest(path: str) -> str | None:
    """sha256 of a file's contents (cached by mtime, size and inode), or None if it is not a readable file."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    if not stat.S_ISREG(st.st_mode):
        return None
    key = (st.st_mtime_ns, st.st_size, st.st_ino)
    hit = _digests.get(path)
    if hit is not None and hit[0] == key:
        return hit[1]
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return None
    _digests[path] = (key, h.hexdigest())
    return h.hexdigest()


def input_digests(paths) -> dict[str, str]:
    """{absolute path: sha256} of the regular files among ``paths``, leaving out the package and the
    Python installation (see the module docstring)."""
    skip = _excluded_roots()
    out = {}
    for p in paths:
        full = os.path.realpath(p)
        if full.endswith(_SKIP_SUFFIXES) or full.startswith(skip):
            continue
        d = file_digest(full)
        if d is not None:
            out[full] = d
    return dict(sorted(out.items()))


def unchanged(files: dict[str, str]) -> str | None:
    """None if every file still has its recorded contents, else the first path that changed or went."""
    for path, digest in files.items():
        if file_digest(path) != digest:
            return path
    return None


def scene_inputs(spec) -> dict[str, str]:
    """{path: sha256} of the files read to build a scene section (experiments.config.SceneSpec).

    Remembered per process and checked against the files' current contents on every call, so an edit
    between two calls is seen. A scene that fails to build has no remembered inputs: the point fails
    with the build's own error when it runs."""
    from .build import build_scene

    key = json.dumps(spec.model_dump(), sort_keys=True, default=str)
    files = _scene_memo.get(key)
    if files is not None and unchanged(files) is None:
        return files
    if spec.path is None and _package_only(key):  # a named scene that reads only the package's files
        _scene_memo[key] = {}
        return {}
    with tracking_reads() as reads:
        try:
            build_scene(spec)
        except Exception as e:  # noqa: BLE001 - reported by the point that renders it
            _scene_memo.pop(key, None)
            return {"<error>": f"{type(e).__name__}: {e}", **input_digests(reads)}
    files = input_digests(reads)
    _scene_memo[key] = files
    if spec.path is None and not files:
        _remember_package_only(key)
    return files


# Named scenes whose build read no file outside the installed package (the built-in scenes: their
# meshes are the package's assets), remembered on disk for this package (the engine version covers
# every package file) and working directory: a later process finds such a scene's inputs (none)
# without building it, so a cached run imports no mesh library. A scene that read any other file is
# built again in every process (its files' contents are checked anyway, and building it may read
# files that did not exist before).
def _package_only_path(key: str) -> Path:
    from ..paths import results_dir
    from ..run.store import engine_id

    digest = hashlib.sha256(f"{engine_id()}\0{os.getcwd()}\0{key}".encode()).hexdigest()[:24]
    return results_dir() / "inputs" / f"{digest}.json"


def _package_only(key: str) -> bool:
    try:
        return json.loads(_package_only_path(key).read_text()) == {"scene": json.loads(key), "files": {}}
    except (OSError, ValueError):
        return False


def _remember_package_only(key: str) -> None:
    from ..run.store import atomic_write, StoreError

    path = _package_only_path(key)
    text = json.dumps({"scene": json.loads(key), "files": {}}, sort_keys=True)
    try:
        atomic_write(path, lambda tmp: Path(tmp).write_text(text))
    except StoreError:
        pass  # a store that cannot be written: the scene is built again next time


def config_inputs(config) -> dict[str, str]:
    """{path: sha256} of every file the scenes of a point (its scene, and an occlusion query's) read."""
    files = dict(scene_inputs(config.scene))
    if config.point.kind == "occlusion_query" and config.point.query is not None:
        files.update(scene_inputs(config.point.query))
    return files

"""Where rast5d reads its configs and writes its results and pages.

- **Configs.** The report and starter configs ship with the package: in a wheel they are package data
  (``experiments/configs/``, copied from the checkout's ``configs/`` at build time); in a checkout they
  are ``configs/``. ``rast5d report`` reads ``--configs DIR``, else ``./configs`` when the working
  directory has one (``rast5d init`` makes it), else the shipped ones.
- **Results.** The result store is ``--results DIR``, else ``$RAST5D_RESULTS``, else ``./results``
  under the working directory.
- **Pages.** ``rast5d report`` writes ``--reports DIR``, else ``./reports`` under the working
  directory; ``rast5d run`` writes a config's page into the result store (``results/pages/``).

Nothing is ever written inside an installed package: a results or pages directory there, or one that
cannot be written, is a clear error (:class:`OutputDirError`) before the first render.
"""
from __future__ import annotations

import os
import sysconfig
import tempfile
from pathlib import Path

from sim.errors import ConfigError

PACKAGE_ROOT = Path(__file__).resolve().parents[1]  # the checkout, or site-packages for a wheel
CHECKOUT = (PACKAGE_ROOT / "pyproject.toml").exists()  # a source checkout (an editable install)


class OutputDirError(ConfigError):
    """A results or pages directory cannot be used: not writable, or inside the installed package."""


def bundled_configs() -> Path:
    """The configs shipped with the package: the wheel's package data, or the checkout's configs/."""
    packaged = Path(__file__).resolve().parent / "configs"
    return packaged if packaged.is_dir() else PACKAGE_ROOT / "configs"


def configs_dir(given: str | Path | None = None) -> Path:
    """The configs `rast5d report` reads: ``given``, else ./configs if the working directory has one,
    else the shipped configs (bundled_configs)."""
    if given is not None:
        path = Path(given)
        if not path.is_dir():
            raise ConfigError(f"--configs: not a directory: {path}")
        return path.resolve()
    local = Path.cwd() / "configs"
    return local.resolve() if local.is_dir() else bundled_configs()


def results_dir() -> Path:
    """The result store: $RAST5D_RESULTS (``--results DIR`` sets it), else ./results."""
    env = os.environ.get("RAST5D_RESULTS")
    return Path(env).expanduser().resolve() if env else (Path.cwd() / "results").resolve()


def reports_dir(given: str | Path | None = None) -> Path:
    """The pages of `rast5d report`: ``given``, else $RAST5D_REPORTS, else ./reports."""
    if given is not None:
        return Path(given).expanduser().resolve()
    env = os.environ.get("RAST5D_REPORTS")
    return Path(env).expanduser().resolve() if env else (Path.cwd() / "reports").resolve()


def _installed_roots() -> list[Path]:
    """The folders of an installed (non-checkout) package: its site-packages folders."""
    roots = {Path(sysconfig.get_paths()[k]).resolve() for k in ("purelib", "platlib")}
    if not CHECKOUT:
        roots.add(PACKAGE_ROOT)
    return sorted(roots)


def inside_installed_package(path: Path) -> bool:
    path = Path(path).resolve()
    return any(path == r or r in path.parents for r in _installed_roots())


def check_output_dir(path: str | Path, what: str, flag: str) -> Path:
    """``path`` created and writable, else OutputDirError naming ``what``, the path and ``flag`` (the
    option that moves it). Refuses a directory inside the installed package."""
    path = Path(path).expanduser().resolve()
    if inside_installed_package(path):
        raise OutputDirError(f"{what}: {path} is inside the installed package; run from a working directory "
                             f"of your own or give {flag}")
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path, prefix=".rast5d-write-test-"):
            pass
    except OSError as e:
        raise OutputDirError(f"{what}: cannot write to {path} ({e.strerror or e}); give a writable directory "
                             f"with {flag}") from None
    return path


def check_results_dir() -> Path:
    """The result store, checked writable (check_output_dir) before any render."""
    return check_output_dir(results_dir(), "results directory", "--results DIR or RAST5D_RESULTS")


def display(path: Path) -> str:
    """A path as a user reads it: relative to the working directory when under it."""
    path = Path(path)
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)

"""Experiments: YAML configs (config/), sweeps on a local pool or Dask into the Parquet result store
(run/), declarative report pages with figures, tables and image-error metrics (report/), the
`rast5d` command line (cli.py), an example application (examples/) and benchmarks (bench/)."""


def version() -> str:
    """The installed package's version (pyproject.toml's project.version)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _version

    try:
        return _version("rast5d")
    except PackageNotFoundError:  # a checkout on sys.path without an install
        import re
        from pathlib import Path

        text = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
        return re.search(r'^version = "([^"]+)"', text, re.M).group(1)


def __getattr__(name: str):
    if name == "__version__":  # read on first use: the package metadata costs 50 ms of start-up
        globals()["__version__"] = v = version()
        return v
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def load(name: str):
    """The result table of experiment ``name`` (results/<name>.parquet) as a pandas DataFrame."""
    from .run.store import load as _load

    return _load(name)

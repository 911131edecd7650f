"""Experiments: YAML configs (config.py), sweeps on a local pool or Dask (runner.py), the Parquet
result store, declarative report pages (plots.py, report.py), image-error metrics (metrics.py)."""


def load(name: str):
    """The result table of experiment ``name`` (results/<name>.parquet) as a pandas DataFrame."""
    from .runner import load as _load

    return _load(name)

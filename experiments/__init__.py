"""Experiments: YAML configs (config/), sweeps on a local pool or Dask into the Parquet result store
(run/), declarative report pages with figures, tables and image-error metrics (report/), the
`rast5d` command line (cli.py), an example application (examples/) and benchmarks (bench/)."""


def load(name: str):
    """The result table of experiment ``name`` (results/<name>.parquet) as a pandas DataFrame."""
    from .run.store import load as _load

    return _load(name)

"""Running experiments: the result store (store.py), the point kinds (points.py), reference images of
the image-error metrics (references.py), the executors (executors.py) and the sweep runner (runner.py)."""
from .points import POINT_KINDS, config_columns, render_point, run_point
from .runner import run_sweep
from .store import engine_id, git_rev, images_dir, load, results_dir, table_path

__all__ = ["run_sweep", "load", "render_point", "run_point", "config_columns", "engine_id", "git_rev", "results_dir",
           "images_dir", "table_path", "POINT_KINDS"]

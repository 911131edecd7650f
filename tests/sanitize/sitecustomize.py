"""`make sanitize`: load the AddressSanitizer + UndefinedBehaviorSanitizer build of the engine
(build/sanitize, CMake option RAST5D_SANITIZE) as ``sim._core`` instead of the installed module.

The Makefile puts this folder on PYTHONPATH (so every Python process of the test run, pool workers
and `rast5d` subprocesses included, imports it at start-up) and RAST5D_CORE_SO names the build."""
import importlib.util
import os
import sys

_SO = os.environ.get("RAST5D_CORE_SO")


class _SanitizedCore:
    @staticmethod
    def find_spec(name, path=None, target=None):
        if name == "sim._core" and _SO:
            return importlib.util.spec_from_file_location(name, _SO)
        return None


if _SO:
    sys.meta_path.insert(0, _SanitizedCore)

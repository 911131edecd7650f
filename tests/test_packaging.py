"""Packaging: compatible dependency ranges in pyproject.toml, exact pins in constraints.txt that
satisfy them (and that this environment was installed from), the version on the command line, and
the licence and citation files. `make test-install` installs a built wheel into fresh 3.12/3.13 venvs."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from importlib.metadata import version
from pathlib import Path

import pytest
from packaging.requirements import Requirement

pytestmark = pytest.mark.smoke

REPO = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())


# The constraints file this environment was installed from: constraints.txt for `make install`,
# constraints-lowest.txt for `make test-lowest` (which sets RAST5D_CONSTRAINTS).
CONSTRAINTS = os.environ.get("RAST5D_CONSTRAINTS", "constraints.txt")


def _pins(name: str = "constraints.txt") -> dict[str, str]:
    pins = {}
    for line in (REPO / name).read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, _, pinned = line.partition("==")
            assert pinned, f"constraints.txt: {line!r} is not an exact pin"
            pins[_norm(name)] = pinned
    return pins


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _requirements() -> list[Requirement]:
    project = PYPROJECT["project"]
    reqs = list(project["dependencies"]) + [r for extra in project["optional-dependencies"].values() for r in extra]
    return [Requirement(r) for r in reqs + PYPROJECT["build-system"]["requires"]]


def test_python_range_admits_311_to_313():
    spec = Requirement(f"python{PYPROJECT['project']['requires-python']}").specifier
    assert all(spec.contains(v) for v in ("3.11.7", "3.12.1", "3.13.0", "3.14.0")), spec


def test_dependencies_are_ranges_pinned_in_constraints():
    pins = _pins()
    for req in _requirements():
        assert not any(s.operator in ("==", "===") for s in req.specifier), f"{req}: a range, not a pin"
        assert req.specifier, f"{req}: give at least a lower bound"
        name = _norm(req.name)
        assert name in pins, f"{req.name}: no pin in constraints.txt"
        assert req.specifier.contains(pins[name]), f"constraints.txt pins {req.name}=={pins[name]} outside {req}"


@pytest.mark.parametrize("name", ["constraints.txt", "constraints-lowest.txt"])
def test_constraint_files_pin_every_dependency_inside_its_range(name):
    """Both constraint files pin every direct dependency inside its range; constraints-lowest.txt
    pins each at the lower end of its range (the release the `>=` bound names, or its first patch)."""
    from packaging.version import Version

    pins = _pins(name)
    for req in _requirements():
        pinned = pins.get(_norm(req.name))
        assert pinned is not None, f"{name}: no pin for {req.name}"
        assert req.specifier.contains(pinned), f"{name} pins {req.name}=={pinned} outside {req}"
        if name == "constraints-lowest.txt":
            low = [Version(s.version) for s in req.specifier if s.operator == ">="]
            assert low, f"{req.name}: no lower bound in {req}"
            got = Version(pinned).release
            assert got[: len(low[0].release)] == low[0].release, f"{name} pins {req.name}=={pinned}, not the lower end of {req}"


def test_environment_installed_from_constraints():
    """make install uses constraints.txt (make test-lowest constraints-lowest.txt): each direct
    dependency here is the pinned version."""
    from importlib.metadata import PackageNotFoundError

    pins = _pins(CONSTRAINTS)
    # The bench extra (Mitsuba) is installed by `make bench` only.
    bench_only = {_norm(Requirement(r).name) for r in PYPROJECT["project"]["optional-dependencies"]["bench"]}
    for req in _requirements():
        try:
            got = version(req.name)
        except PackageNotFoundError:
            assert _norm(req.name) in bench_only, f"{req.name}: not installed"
            continue
        assert got == pins[_norm(req.name)], req.name


def test_cli_version_and_files():
    out = subprocess.run([sys.executable, "-m", "experiments.cli", "--version"], capture_output=True, text=True,
                         check=True, cwd=REPO).stdout
    assert out.startswith(f"rast5d {PYPROJECT['project']['version']} "), out
    assert "MIT License" in (REPO / "LICENSE").read_text()
    citation = (REPO / "CITATION.cff").read_text()
    assert "cff-version:" in citation and f"version: {PYPROJECT['project']['version']}" in citation
    assert f"## {PYPROJECT['project']['version']}" in (REPO / "CHANGELOG.md").read_text()

"""Packaging: compatible dependency ranges in pyproject.toml, exact pins in constraints.txt that
satisfy them (and that this environment was installed from), the version on the command line, and
the licence and citation files. `make test-install` installs a built wheel into fresh 3.12/3.13 venvs."""
from __future__ import annotations

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


def _pins() -> dict[str, str]:
    pins = {}
    for line in (REPO / "constraints.txt").read_text().splitlines():
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


def test_environment_installed_from_constraints():
    """make install uses constraints.txt: each direct dependency here is the pinned version."""
    pins = _pins()
    for req in _requirements():
        assert version(req.name) == pins[_norm(req.name)], req.name


def test_cli_version_and_files():
    out = subprocess.run([sys.executable, "-m", "experiments.cli", "--version"], capture_output=True, text=True,
                         check=True, cwd=REPO).stdout
    assert out.startswith(f"rast5d {PYPROJECT['project']['version']} "), out
    assert "MIT License" in (REPO / "LICENSE").read_text()
    citation = (REPO / "CITATION.cff").read_text()
    assert "cff-version:" in citation and f"version: {PYPROJECT['project']['version']}" in citation
    assert f"## {PYPROJECT['project']['version']}" in (REPO / "CHANGELOG.md").read_text()

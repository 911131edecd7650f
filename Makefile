# rast5d: every target sets up what it needs (venv, build, install) on a fresh machine.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMPS := .make-stamps
SOURCES := $(shell find sim/engine sim/bindings -type f 2>/dev/null) CMakeLists.txt pyproject.toml
export CMAKE_BUILD_PARALLEL_LEVEL ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: install run test test-all bench golden report report-quick clean

install: $(STAMPS)/install

$(STAMPS)/venv:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade "pip>=23.2"
	$(PY) -m pip install --quiet "scikit-build-core==1.1.2" "pybind11==3.1.0"
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/install: $(STAMPS)/venv $(SOURCES)
	$(PY) -m pip install --quiet --no-build-isolation -e ".[test]"
	@mkdir -p $(STAMPS) && touch $@

run: install
	$(VENV)/bin/rast5d report --only quickstart

test: install
	$(PY) -m pytest -q

test-all: install
	$(PY) -m pytest -q -m "not bench"

bench: install
	$(PY) -m pytest -q -s -m bench

golden: install
	$(PY) -m tests.golden.golden

report: install
	$(VENV)/bin/rast5d report

report-quick: install
	$(VENV)/bin/rast5d report --quick

clean:
	rm -rf build $(VENV) $(STAMPS) .pytest_cache .hypothesis
	find . -name __pycache__ -type d -prune -exec rm -rf {} +

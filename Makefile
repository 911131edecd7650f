# rast5d: every target sets up what it needs (venv, build, install) on a fresh machine.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMPS := .make-stamps
SOURCES := $(shell find sim/engine sim/bindings -type f 2>/dev/null) CMakeLists.txt pyproject.toml
export CMAKE_BUILD_PARALLEL_LEVEL ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: install run test test-all bench golden report report-quick clean sanitize

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

# The engine with AddressSanitizer + UndefinedBehaviorSanitizer (build/sanitize), loaded in place of the
# installed module (tests/sanitize/sitecustomize.py) into every Python process of the fast test tier.
# SANITIZE_TESTS narrows the run (default: the whole fast tier).
SAN_BUILD := build/sanitize
SANITIZE_TESTS ?=
SAN_ENV = PYTHONPATH=$(CURDIR)/tests/sanitize RAST5D_CORE_SO=$$(ls $(CURDIR)/$(SAN_BUILD)/_core*.so) \
	LD_PRELOAD=$$(gcc -print-file-name=libasan.so) \
	ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:halt_on_error=1 \
	UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 RAST5D_SANITIZED=1
sanitize: install
	cmake -S . -B $(SAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRAST5D_SANITIZE=ON \
		-DRAST5D_NATIVE=OFF -DPython_EXECUTABLE=$(CURDIR)/$(PY) \
		-Dpybind11_DIR=$$($(PY) -c "import pybind11; print(pybind11.get_cmake_dir())") > /dev/null
	cmake --build $(SAN_BUILD) --target _core
	$(SAN_ENV) $(PY) -c "import sim; assert '$(SAN_BUILD)' in sim._core.__file__, sim._core.__file__"
	$(SAN_ENV) $(PY) -m pytest -q -p no:cacheprovider $(SANITIZE_TESTS)

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

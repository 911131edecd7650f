# rast5d: every target sets up what it needs (venv, build, install) on a fresh machine.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMPS := .make-stamps
CONSTRAINTS := constraints.txt
SOURCES := $(shell find sim/engine sim/bindings -type f 2>/dev/null) CMakeLists.txt pyproject.toml $(CONSTRAINTS)
# Pythons that `make test-install` builds a wheel for and installs it into (pyenv or pythonX.Y on PATH)
INSTALL_PYTHONS ?= 3.12 3.13
export CMAKE_BUILD_PARALLEL_LEVEL ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: install run test test-all test-install test-lowest bench golden report report-quick clean sanitize docs

install: $(STAMPS)/install

$(STAMPS)/venv:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade "pip>=23.2"
	$(PY) -m pip install --quiet -c $(CONSTRAINTS) scikit-build-core pybind11
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/install: $(STAMPS)/venv $(SOURCES)
	$(PY) -m pip install --quiet --no-build-isolation -c $(CONSTRAINTS) -e ".[test,docs]"
	@# Byte-compile the checkout's packages, as pip does for a wheel: a run then starts from bytecode even
	@# where PYTHONDONTWRITEBYTECODE is set (a cached run's start-up, reports/bench/bench_overhead.md).
	$(PY) -m compileall -q sim experiments models > /dev/null
	@mkdir -p $(STAMPS) && touch $@

run: install
	$(VENV)/bin/rast5d report --only quickstart

test: install
	$(PY) -m pytest -q

# The documentation site (docs/conf.py): README, docs/, the report pages and the API reference from
# the docstrings, warnings as errors, into build/docs/html/ (open build/docs/html/index.html).
DOCS_OUT := build/docs/html
docs: install
	@start=$$(date +%s); rm -rf $(DOCS_OUT); \
	  $(PY) -m sphinx -b html -W --keep-going -q -c docs . $(DOCS_OUT) && \
	  echo "docs: $$(find $(DOCS_OUT) -name '*.html' | wc -l) pages in $(DOCS_OUT)/ in $$(( $$(date +%s) - start )) s"

# The engine with AddressSanitizer + UndefinedBehaviorSanitizer (build/sanitize), loaded in place of the
# installed module (tests/sanitize/sitecustomize.py) into every Python process of the fast test tier.
# libstdc++ is preloaded with libasan so ASan's C++ exception interceptor finds the real __cxa_throw
# (python itself does not link libstdc++; without it the first exception the engine throws aborts).
# SANITIZE_TESTS narrows the run (default: the whole fast tier).
SAN_BUILD := build/sanitize
SANITIZE_TESTS ?=
SAN_ENV = PYTHONPATH=$(CURDIR)/tests/sanitize RAST5D_CORE_SO=$$(ls $(CURDIR)/$(SAN_BUILD)/_core*.so) \
	LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libstdc++.so)" \
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

# Build a wheel with each of INSTALL_PYTHONS, install it into a fresh venv with the pinned
# dependencies (constraints.txt) and run tests/install_smoke.py there, outside the checkout: what a new
# user runs in an empty directory (the whole quickstart report with the last Python, its quick variant
# with the others; with the last Python also the notebooks `rast5d init` copies, run by nbclient).
test-install:
	@set -e; for v in $(INSTALL_PYTHONS); do \
	  py=$$(ls -d $$(pyenv root 2>/dev/null)/versions/$$v.*/bin/python3 2>/dev/null | sort -V | tail -1); \
	  if [ -z "$$py" ]; then py=$$(command -v python$$v || true); fi; \
	  if [ -z "$$py" ]; then echo "test-install: no Python $$v (pyenv or python$$v on PATH)"; exit 1; fi; \
	  dir=build/test-install/$$v; rm -rf $$dir; mkdir -p $$dir; start=$$(date +%s); \
	  echo "test-install: Python $$v ($$py)"; \
	  $$py -m venv $$dir/build-env; \
	  $$dir/build-env/bin/python -m pip install --quiet -c $(CONSTRAINTS) scikit-build-core pybind11; \
	  $$dir/build-env/bin/python -m pip wheel --quiet --no-deps --no-build-isolation -w $$dir/dist .; \
	  $$py -m venv $$dir/env; \
	  $$dir/env/bin/python -m pip install --quiet -c $(CONSTRAINTS) $$dir/dist/rast5d-*.whl; \
	  quick=$$( [ "$$v" = "$(lastword $(INSTALL_PYTHONS))" ] || echo --quick ); \
	  [ -n "$$quick" ] || $$dir/env/bin/python -m pip install --quiet -c $(CONSTRAINTS) nbclient nbformat ipykernel; \
	  (cd $$dir && env/bin/python $(CURDIR)/tests/install_smoke.py $$quick); \
	  echo "test-install: Python $$v passed in $$(( $$(date +%s) - start )) s"; \
	done

# The lowest dependency versions pyproject.toml allows (constraints-lowest.txt) in a fresh venv of
# LOWEST_PYTHON: the package installed there (editable, its own build directory) and the fast test
# tier run against it, so the lower ends of pyproject.toml's ranges are tested, not guessed.
LOWEST_PYTHON ?= 3.11
LOWEST := build/test-lowest
test-lowest:
	@set -e; v=$(LOWEST_PYTHON); \
	  py=$$(ls -d $$(pyenv root 2>/dev/null)/versions/$$v.*/bin/python3 2>/dev/null | sort -V | tail -1); \
	  if [ -z "$$py" ]; then py=$$(command -v python$$v || true); fi; \
	  if [ -z "$$py" ]; then echo "test-lowest: no Python $$v (pyenv or python$$v on PATH)"; exit 1; fi; \
	  rm -rf $(LOWEST); $$py -m venv $(LOWEST)/env; start=$$(date +%s); \
	  $(LOWEST)/env/bin/python -m pip install --quiet --upgrade "pip>=23.2"; \
	  $(LOWEST)/env/bin/python -m pip install --quiet -c constraints-lowest.txt scikit-build-core pybind11; \
	  $(LOWEST)/env/bin/python -m pip install --quiet --no-build-isolation -c constraints-lowest.txt \
	    --config-settings=build-dir=$(LOWEST)/cmake -e ".[test,docs]"; \
	  $(LOWEST)/env/bin/python -m pip list --format=freeze | grep -iE "^($$(sed -n 's/==.*//p' constraints-lowest.txt | paste -sd'|'))==" ; \
	  RAST5D_CONSTRAINTS=constraints-lowest.txt $(LOWEST)/env/bin/python -m pytest -q -p no:cacheprovider; \
	  $(LOWEST)/env/bin/python -m sphinx -b html -W --keep-going -q -c docs . $(LOWEST)/docs; \
	  echo "test-lowest: Python $$v passed in $$(( $$(date +%s) - start )) s"

# The benchmarks, with the optional `bench` extra (Mitsuba 3, pyproject.toml) installed first; Mitsuba's
# vectorised variant also needs LLVM >= 16 on the machine (Debian: libllvm19), else its rows are skipped
# with a message on the page.
$(STAMPS)/bench: $(STAMPS)/install pyproject.toml $(CONSTRAINTS)
	$(PY) -m pip install --quiet -c $(CONSTRAINTS) $$($(PY) -c "import tomllib; print(' '.join(tomllib.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['bench']))")
	@mkdir -p $(STAMPS) && touch $@

bench: install $(STAMPS)/bench
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

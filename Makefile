# robotdyn: everything a newcomer needs, from a fresh machine with Python 3.11 and pip.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench venv clean chromium

$(STAMP): pyproject.toml setup.py robotdyn/_compiled.cpp
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet "setuptools>=77" wheel "pybind11>=2.12" "pin>=4.1,<5" "cmeel-eigen>=3.4"  # build requirements (pyproject.toml)
	$(PY) -m pip install --quiet --no-build-isolation -e ".[test]"  # compiles robotdyn._compiled (~2 min)
	$(PY) -c "import robotdyn.compiled as c; print('robotdyn: compiled fast path', 'built' if c.available() else 'NOT built (no C++ compiler?): Python path only')"
	touch $(STAMP)

venv: $(STAMP)

## make demo: install, then compute the Quasimoro's reduced dynamics, compare it with the paper and simulate
demo: $(STAMP)
	$(PY) -m robotdyn info quasimoro
	$(PY) -m robotdyn dump quasimoro --q 0 0 0 0 0 0.3 --v 1.0 0.5 0.2 --a 0.1 0.2 0.3
	$(PY) -m robotdyn compare quasimoro
	mkdir -p out
	$(PY) -m robotdyn simulate quasimoro --scenario rectilinear --t-end 10 --csv out/quasimoro_rectilinear.csv --plot out/quasimoro_rectilinear.png

## make chromium: Debian's chromium for the browser tests (tests/test_browser.py), installed if missing
## (ROBOTDYN_SKIP_BROWSER=1 skips both the install and those tests)
chromium:
	@[ "$$ROBOTDYN_SKIP_BROWSER" = 1 ] || command -v chromium >/dev/null 2>&1 || { SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y chromium; }

## make test: install, then run the whole test suite, notebooks included
test: $(STAMP) chromium
	$(PY) -m pytest -q tests
	$(PY) -m pytest -q --nbmake notebooks

## make bench: speed of the reduced model against raw Pinocchio, side by side in one run; MuJoCo on the same
## manoeuvre and sweep throughput on Dask (the `bench` extra of pyproject.toml, installed here without a rebuild)
bench: $(STAMP)
	$(PY) -c "import tomllib; print('\n'.join(tomllib.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['bench']))" | xargs $(PY) -m pip install --quiet
	$(PY) bench/bench.py

clean:
	rm -rf $(VENV) out .pytest_cache

# robotdyn: everything a newcomer needs, from a fresh machine with Python 3.11 and pip.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench venv clean chromium docs

$(STAMP): pyproject.toml setup.py robotdyn/_compiled.cpp robotdyn/_integrator.hpp robotdyn/_torque_profile.hpp robotdyn/_controller.hpp robotdyn/_stiff_integrator.hpp $(wildcard robotdyn/kernels/*.hpp)
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet "setuptools>=77" wheel "pybind11>=2.12" "pin>=4.1,<5" "cmeel-eigen>=3.4"  # build requirements (pyproject.toml)
	@# robotdyn._compiled compiles in place on one CPU (~8 min) while pip installs robotdyn (editable, without the
	@# extension) and its dependencies on another (setup.py)
	$(PY) setup.py -q build_ext --inplace > $(VENV)/build-ext.log 2>&1 & build=$$!; \
	  ROBOTDYN_EXTENSION_IN_PLACE=1 $(PY) -m pip install --quiet --no-build-isolation -e ".[test]"; installed=$$?; \
	  wait $$build; built=$$?; tail -3 $(VENV)/build-ext.log; [ $$installed = 0 ] && [ $$built = 0 ]
	$(PY) -c "import robotdyn.fast.compiled as c; print('robotdyn: compiled fast path', 'built' if c.available() else 'NOT built (no C++ compiler?): Python path only')"
	touch $(STAMP)

venv: $(STAMP)

## make demo: install, then compute the Quasimoro's reduced dynamics, compare it with the paper and simulate
demo: $(STAMP)
	$(PY) -m robotdyn info quasimoro
	$(PY) -m robotdyn dump quasimoro --q 0 0 0 0 0 0.3 --v 1.0 0.5 0.2 --a 0.1 0.2 0.3
	$(PY) -m robotdyn compare quasimoro
	mkdir -p out
	$(PY) -m robotdyn simulate quasimoro --scenario rectilinear --t-end 10 --csv out/quasimoro_rectilinear.csv --plot out/quasimoro_rectilinear.png
	@echo ""
	@echo "robotdyn is installed in .venv/, not on your PATH: run it as .venv/bin/robotdyn (e.g. .venv/bin/robotdyn list),"
	@echo "or run 'source .venv/bin/activate' once per shell, then robotdyn ... and python -c 'import robotdyn' work."
	@echo "Next: docs/getting-started.md (or make docs, then open docs/_build/html/index.html)."

## make chromium: Debian's chromium for the browser tests (tests/test_browser.py), installed if missing
## (ROBOTDYN_SKIP_BROWSER=1 skips both the install and those tests)
chromium:
	@[ "$$ROBOTDYN_SKIP_BROWSER" = 1 ] || command -v chromium >/dev/null 2>&1 || { SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y chromium; }

## make test: install, then run the whole test suite, notebooks included: each notebook executed in a temporary
## directory outside the repository, its outputs kept in $(NB_CACHE) for make docs (tools/notebook_cache.py)
NB_CACHE := docs/_build/.jupyter_cache
test: $(STAMP) chromium
	$(PY) -m pytest -q -n auto tests  # pytest-xdist: one worker per CPU
	$(PY) tools/notebook_cache.py execute $(NB_CACHE) notebooks/*.ipynb

## make docs: the documentation site into docs/_build/html (Sphinx + MyST-NB: the notebooks executed, the API
## reference from the docstrings, the errata, the viewer pages), warnings as errors, then checked by
## tools/check_site.py (screenshots of four pages in docs/_build/screenshots/). Installs the `docs` group of
## pyproject.toml without reinstalling robotdyn (no recompilation). A notebook whose outputs make test left in
## $(NB_CACHE) is not executed again, unless it or robotdyn's code changed since; SPHINXOPTS="-D
## nb_execution_mode=force" executes every notebook.
DOCS_STAMP := $(VENV)/.docs-installed
SPHINXOPTS ?=
$(DOCS_STAMP): $(STAMP) pyproject.toml
	$(PY) -c "import tomllib; print('\n'.join(tomllib.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['docs']))" > $(VENV)/docs-requirements.txt
	$(PY) -m pip install --quiet -r $(VENV)/docs-requirements.txt
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP) chromium
	rm -rf docs/api
	$(PY) tools/notebook_cache.py drop-stale $(NB_CACHE)  # outputs of older code are not reused
	$(PY) -m sphinx -b html -W --keep-going -c docs $(SPHINXOPTS) . docs/_build/html
	$(PY) tools/check_site.py docs/_build/html  # local links and anchors, machine paths, alt text; math and figures in Chromium
	@echo "docs: open docs/_build/html/index.html"

## make bench: speed of the reduced model against raw Pinocchio, side by side in one run; MuJoCo on the same
## manoeuvre and sweep throughput on Dask (the `bench` extra of pyproject.toml, installed here without a rebuild)
bench: $(STAMP)
	$(PY) -c "import tomllib; print('\n'.join(tomllib.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['bench']))" | xargs $(PY) -m pip install --quiet
	$(PY) bench/bench.py

clean:
	rm -rf $(VENV) out .pytest_cache docs/_build docs/api

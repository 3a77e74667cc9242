# Everything a fresh machine needs: Python 3.11+, a C compiler and make.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
PYTEST := $(BIN)/python -m pytest
# the build backend, installed into the environment for the editable install (meson-python
# rebuilds the compiled model there when generated/ or the C sources change)
BACKEND := "meson-python>=0.18" "meson>=1.3" "ninja>=1.11"
# the environment's meson and ninja first, for the build and the editable install's rebuilds
export PATH := $(abspath $(BIN)):$(PATH)
# Python caches the bytecode of the tests and derive/ (in __pycache__, ignored by git), so that
# each test worker and each command a test runs does not compile them again
unexport PYTHONDONTWRITEBYTECODE

.PHONY: install paper test check test-slow test-floors bench bench-all derive docs clean

# The dependencies are installed by uv (itself installed by pip, with the build backend): it
# downloads and unpacks them in parallel, and builds gsfric (the compile of the model) while it
# does. It writes no bytecode at install time: Python compiles each module on its first import,
# once, and only the modules that are imported (pip would compile every installed file first).
$(STAMP): pyproject.toml meson.build
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip uv $(BACKEND)
	$(BIN)/uv pip install --quiet --python $(BIN)/python --no-build-isolation -e ".[test]"
	# derive/ is not an installed package (the wheel ships only its output): the checkout is
	# put on this environment's path so that the notebooks and tests can import it
	$(BIN)/python -c "import pathlib, sysconfig; pathlib.Path(sysconfig.get_paths()['purelib'], 'gsfric-checkout.pth').write_text(str(pathlib.Path.cwd().resolve()) + '\n')"
	touch $(STAMP)

install: $(STAMP)

# The editable install rebuilds the compiled model on import when its sources changed: once
# here, before parallel test workers import it. Its importer never writes bytecode: the
# package's is compiled here, once, instead of in every process that imports it.
.PHONY: built
built: $(STAMP)
	$(BIN)/python -c "import gsfric.compiled.native as n; n.library()"
	$(BIN)/python -m compileall -q gsfric

## The main job: the paper's 40-step evaluation, its tables, report and plots, in out/paper.
paper: built
	$(BIN)/gsfric paper --out out/paper

## Every test that guards behaviour: the docs build, the notebooks and the wheel included.
test: built
	$(PYTEST) -n 2 --dist worksteal tests

## The inner loop: every test but the end-to-end runs (wheel, docs, notebooks, derivation,
## whole discoveries) and the slow suites.
check: built
	$(PYTEST) -n 2 --dist worksteal -m "not slow and not integration" tests

## The long statistical suites that `make test` leaves out.
test-slow: built
	$(PYTEST) -n 2 --dist worksteal -m slow tests

## The suite on the lowest versions of the dependencies that pyproject.toml declares.
test-floors:
	$(PYTHON) -m venv .venv-floors
	.venv-floors/bin/pip install --quiet --upgrade pip uv $(BACKEND)
	.venv-floors/bin/uv pip install --quiet --python .venv-floors/bin/python \
		--resolution lowest-direct --no-build-isolation -e ".[test]"
	.venv-floors/bin/python -c "import pathlib, sysconfig; pathlib.Path(sysconfig.get_paths()['purelib'], 'gsfric-checkout.pth').write_text(str(pathlib.Path.cwd().resolve()) + '\n')"
	PATH="$(abspath .venv-floors/bin):$$PATH" .venv-floors/bin/python -m pytest -n 2 --dist worksteal tests

## The throughput table of the compiled model.
bench: built
	$(BIN)/gsfric bench

## Every user path against its goal, in one run (about 5-10 minutes; benchmarks/all.py).
bench-all: built
	$(BIN)/python -m benchmarks.all

## The documentation site, tutorials executed, into docs/_build/html (warnings are errors).
docs: built
	$(BIN)/python -m sphinx -b html -W -n --keep-going docs docs/_build/html

derive: built
	$(BIN)/gsfric derive

clean:
	rm -rf $(VENV) .venv-floors build out docs/_build docs/_generated

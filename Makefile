# Everything a fresh machine needs: Python 3.10+, a C compiler and make.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: install paper test test-slow bench derive docs clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[test]"
	# derive/ is not an installed package (the wheel ships only its output): the checkout is
	# put on this environment's path so that the notebooks and tests can import it
	$(BIN)/python -c "import pathlib, sysconfig; pathlib.Path(sysconfig.get_paths()['purelib'], 'gsfric-checkout.pth').write_text(str(pathlib.Path.cwd().resolve()) + '\n')"
	touch $(STAMP)

install: $(STAMP)

## The main job: the paper's 40-step evaluation, its tables, report and plots, in out/paper.
paper: $(STAMP)
	$(BIN)/gsfric paper --out out/paper

## The whole test suite (the slow statistical suites are left to `make test-slow`).
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 --dist worksteal tests

test-slow: $(STAMP)
	$(BIN)/python -m pytest -m slow tests

bench: $(STAMP)
	$(BIN)/gsfric bench

## The documentation site, tutorials executed, into docs/_build/html (warnings are errors).
docs: $(STAMP)
	$(BIN)/python -m sphinx -b html -W -n --keep-going docs docs/_build/html

derive: $(STAMP)
	$(BIN)/gsfric derive

clean:
	rm -rf $(VENV) out docs/_build docs/_generated

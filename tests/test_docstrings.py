"""The public API's docstrings: every public function and class says what it takes and gives
(numpydoc sections) with an example, and every example runs (doctest): a docstring cannot
promise what is not there. An example that cannot run here (it reads a file of the user's, or
takes seconds) is marked ``# doctest: +SKIP`` with the reason in a comment before it."""

from __future__ import annotations

import doctest
import importlib
import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import gsfric

PUBLIC = sorted(name for name in gsfric.__all__ if name[0].isupper() or callable(
    getattr(gsfric, name)) and not inspect.ismodule(getattr(gsfric, name)))
"""Every public name of ``gsfric`` that is a function or a class."""



def _modules_with_examples() -> list[str]:
    """Every module of gsfric whose source holds an example (``>>>``)."""
    root = Path(gsfric.__file__).parent
    out = []
    for path in sorted(root.rglob("*.py")):
        if ">>>" in path.read_text():
            parts = path.relative_to(root.parent).with_suffix("").parts
            out.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return out


DOCTEST_MODULES = _modules_with_examples()
"""Modules whose examples run as doctests: every one that has an example."""

SKIP_REASON = re.compile(r"#\s*(?!doctest:)\S[^#]*#\s*doctest:")
"""A skipped example's reason: a comment before its directive (``# takes seconds  # doctest:
+SKIP``)."""


def _sections(obj) -> set[str]:
    doc = inspect.getdoc(obj) or ""
    lines = doc.splitlines()
    return {lines[i].strip() for i in range(len(lines) - 1)
            if set(lines[i + 1].strip()) == {"-"} and lines[i].strip()}


@pytest.mark.parametrize("name", PUBLIC)
def test_public_name_documents_its_interface(name):
    obj = getattr(gsfric, name)
    sections = _sections(obj)
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return
    assert "Examples" in sections, f"gsfric.{name}: no Examples section"
    if inspect.isfunction(obj):
        if inspect.signature(obj).parameters:
            assert "Parameters" in sections, f"gsfric.{name}: no Parameters section"
        assert "Returns" in sections, f"gsfric.{name}: no Returns section"
    else:
        assert sections & {"Parameters", "Attributes"}, f"gsfric.{name}: no Parameters section"


@pytest.mark.parametrize("module", DOCTEST_MODULES)
def test_examples_run(module):
    """Each example runs with only ``np`` and ``gsfric`` given (what else it needs, it
    imports), and each skipped one says why."""
    mod = importlib.import_module(module)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = finder.find(mod, module, globs={"np": np, "gsfric": gsfric})
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{module}: {result.failed} of {result.attempted} examples fail"
    silent = [f"{test.name}: {example.source.strip()}" for test in tests
              for example in test.examples
              if example.options.get(doctest.SKIP) and not SKIP_REASON.search(example.source)]
    assert silent == [], "skipped without a reason"


@pytest.mark.parametrize("name", PUBLIC)
def test_public_examples_are_run(name):
    """The examples of every public name are in a module whose examples run."""
    obj = getattr(gsfric, name)
    if ">>>" in (inspect.getdoc(obj) or ""):
        assert obj.__module__ in DOCTEST_MODULES


def test_a_skipped_example_without_a_reason_is_found():
    assert SKIP_REASON.search(">>> run()  # takes seconds  # doctest: +SKIP\n")
    assert not SKIP_REASON.search(">>> run()  # doctest: +SKIP\n")
    assert not SKIP_REASON.search(">>> run()     #   # doctest: +SKIP\n")

"""The public API's docstrings: every public function and class says what it takes and gives
(numpydoc sections) with an example, and every example runs (doctest)."""

from __future__ import annotations

import doctest
import importlib
import inspect

import numpy as np
import pytest

import gsfric

PUBLIC = sorted(name for name in gsfric.__all__ if name[0].isupper() or callable(
    getattr(gsfric, name)) and not inspect.ismodule(getattr(gsfric, name)))
"""Every public name of ``gsfric`` that is a function or a class."""

DOCTEST_MODULES = ("gsfric", "gsfric.evaluation.evaluator", "gsfric.evaluation.result",
                   "gsfric.trajectory", "gsfric.models", "gsfric.platform.description",
                   "gsfric.io.readers", "gsfric.io.logs", "gsfric.errors",
                   "gsfric.signal.filters", "gsfric.discovery.pvalues", "gsfric.view.frames")
"""Modules whose examples run as doctests."""


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
    mod = importlib.import_module(module)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = finder.find(mod, module, globs={"np": np, "gsfric": gsfric})
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{module}: {result.failed} of {result.attempted} examples fail"

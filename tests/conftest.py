"""Shared fixtures."""

from __future__ import annotations

import numpy as np
import pytest

from gsfric import models


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def platform():
    return models.reference_platform()


@pytest.fixture(scope="session", autouse=True)
def compiled_library():
    """Compile the generated C once before any test, so that no test's output carries the
    one-time compilation notice (each xdist worker waits on the cache's lock)."""
    from gsfric.compiled import native

    native.is_compiled()

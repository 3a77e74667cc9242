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

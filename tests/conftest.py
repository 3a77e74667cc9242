"""Shared fixtures, and the linear-algebra threads of parallel test workers."""

from __future__ import annotations

import gc
import os

import numpy as np
import pytest
from helpers import build_folder_lock
from threadpoolctl import threadpool_limits

from gsfric import models

_BLAS_LIMIT = []
"""The BLAS thread limit of this test worker, kept for the session (see pytest_configure)."""


def pytest_configure(config):
    """A worker of ``pytest -n N`` gets its share of the cores for BLAS (NumPy's and SciPy's
    linear algebra), and so does every process it starts (the CLI, a notebook's kernel): N
    workers each running a BLAS thread per core would oversubscribe the cores, and a
    multithreaded BLAS whose threads wait for a core spins instead of computing."""
    workers = getattr(config, "workerinput", {}).get("workercount")
    if not workers:
        return
    share = str(max(1, (os.cpu_count() or 1) // int(workers)))
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, share)
    _BLAS_LIMIT.append(threadpool_limits(limits=int(share), user_api="blas"))


def pytest_collection_finish(session):
    """What collection built (the imported modules, SymPy's and SciPy's included, and the test
    items) lives for the whole session: frozen out of the cyclic garbage collector, whose full
    collections would otherwise walk it again and again between tests."""
    gc.collect()
    gc.freeze()


@pytest.fixture(autouse=True)
def build_folder_in_use():
    """Each test holds the build folder's lock shared (``helpers.build_folder_lock``): what
    it starts may check the editable install's build, which test_packaging reconfigures."""
    with build_folder_lock(exclusive=False):
        yield


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def platform():
    return models.reference_platform()

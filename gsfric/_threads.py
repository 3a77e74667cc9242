"""Threads of the linear-algebra library (BLAS) that NumPy and SciPy call."""

from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def one_blas_thread(function):
    """``function`` run with BLAS limited to one thread (restored afterwards).

    The discovery's products are small (tens of columns, stretches of a record): a second
    BLAS thread halves little, and on a machine whose cores are busy the threads of a
    multithreaded BLAS wait for each other at every call; one thread keeps the cost at the
    arithmetic. The compiled model's own threads (``n_threads``) are not affected.
    """

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)

    return wrapper

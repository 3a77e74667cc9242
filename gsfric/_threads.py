"""Threads: the linear-algebra library's (BLAS, which NumPy and SciPy call) held to one, and
independent calls run side by side (``in_parallel``)."""

from __future__ import annotations

import contextvars
import functools
import threading

from threadpoolctl import threadpool_limits


def one_blas_thread(function):
    """``function`` run with BLAS limited to one thread (restored afterwards).

    The discovery's and the streamed simulation's products are small (tens of columns,
    stretches of a record, a chunk's 3 x 3 rotations): a second BLAS thread halves little,
    and on a machine whose cores are busy the threads of a multithreaded BLAS wait for each
    other at every call (the simulation's own threads are such work); one thread keeps the
    cost at the arithmetic. The compiled model's own threads (``n_threads``) are not
    affected.
    """

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)

    return wrapper


def in_parallel(*calls):
    """The results of the zero-argument ``calls``, the first in this thread and each other in
    a thread of its own (in a copy of this thread's context), in order; an exception of any is
    raised here, after all have ended.

    For work that releases the interpreter lock (SciPy's ``ndimage`` filters, NumPy's large
    array operations, the compiled model): on a machine with a free core, the calls share two
    cores; on a busy one, they take the time they would one after the other.
    """
    results: list = [None] * len(calls)
    errors: list = [None] * len(calls)

    def run(i):
        try:
            results[i] = calls[i]()
        except BaseException as error:   # re-raised in the calling thread
            errors[i] = error

    # each thread in a copy of this one's context: NumPy's errstate and the like hold there
    threads = [threading.Thread(target=contextvars.copy_context().run, args=(run, i),
                                daemon=True) for i in range(1, len(calls))]
    for thread in threads:
        thread.start()
    run(0)
    for thread in threads:
        thread.join()
    for error in errors:
        if error is not None:
            raise error
    return results

"""Memory of result arrays: cache-line aligned, large ones on huge pages, reused once dropped.

Result arrays of 1 MiB and more are each on a mapping of whole huge pages of their own; the
memory of results the caller has dropped is kept (up to ``POOL_KEEP_BYTES``) and reused by the
next evaluation of the same size, which then neither faults pages in nor has the kernel zero
them (``release_memory()`` returns it to the system).
"""

from __future__ import annotations

import ctypes
import mmap
import os
import threading
import weakref

import numpy as np

HUGE_PAGE = 1 << 21
"""Bytes of a transparent huge page (x86-64, arm64 with 4 kB pages)."""
POOL_MIN_BYTES = 1 << 20
"""Result arrays from this size up are taken from ``_POOL`` (smaller ones from NumPy)."""
POOL_KEEP_BYTES = 512 << 20
"""At most this much memory of dropped results is kept for the next evaluations."""


class _BlockPool:
    """Memory for large result arrays: anonymous mappings, rounded up to whole huge pages
    (``HUGE_PAGE``, 2 MiB, advised ``MADV_HUGEPAGE``: one page fault per 2 MiB instead of per
    4 kB) from 2 MiB up and to whole pages below; and the blocks of results the caller has
    dropped, kept (up to ``POOL_KEEP_BYTES``) for the next evaluation of the same rounded
    size, which then writes into memory that is already mapped: no page faults, no zeroing by
    the kernel (about 200 ns of every step's 1.8 kB otherwise).

    An array handed out is the caller's alone: its block comes back only when the array and
    every view of it are gone (a ``weakref.finalize`` on the buffer object they all keep
    alive). Thread-safe: one lock guards the free lists (keyed by length) and the count of
    kept bytes. A returning block never waits for it: the finalizer may run inside ``take``
    while this thread holds the lock (a garbage collection there), so when the lock is taken
    the block is not kept but unmapped with its last reference."""

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self._free: dict[int, list] = {}
        self._kept = 0
        self._new_lock()
        if hasattr(os, "register_at_fork"):   # a fork while another thread holds the lock
            os.register_at_fork(after_in_child=self._new_lock)

    def _new_lock(self) -> None:
        self._lock = threading.Lock()

    @staticmethod
    def _length(nbytes: int) -> int:
        unit = HUGE_PAGE if nbytes >= HUGE_PAGE else mmap.PAGESIZE
        return -(-nbytes // unit) * unit

    def take(self, nbytes: int):
        """A mapping of at least ``nbytes`` bytes, page-aligned, not in use."""
        length = self._length(max(nbytes, 1))
        with self._lock:
            blocks = self._free.get(length)
            if blocks:
                block = blocks.pop()
                self._kept -= length
                return block
        block = mmap.mmap(-1, length, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
        if length >= HUGE_PAGE and hasattr(mmap, "MADV_HUGEPAGE"):
            try:
                block.madvise(mmap.MADV_HUGEPAGE)
            except OSError:  # a kernel without transparent huge pages
                pass
        return block

    def give(self, block) -> None:
        """Keep a block whose arrays are all gone, if there is room (else it is unmapped)."""
        if not self._lock.acquire(blocking=False):
            return
        try:
            if self._kept + len(block) <= self.keep:
                self._free.setdefault(len(block), []).append(block)
                self._kept += len(block)
        finally:
            self._lock.release()

    def clear(self) -> None:
        """Unmap every kept block."""
        with self._lock:
            self._free.clear()
            self._kept = 0

    def empty(self, n: int, size: int) -> np.ndarray:
        """An uninitialised C-contiguous float64 array (n, size) on a block of its own."""
        nbytes = n * size * 8
        block = self.take(nbytes)
        owner = (ctypes.c_char * nbytes).from_buffer(block)
        weakref.finalize(owner, self.give, block).atexit = False
        return np.frombuffer(owner, dtype=np.float64).reshape(n, size)


_POOL = _BlockPool(POOL_KEEP_BYTES)
_ANONYMOUS = hasattr(mmap, "MAP_ANONYMOUS")   # POSIX anonymous mappings (not on Windows)


def release_memory() -> None:
    """Return to the system the memory of dropped results that evaluations keep for reuse
    (at most ``POOL_KEEP_BYTES``)."""
    _POOL.clear()


def aligned_empty(n: int, size: int) -> np.ndarray:
    """An uninitialised C-contiguous float64 array (n, size) whose data starts on a 64-byte
    boundary (a cache line): the compiled code then writes whole lines of it with vector
    non-temporal stores (derive/simd.py). Large ones (``POOL_MIN_BYTES``) on page-aligned
    blocks of ``_POOL``; small ones a view of a slightly larger NumPy buffer."""
    count = n * size
    if count * 8 >= POOL_MIN_BYTES and _ANONYMOUS:
        return _POOL.empty(n, size)
    raw = np.empty(count + 8)
    start = (-raw.ctypes.data % 64) // 8
    return raw[start:start + count].reshape(n, size)

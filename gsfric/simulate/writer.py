"""Appending the output's columns to an open CSV or Parquet file, handing it to the disk as it grows.

Rows are appended chunk by chunk (a Parquet row group or a CSV block per chunk) to the
temporary file of ``gsfric.io.atomic_write``, which renames it onto the output only when every
chunk succeeded.
"""

from __future__ import annotations

import contextlib
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from gsfric._optional import optional
from gsfric.evaluation.columns import arrow_table
from gsfric.io.arrow import arrow_array

PARQUET_COMPRESSION = "lz4"
"""Compression of ``simulate``'s Parquet output: the outputs' float64 mantissas are close to
random bytes, so general-purpose compression saves little unless the bytes are split by
significance first (``PARQUET_SPLIT_FLOATS``); the choices compared are in
benchmarks/results/2026-11-27-parquet-encodings.md."""

PARQUET_SPLIT_FLOATS = True
"""Write the float columns with Parquet's BYTE_STREAM_SPLIT encoding (pays only with a
compression)."""

FLUSH_BYTES = 256 * 2**20
"""Bytes written between two requests to the disk (``Flusher``)."""


class Flusher:
    """Hands the written part of a file to the disk while more is being written.

    Every ``FLUSH_BYTES`` (when the previous flush has finished), ``os.fdatasync`` runs in a
    thread of its own (it waits for the disk, not the processor): the disk writes during the
    run instead of after it, so that the final ``fsync`` of ``atomic_write`` finds little
    left. Without it, the kernel holds back up to a tenth of the memory before writing."""

    def __init__(self, handle) -> None:
        self.handle = handle
        self.fileno = handle.fileno()
        self.sync = getattr(os, "fdatasync", os.fsync)
        self.pool = ThreadPoolExecutor(1, thread_name_prefix="gsfric-flush")
        self.pending = None
        self.flushed = 0

    def written(self) -> None:
        """Called after each write, from the writing thread."""
        if self.pending is not None and not self.pending.done():
            return
        if self.pending is not None:
            self.pending.result()
        position = self.handle.tell()
        if position - self.flushed >= FLUSH_BYTES:
            self.handle.flush()
            self.flushed = position
            self.pending = self.pool.submit(self.sync, self.fileno)

    def close(self) -> None:
        self.pool.shutdown(wait=True)
        pending, self.pending = self.pending, None
        if pending is not None:
            pending.result()


class Writer:
    """Appends column dicts to an open binary (Parquet) or text (CSV) handle.

    Parquet: floats BYTE_STREAM_SPLIT (no dictionary: they almost never repeat), compression
    ``PARQUET_COMPRESSION``, the flag column dictionary-encoded; one row group per chunk.
    The Arrow arrays are the column arrays themselves (no copy); the schema, with each field's
    ``unit`` and ``description``, is built once, from the first chunk."""

    def __init__(self, handle, kind: str) -> None:
        self.handle, self.kind = handle, kind
        self.parquet = None
        self.schema = None
        self.header = True
        self.flusher = Flusher(handle) if handle.seekable() else None   # not a pipe

    @staticmethod
    def load(kind: str) -> None:
        """Import what writing ``kind`` needs, before the temporary output exists: a stop
        signal that lands inside an import comes out as whatever error the import makes of it
        (or is swallowed in an import's callback), not as the stop."""
        optional("pandas" if kind == "csv" else "pyarrow.parquet")

    def write(self, columns: dict[str, np.ndarray]) -> None:
        if self.kind == "csv":
            pd = optional("pandas")
            pd.DataFrame(columns, copy=False).to_csv(self.handle, index=False,
                                                     header=self.header)
            self.header = False
        else:
            self._write_parquet(columns)
        if self.flusher is not None:
            self.flusher.written()

    def _write_parquet(self, columns: dict[str, np.ndarray]) -> None:
        pa = optional("pyarrow")
        pq = optional("pyarrow.parquet")
        arrays = [arrow_array(values) for values in columns.values()]
        if self.parquet is None:
            self.schema = arrow_table(dict(zip(columns, arrays))).schema
            floats = [f.name for f in self.schema if pa.types.is_floating(f.type)]
            self.parquet = pq.ParquetWriter(
                self.handle, self.schema, use_dictionary=["flag"],
                compression=PARQUET_COMPRESSION,
                use_byte_stream_split=floats if PARQUET_SPLIT_FLOATS else False)
        self.parquet.write_table(pa.Table.from_arrays(arrays, schema=self.schema))

    def close(self) -> None:
        try:
            if self.parquet is not None:
                writer, self.parquet = self.parquet, None
                writer.close()
        finally:
            if self.flusher is not None:
                self.flusher.close()

    def abandon(self) -> None:
        with contextlib.suppress(BaseException):
            self.close()

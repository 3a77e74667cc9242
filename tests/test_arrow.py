"""Arrow arrays of numbers to NumPy and back (``gsfric.io.arrow``), and a streamed Parquet run
that needs no pandas."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from gsfric import models
from gsfric.io.arrow import arrow_array, numpy_view
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import column_values, read_columns, read_table, write_table
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.simulate.run import simulate_file

NUMBERS = st.sampled_from(["<f8", "<f4", "<f2", "<i8", "<i4", "<i2", "<i1", "<u8", "<u4",
                           "<u1"])


@given(hnp.arrays(NUMBERS, st.integers(0, 50)), st.integers(0, 10), st.integers(0, 10))
def test_numbers_round_trip_as_pyarrow_converts_them(values, start, stop):
    array, expected = arrow_array(values), pa.array(values)
    assert array.type == expected.type and array.null_count == expected.null_count == 0
    np.testing.assert_array_equal(array.to_numpy(), expected.to_numpy())   # NaN == NaN here
    part = array.slice(start, max(0, len(values) - start - stop))   # an offset into the buffer
    view = numpy_view(part)
    expected = part.to_numpy(zero_copy_only=True)
    assert view.dtype == expected.dtype
    np.testing.assert_array_equal(view, expected)


def test_contiguous_numbers_share_memory_both_ways():
    values = np.arange(6.0)
    array = arrow_array(values)
    assert array.buffers()[1].address == values.ctypes.data
    assert np.shares_memory(numpy_view(array), values)


@pytest.mark.parametrize("array", [pa.array([1.0, None, 3.0]), pa.array([True, False]),
                                   pa.array(["a", "b"]), pa.array([1, 2], pa.timestamp("s"))],
                         ids=["nulls", "booleans", "strings", "times"])
def test_anything_but_numbers_without_nulls_is_left_to_pyarrow(array):
    assert numpy_view(array) is None


@pytest.mark.parametrize("values", [np.arange(10.0)[::2], np.array([True, False]),
                                    np.array(["a", "bc"])],
                         ids=["strided", "booleans", "strings"])
def test_other_arrays_convert_as_pyarrow_converts_them(values):
    assert arrow_array(values).equals(pa.array(values))


def test_streamed_parquet_run_loads_no_pandas_and_matches_csv(tmp_path):
    """A Parquet trajectory streamed to Parquet gives the values of the same trajectory read
    from CSV (through pandas), without loading pandas."""
    t = np.arange(600) / 200.0
    motion = models.sinusoidal(t)
    q = quaternion_from_rotation(motion.rotation)
    frame = pd.DataFrame({"t": t, **dict(zip("xyz", motion.position.T)),
                          **dict(zip(("qw", "qx", "qy", "qz"), q.T))})
    write_table(frame, tmp_path / "t.parquet")
    write_table(frame, tmp_path / "t.csv")
    code = ("import sys; from gsfric.simulate.run import simulate_file\n"
            f"simulate_file({str(tmp_path / 't.parquet')!r}, {str(tmp_path / 'a.parquet')!r},"
            " chunk=250, window=9, progress=False)\n"
            "print('pandas' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.split()[-1] == "False"
    simulate_file(tmp_path / "t.csv", tmp_path / "b.parquet", chunk=250, window=9,
                  progress=False)
    assert pq.read_table(tmp_path / "a.parquet").equals(pq.read_table(tmp_path / "b.parquet"))


def test_read_columns_gives_read_tables_columns(tmp_path):
    """Numbers as NumPy (without pandas), anything else (here a NaN, which pandas stores as
    null) as pyarrow converts it, and an unnamed pandas index left out: the same numbers and
    the same first problem as the columns of ``read_table`` (pandas)."""
    frame = pd.DataFrame({"f": [0.5, 1.0, 2.0], "nan": [0.5, np.nan, 2.0], "i": [1, 2, 3],
                          "gap": pd.array([1, None, 3], dtype="Int64"), "s": ["a", "b", "c"],
                          "b": [True, False, True], "f32": np.float32([1, 2, 3])},
                         index=pd.Index([7, 8, 9]))
    path = tmp_path / "t.parquet"
    frame.to_parquet(path)      # the unnamed index is stored as __index_level_0__
    names, columns = read_columns(path)
    expected = read_table(path)
    assert names == list(expected.columns) == ["f", "nan", "i", "gap", "s", "b", "f32"]
    for name, column in zip(names, columns):
        assert isinstance(column, np.ndarray) == (name in ("f", "i", "f32")), name
        got, want = column_values(column, name), column_values(expected[name], name)
        np.testing.assert_array_equal(got[0], want[0])
        assert got[1] == want[1]


def test_read_columns_of_a_csv_file_are_read_tables(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("t,x\n0,1.5\n1,2.5\n")
    names, columns = read_columns(path)
    assert names == ["t", "x"]
    np.testing.assert_array_equal(columns[1], [1.5, 2.5])


@pytest.mark.parametrize("metadata", [b"not json", b"[]", b'{"index_columns": null}',
                                      b'{"index_columns": [1, {"kind": "range"}]}'],
                         ids=["not-json", "a-list", "null", "no-names"])
def test_unreadable_pandas_metadata_leaves_every_column(tmp_path, metadata):
    table = pa.table({"t": [0.0, 1.0], "x": [1.0, 2.0]})
    pq.write_table(table.replace_schema_metadata({b"pandas": metadata}), tmp_path / "m.parquet")
    names, columns = read_columns(tmp_path / "m.parquet")
    assert names == ["t", "x"]
    np.testing.assert_array_equal(columns[1], [1.0, 2.0])


def test_a_named_index_is_a_trajectory_column_streamed_or_not(tmp_path):
    """A trajectory whose time is the DataFrame's index (``set_index("t")``) reads, streamed
    (simulate) or whole (read_trajectory), as the flat file."""
    t = np.arange(300) / 200.0
    motion = models.sinusoidal(t)
    q = quaternion_from_rotation(motion.rotation)
    frame = pd.DataFrame({"t": t, **dict(zip("xyz", motion.position.T)),
                          **dict(zip(("qw", "qx", "qy", "qz"), q.T))})
    frame.to_parquet(tmp_path / "flat.parquet", index=False)
    frame.set_index("t").to_parquet(tmp_path / "indexed.parquet")
    flat, indexed = (read_trajectory(tmp_path / f"{n}.parquet") for n in ("flat", "indexed"))
    np.testing.assert_array_equal(flat.acceleration, indexed.acceleration)
    for name in ("flat", "indexed"):
        simulate_file(tmp_path / f"{name}.parquet", tmp_path / f"{name}-out.parquet",
                      chunk=128, window=9, progress=False)
    assert pq.read_table(tmp_path / "flat-out.parquet").equals(
        pq.read_table(tmp_path / "indexed-out.parquet"))


def test_text_with_gaps_is_written_with_missing_values():
    """A kept text column with gaps (pandas gives NaN or None there) becomes nulls."""
    array = arrow_array(np.array(["a", np.nan, None, "b"], dtype=object))
    assert array.to_pylist() == ["a", None, None, "b"]
    floats = arrow_array(np.array([1.0, np.nan])[::-1])          # strided: NaN stays a value
    assert floats.null_count == 0 and np.isnan(floats.to_numpy()[0])

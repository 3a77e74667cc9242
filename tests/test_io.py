"""File I/O: atomic writes, tables, trajectory and measured-data files and their messages."""

from __future__ import annotations

import os
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gsfric.errors import GsfricWarning, InputError
from gsfric.io.files import atomic_write
from gsfric.io.readers import read_measured, read_trajectory
from gsfric.io.tables import read_table, write_table
from gsfric.signal.rotations import quaternion_from_euler
from gsfric.trajectory import Motion

fuzz_settings = settings(suppress_health_check=[HealthCheck.function_scoped_fixture],
                         deadline=None, max_examples=150)


def trajectory_frame(n: int = 30, orientation: str = "euler") -> pd.DataFrame:
    t = np.linspace(0.0, 2.9, n)
    frame = pd.DataFrame({"t": t, "x": 0.01 * np.sin(t), "y": 0.02 * t, "z": 0.8 + 0.0 * t})
    euler = np.stack([0.1 * t, 0.2 + 0.05 * np.sin(t), -0.1 * t], axis=1)
    if orientation == "euler":
        frame[["alpha", "beta", "gamma"]] = euler
    else:
        frame[["qw", "qx", "qy", "qz"]] = quaternion_from_euler(*euler.T)
    return frame


def measured_frame(n: int = 30, lengths: bool = True) -> pd.DataFrame:
    frame = trajectory_frame(n)
    for i in range(1, 7):
        frame[f"F{i}"] = 10.0 * i + np.arange(n)
        if lengths:
            frame[f"D{i}"] = 0.7 + 0.001 * np.arange(n)
    return frame


def csv_text(frame: pd.DataFrame) -> str:
    return frame.to_csv(index=False)


def message_for(tmp_path, text: str, name: str = "trajectory.csv", measured: bool = False) -> str:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as info:
        (read_measured if measured else read_trajectory)(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message[len(f"{path}: "):]


def set_cell_frame(frame: pd.DataFrame, row: int, column: str, value: object) -> pd.DataFrame:
    """A copy with data row ``row`` (1-based) of ``column`` replaced by ``value``."""
    frame = frame.astype(object)
    frame.loc[row - 1, column] = value
    return frame


def set_cell(frame: pd.DataFrame, row: int, column: str, value: object) -> str:
    """CSV text of ``set_cell_frame``."""
    return csv_text(set_cell_frame(frame, row, column, value))


def _write(tmp_path, frame, name="trajectory.csv"):
    path = tmp_path / name
    write_table(frame, path)
    return path


# -- atomic writes ------------------------------------------------------------------------------


def test_atomic_write_writes(tmp_path):
    path = tmp_path / "a.txt"
    with atomic_write(path) as handle:
        handle.write("hello")
    assert path.read_text() == "hello"
    assert os.listdir(tmp_path) == ["a.txt"]
    with atomic_write(path, "wb") as handle:
        handle.write(b"\x00\x01")
    assert path.read_bytes() == b"\x00\x01"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_atomic_write_leaves_no_file_when_the_body_raises(tmp_path):
    path = tmp_path / "a.txt"
    with pytest.raises(RuntimeError):
        with atomic_write(path) as handle:
            handle.write("partial")
            raise RuntimeError("boom")
    assert os.listdir(tmp_path) == []


def test_atomic_write_keeps_the_old_file_when_the_body_raises(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(path) as handle:
            handle.write("new")
            raise KeyboardInterrupt
    assert path.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_atomic_write_permissions(tmp_path):
    path = tmp_path / "a.txt"
    with atomic_write(path) as handle:
        handle.write("x")
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask
    os.chmod(path, 0o600)
    with atomic_write(path) as handle:
        handle.write("y")
    assert path.stat().st_mode & 0o777 == 0o600


def test_atomic_write_missing_directory(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        with atomic_write(tmp_path / "no" / "a.txt") as handle:
            handle.write("x")


# -- tables -------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["t.csv", "t.parquet", "t.pq", "T.CSV"])
def test_table_round_trip_is_exact(tmp_path, name):
    rng = np.random.default_rng(3)
    frame = pd.DataFrame({
        "a": rng.standard_normal(200) * 10.0 ** rng.integers(-300, 300, 200),
        "b": np.arange(200, dtype=float) / 3,
        "c": np.full(200, 0.1 + 0.2),
    })
    write_table(frame, tmp_path / name)
    back = read_table(tmp_path / name)
    assert list(back.columns) == ["a", "b", "c"]
    for column in frame:
        np.testing.assert_array_equal(back[column].to_numpy(), frame[column].to_numpy())
    assert os.listdir(tmp_path) == [name]


def test_table_errors(tmp_path):
    with pytest.raises(InputError, match=r"t.xlsx: unknown extension '.xlsx'; use .csv"):
        read_table(tmp_path / "t.xlsx")
    with pytest.raises(InputError, match=r"unknown extension '\(none\)'"):
        write_table(pd.DataFrame({"a": [1]}), tmp_path / "t")
    with pytest.raises(InputError, match=r"missing.csv: file not found$"):
        read_table(tmp_path / "missing.csv")
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(InputError, match=r"empty.csv: file is empty$"):
        read_table(tmp_path / "empty.csv")
    (tmp_path / "blank.csv").write_text("\n\n")
    with pytest.raises(InputError, match=r"blank.csv: file is empty \(no header line\)$"):
        read_table(tmp_path / "blank.csv")
    (tmp_path / "bad.parquet").write_text("t,x\n1,2\n")
    with pytest.raises(InputError, match=r"bad.parquet: cannot read as Parquet"):
        read_table(tmp_path / "bad.parquet")
    (tmp_path / "bad.csv").write_text('t,x\n1,2\n3,4,5,6\n')
    with pytest.raises(InputError, match=r"bad.csv: cannot parse as CSV: row 2 has 4 fields "
                                         r"but the header has 2$"):
        read_table(tmp_path / "bad.csv")
    (tmp_path / "quote.csv").write_text('t,x\n1,"2\n3,4\n')
    with pytest.raises(InputError, match=r"quote.csv: cannot parse as CSV: .*EOF"):
        read_table(tmp_path / "quote.csv")
    (tmp_path / "bin.csv").write_bytes(b"t,x\n\xff\xfe,1\n")
    with pytest.raises(InputError, match=r"bin.csv: not UTF-8 text"):
        read_table(tmp_path / "bin.csv")
    (tmp_path / "dup.csv").write_text("t,x,x\n1,2,3\n")
    with pytest.raises(InputError, match=r"dup.csv: column 'x' appears more than once"):
        read_table(tmp_path / "dup.csv")
    (tmp_path / "dir.csv").mkdir()
    with pytest.raises(InputError, match=r"dir.csv: is a directory"):
        read_table(tmp_path / "dir.csv")


def test_a_byte_that_is_not_utf8_is_named_by_its_place_in_the_file(tmp_path):
    """pandas decodes a buffer at a time and counts from the buffer's start: the message
    names the line and the offset in the file, as decoding the whole file finds them."""
    data = b"t,x\n" + b"".join(b"%d,0.%d\n" % (k, k) for k in range(200_000)) + b"7,\xe9\n"
    (tmp_path / "late.csv").write_bytes(data)
    with pytest.raises(UnicodeDecodeError) as decoded:
        data.decode("utf-8")
    line = data[:decoded.value.start].count(b"\n") + 1
    with pytest.raises(InputError, match=rf"late.csv: not UTF-8 text \(line {line}, byte "
                                         rf"{decoded.value.start} of the file\)$"):
        read_table(tmp_path / "late.csv")


# -- trajectories -------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@pytest.mark.parametrize("orientation", ["euler", "quaternion"])
def test_read_trajectory(tmp_path, suffix, orientation):
    frame = trajectory_frame(orientation=orientation)
    path = tmp_path / f"trajectory{suffix}"
    write_table(frame, path)
    motion = read_trajectory(path)
    assert isinstance(motion, Motion) and len(motion) == 30
    np.testing.assert_array_equal(motion.t, frame["t"].to_numpy())
    np.testing.assert_allclose(motion.position, frame[["x", "y", "z"]].to_numpy(), atol=1e-6)


def test_euler_and_quaternion_files_agree(tmp_path):
    write_table(trajectory_frame(orientation="euler"), tmp_path / "e.csv")
    write_table(trajectory_frame(orientation="quaternion"), tmp_path / "q.csv")
    a, b = read_trajectory(tmp_path / "e.csv"), read_trajectory(tmp_path / "q.csv")
    for name in ("rotation", "omega", "alpha"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), atol=1e-12)


def test_motion_frame_reads_back(tmp_path):
    motion = read_trajectory(_write(tmp_path, trajectory_frame()))
    write_table(motion.to_frame(), tmp_path / "again.csv")
    again = read_trajectory(tmp_path / "again.csv")
    np.testing.assert_allclose(again.rotation, motion.rotation, atol=1e-7)
    np.testing.assert_allclose(again.position, motion.position, atol=1e-7)


def test_spaces_after_commas_are_accepted(tmp_path):
    text = csv_text(trajectory_frame()).replace(",", ", ")
    path = tmp_path / "spaced.csv"
    path.write_text(text)
    assert len(read_trajectory(path)) == 30


def test_read_measured(tmp_path):
    frame = measured_frame()
    motion, forces, lengths = read_measured(_write(tmp_path, frame, "m.csv"))
    assert len(motion) == 30 and forces.shape == (30, 6) and lengths.shape == (30, 6)
    np.testing.assert_array_equal(forces[:, 2], frame["F3"].to_numpy())
    np.testing.assert_array_equal(lengths[:, 5], frame["D6"].to_numpy())
    _, _, none = read_measured(_write(tmp_path, measured_frame(lengths=False), "m2.parquet"))
    assert none is None


def rows_removed(frame, count):
    return csv_text(frame.iloc[:count])


def renamed(frame, old, new):
    return csv_text(frame.rename(columns={old: new}))


def dropped(frame, *columns):
    return csv_text(frame.drop(columns=list(columns)))


def with_time(frame, row, value):
    frame = frame.copy()
    frame.loc[row - 1, "t"] = value
    return csv_text(frame)


def swapped_to_both(frame):
    frame = frame.copy()
    frame[["qw", "qx"]] = 1.0, 0.0
    return csv_text(frame)


def extra_field(frame, row):
    lines = csv_text(frame).splitlines()
    lines[row] += ",7"
    return "\n".join(lines) + "\n"


def zero_quaternion(frame, row):
    frame = frame.copy()
    frame.loc[row - 1, ["qw", "qx", "qy", "qz"]] = 0.0
    return csv_text(frame)


T = trajectory_frame()
Q = trajectory_frame(orientation="quaternion")
M = measured_frame()

BAD_TRAJECTORIES = [
    (set_cell(T, 17, "x", np.nan), "row 17: column 'x' is empty or NaN"),
    (set_cell(T, 17, "x", ""), "row 17: column 'x' is empty or NaN"),
    (set_cell(T, 3, "y", "abc"), "row 3: column 'y' is not a number: 'abc'"),
    (set_cell(T, 5, "beta", "inf"), "row 5: column 'beta' is infinite"),
    (set_cell(T, 9, "gamma", "1e400"), "row 9: column 'gamma' is infinite"),
    (set_cell(T, 4, "t", "-"), "row 4: column 't' is not a number: '-'"),
    (renamed(T, "gamma", "gama"),
     "missing column 'gamma' (is it 'gama'? map it with --column-map gamma=gama)"),
    (renamed(T, "x", "X"), "missing column 'x' (is it 'X'? map it with --column-map x=X)"),
    (renamed(T, "alpha", "psi"),
     "missing column 'alpha' (columns alpha, beta, gamma go together)"),
    (dropped(T, "z"), "missing column 'z' (map the log's column to it with --column-map z=NAME)"),
    (dropped(T, "alpha", "beta", "gamma"),
     "missing orientation: give columns alpha, beta, gamma, qw, qx, qy, qz or roll, pitch, yaw"),
    (dropped(Q, "qz"), "missing column 'qz' (columns qw, qx, qy, qz go together)"),
    (dropped(T, "beta"), "missing column 'beta' (columns alpha, beta, gamma go together)"),
    (with_time(T, 5, 0.0), "row 5: t = 0.0 is less than t = 0.3 in row 4; t must increase"),
    (with_time(T, 5, 0.3), "row 5: duplicate time t = 0.3 (same as row 4)"),
    (rows_removed(T, 5), "5 data rows; at least 7 are needed to differentiate the motion"),
    (rows_removed(T, 0), "no data rows"),
    (zero_quaternion(Q, 3), "row 3: quaternion of zero length"),
    ("t,x,y,z,alpha,beta,gamma\n" + "1,2,3,4,true,5,6\n" * 8,
     "row 1: column 'alpha' holds true/false values, not numbers"),
    ("t,x,y,z,alpha,beta,gamma\n" + "1,2,3,4,NULL,5,6\n" * 8,
     "row 1: column 'alpha' is not a number: 'NULL'"),
    (set_cell(T, 4, "beta", "nan"), "row 4: column 'beta' is empty or NaN"),
    (extra_field(T, 3), "cannot parse as CSV: row 3 has 8 fields but the header has 7"),
    (extra_field(T, 1), "cannot parse as CSV: row 1 has 8 fields but the header has 7"),
]


@pytest.mark.parametrize(("text", "expected"), BAD_TRAJECTORIES,
                         ids=[e for _, e in BAD_TRAJECTORIES])
def test_bad_trajectory_names_row_and_column(tmp_path, text, expected):
    assert message_for(tmp_path, text) == expected


BAD_MEASURED = [
    (dropped(M, "F3"), "missing column 'F3' (measured data need F1..F6)"),
    (dropped(M, "D4"), "missing column 'D4' (give all of D1..D6 or none)"),
    (set_cell(M, 6, "D2", -0.1), "row 6: column 'D2' must be positive (a leg length)"),
    (set_cell(M, 8, "F5", "n/a"), "row 8: column 'F5' is not a number: 'n/a'"),
    (renamed(M, "F6", "f6"), "missing column 'F6' (is it 'f6'? map it with --column-map F6=f6)"),
    (renamed(M, "F6", "F7"), "missing column 'F6' (measured data need F1..F6)"),
]


@pytest.mark.parametrize(("text", "expected"), BAD_MEASURED, ids=[e for _, e in BAD_MEASURED])
def test_bad_measured_names_row_and_column(tmp_path, text, expected):
    assert message_for(tmp_path, text, name="measured.csv", measured=True) == expected


def test_earliest_bad_row_is_reported(tmp_path):
    text = set_cell(set_cell_frame(T, 9, "z", np.nan), 4, "y", np.nan)
    assert message_for(tmp_path, text) == "row 4: column 'y' is empty or NaN"


def test_both_orientations_use_the_quaternion(tmp_path):
    frame = trajectory_frame(orientation="quaternion")
    motion = trajectory_frame(orientation="euler")
    frame[["alpha", "beta", "gamma"]] = motion[["alpha", "beta", "gamma"]]
    both = read_trajectory(_write(tmp_path, frame))
    plain = trajectory_frame(orientation="quaternion")
    expected = read_trajectory(_write(tmp_path, plain, "q.csv"))
    np.testing.assert_array_equal(both.rotation, expected.rotation)


def test_contradicting_orientations_are_an_error_naming_the_first_row(tmp_path):
    frame = trajectory_frame(orientation="quaternion")
    frame[["alpha", "beta", "gamma"]] = trajectory_frame(orientation="euler")[
        ["alpha", "beta", "gamma"]]
    frame.loc[17:, "gamma"] += 0.01
    path = _write(tmp_path, frame)
    with pytest.raises(InputError, match=r"row 18: the orientation columns disagree: alpha, "
                                         r"beta, gamma and qw, qx, qy, qz give rotations "
                                         r"0.01 rad apart \(tolerance 0.001 rad"):
        read_trajectory(path)
    frame[["alpha", "beta", "gamma"]] = 5.0                # junk in one set
    with pytest.raises(InputError, match="row 1: the orientation columns disagree"):
        read_trajectory(_write(tmp_path, frame))
    frame["beta"] = "n/a"
    with pytest.raises(InputError, match="row 1: column 'beta' is not a number"):
        read_trajectory(_write(tmp_path, frame))


def test_degree_warning_names_the_file(tmp_path):
    frame = trajectory_frame()
    frame[["alpha", "beta", "gamma"]] *= 180 / np.pi * 20
    path = _write(tmp_path, frame)
    with pytest.warns(GsfricWarning, match=rf"^{path}: angles look like degrees"):
        read_trajectory(path)


def test_gimbal_warning_names_rows(tmp_path):
    frame = trajectory_frame()
    frame["beta"] = 0.0
    frame.loc[10:, "alpha"] += 2.0
    frame.loc[10:, "gamma"] -= 2.0
    path = _write(tmp_path, frame)
    with pytest.warns(GsfricWarning, match=r"near beta = 0 .* at row 11;"):
        read_trajectory(path)


def test_clean_file_gives_no_warning(tmp_path):
    path = _write(tmp_path, trajectory_frame())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_trajectory(path)


# -- fuzzing ------------------------------------------------------------------------------------


@fuzz_settings
@given(raw=st.binary(max_size=400), suffix=st.sampled_from([".csv", ".parquet"]),
       measured=st.booleans())
def test_random_bytes_raise_only_input_error(tmp_path_factory, raw, suffix, measured):
    path = tmp_path_factory.mktemp("fuzz") / f"data{suffix}"
    path.write_bytes(raw)
    try:
        (read_measured if measured else read_trajectory)(path)
    except InputError as error:
        assert "\n" not in str(error)


names = st.sampled_from(["t", "x", "y", "z", "alpha", "beta", "gamma", "qw", "qx", "qy", "qz",
                         "F1", "F2", "F3", "F4", "F5", "F6", "D1", "gama", "", " t", "x.1"])
cells = st.one_of(
    st.sampled_from(["", "nan", "inf", "-inf", "abc", "1e400", "-1e308", "1e308", "0", "1",
                     '"', "'", "true", "1,5", "\t", "#", "0x10", "1e-320"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**30, 10**30).map(str),
    st.text(max_size=4),
)


@fuzz_settings
@given(header=st.lists(names, min_size=0, max_size=12),
       rows=st.lists(st.lists(cells, max_size=13), max_size=12),
       measured=st.booleans())
def test_random_csv_raises_only_input_error(tmp_path_factory, header, rows, measured):
    path = tmp_path_factory.mktemp("fuzz") / "data.csv"
    text = "\n".join([",".join(header)] + [",".join(row) for row in rows])
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", GsfricWarning)
            (read_measured if measured else read_trajectory)(path)
    except InputError as error:
        assert "\n" not in str(error)


good_columns = ["t", "x", "y", "z", "alpha", "beta", "gamma"]


@fuzz_settings
@given(values=st.lists(st.lists(st.floats(allow_nan=False, allow_infinity=False),
                                min_size=7, max_size=7), min_size=7, max_size=12))
def test_random_numbers_raise_only_input_error(tmp_path_factory, values):
    path = tmp_path_factory.mktemp("fuzz") / "data.csv"
    path.write_text("\n".join([",".join(good_columns)]
                              + [",".join(repr(v) for v in row) for row in values]))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", GsfricWarning)
            read_trajectory(path)
    except InputError as error:
        assert "\n" not in str(error)

"""What ``gsfric simulate`` tells at the end of a run: the per-leg table of peaks (the numbers of
its own output file, at their times from the record's start), the figure of ``--plot``, each
warning once, the ignored columns counted, and the limit on the share of flagged steps."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from helpers import trajectory_frame

from gsfric.cli import main
from gsfric.evaluation.peaks import Peaks
from gsfric.io.tables import read_table, write_table
from gsfric.platform.usable import FLAGGED_LIMIT
from gsfric.simulate.figure import MAX_BINS, Trace

DATA = Path(__file__).resolve().parent / "data"
LOG, LOG_FORMAT = DATA / "controller_log.csv", DATA / "controller_log.toml"


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def _table(stdout: str) -> np.ndarray:
    """The peaks table's rows (leg, |F|, t, |Ffr|, t, |R_E|, t, |R_C|, t, |M_C|, t)."""
    lines = stdout.splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("leg "))
    return np.array([[float(v) for v in line.split()] for line in lines[head + 1:head + 7]])


@pytest.fixture(scope="module")
def log_run(tmp_path_factory):
    """The shipped controller log (a wrapping microsecond counter, jittered stamps, its own
    velocity columns, a z-down frame) simulated with --breakdown and --plot."""
    folder = tmp_path_factory.mktemp("log")
    for path in (LOG, LOG_FORMAT):
        shutil.copy(path, folder / path.name)
    out, plot = folder / "forces.csv", folder / "forces.png"
    result = _cli("simulate", "--trajectory", folder / LOG.name, "--column-map",
                  folder / LOG_FORMAT.name, "--out", out, "--plot", plot, "--breakdown",
                  folder / "parts.csv")
    assert result.exit_code == 0, result.output
    return result, read_table(out), plot


@pytest.mark.integration
def test_the_peaks_table_holds_the_output_files_peaks_at_their_times(log_run):
    result, frame, _ = log_run
    table = _table(result.stdout)
    assert table[:, 0].tolist() == [1, 2, 3, 4, 5, 6]
    assert "|F| (N)" in result.stdout and "|M_C| (N m)" in result.stdout
    sound = frame[frame["flag"] == 0]
    t = sound["t"].to_numpy() - frame["t"].iloc[0]
    assert frame["t"].iloc[0] > 4000.0         # the counter's origin: the times are shifted
    for column, (value, when) in (("F", (1, 2)), ("Ffr", (3, 4)), ("MC", (9, 10))):
        values = np.abs(sound[[f"{column}{i}" for i in range(1, 7)]].to_numpy())
        np.testing.assert_allclose(table[:, value], values.max(axis=0), rtol=1e-3)
        np.testing.assert_allclose(table[:, when], t[values.argmax(axis=0)], atol=1e-3)
    reaction = np.linalg.norm(sound[[f"RE{a}{i}" for i in range(1, 7) for a in "xyz"]]
                              .to_numpy().reshape(-1, 6, 3), axis=2)
    np.testing.assert_allclose(table[:, 5], reaction.max(axis=0), rtol=1e-3)


@pytest.mark.integration
def test_each_warning_prints_once_and_ignored_columns_are_counted(log_run):
    result, _, _ = log_run
    warnings = [line for line in result.stderr.splitlines() if "warning" in line]
    assert warnings and len(warnings) == len(set(warnings))     # --breakdown reads it twice
    assert [line for line in warnings if "1 column ignored" in line] == [
        line for line in warnings if "(not gsfric inputs: 'Mode';" in line]
    assert result.stderr.count("'Mode'") == 1           # named once, in the warning


@pytest.mark.integration
def test_verbose_names_the_ignored_columns(tmp_path):
    for path in (LOG, LOG_FORMAT):
        shutil.copy(path, tmp_path / path.name)
    result = _cli("simulate", "--trajectory", tmp_path / LOG.name, "--column-map",
                  tmp_path / LOG_FORMAT.name, "--out", tmp_path / "o.csv", "--verbose",
                  "--breakdown", tmp_path / "parts.csv")
    assert result.exit_code == 0, result.output
    assert result.stderr.count("gsfric: ignored columns: 'Mode'") == 1


@pytest.mark.integration
def test_plot_is_a_figure_file(log_run):
    _, _, plot = log_run
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(plot.parent.glob(".*.tmp"))


def test_trace_bins_keep_every_extreme_in_bounded_memory(rng):
    n = 5 * MAX_BINS + 123
    t = np.arange(n) * 0.01
    F = rng.normal(size=(n, 6))
    F[1234, 2] = 50.0                       # one spike: a bin must keep it
    flag = np.zeros(n, dtype=np.int64)
    flag[7000] = 2
    sigma = np.abs(rng.normal(size=(n, 6)))
    sigma[4321, 5] = 9.0                    # the force's band keeps its largest sigma_F too
    trace = Trace()
    for s in range(0, n, 997):              # pieces that do not line up with the bins
        trace.add(t[s:s + 997], {"F": F[s:s + 997], "Ffr": -F[s:s + 997],
                                 "sigma_F": sigma[s:s + 997]}, flag[s:s + 997])
    assert MAX_BINS // 2 <= len(trace.t) <= MAX_BINS and trace.stride > 1
    np.testing.assert_allclose(np.diff(trace.t), trace.stride * 0.01)   # consecutive bins
    high, low = trace.high, trace.low
    np.testing.assert_array_equal(high[:, 0].max(axis=0), F.max(axis=0))
    np.testing.assert_array_equal(low[:, 0].min(axis=0), F.min(axis=0))
    np.testing.assert_array_equal(high[:, 1].max(axis=0), (-F).max(axis=0))
    # each bin starts `stride` steps after the one before and holds its steps' extremes
    k = 1234 // trace.stride
    assert trace.t[k] == pytest.approx(t[k * trace.stride])
    assert high[k, 0, 2] == 50.0
    assert np.flatnonzero(trace.flagged).tolist() == [7000 // trace.stride]
    assert high.shape[1] == 3 and high[4321 // trace.stride, 2, 5] == 9.0
    np.testing.assert_array_equal(high[:, 2].max(axis=0), sigma.max(axis=0))


def test_peaks_added_in_pieces_are_the_peaks_of_the_whole(rng):
    n = 1000
    t = 100.0 + np.arange(n) * 0.01
    arrays = {"F": rng.normal(size=(n, 6)), "R_E": rng.normal(size=(n, 18))}
    flag = np.zeros(n, dtype=np.int64)
    big = np.abs(arrays["F"]).argmax(axis=0)
    flag[big[0]] = 2                        # a flagged step's value is not a peak
    whole, pieces = Peaks(), Peaks()
    whole.add(t, arrays, flag)
    for s in range(0, n, 300):
        pieces.add(t[s:s + 300], {k: v[s:s + 300] for k, v in arrays.items()}, flag[s:s + 300])
    good = np.abs(arrays["F"])[flag == 0]
    np.testing.assert_array_equal(pieces.values["F"], good.max(axis=0))
    np.testing.assert_array_equal(pieces.values["F"], whole.values["F"])
    np.testing.assert_allclose(pieces.times["R_E"], whole.times["R_E"])
    assert pieces.sound == n - 1 and pieces.t0 == 100.0
    assert pieces.values["F"][0] < np.abs(arrays["F"][big[0], 0])


def _lifted(path: Path, spans) -> Path:
    """A 10 s, 100 Hz trajectory with the platform lifted 0.5 m (legs beyond the stroke)
    over the rows of each span."""
    frame = trajectory_frame(1000)
    for first, last in spans:
        frame.loc[first:last - 1, "z"] += 0.5
    write_table(frame, path)
    return path


def test_a_third_flagged_fails_naming_the_share_and_where_unless_kept(tmp_path):
    path = _lifted(tmp_path / "lifted.csv", [(200, 500)])     # 30 %, across two chunks
    out = tmp_path / "out.csv"
    kept = _cli("simulate", "--trajectory", path, "--out", out, "--chunk", 400,
                "--keep-flagged")
    assert kept.exit_code == 0, kept.output
    frame = read_table(out)
    flagged = np.flatnonzero(frame["flag"])
    # one run around the lifted rows (the streamed smoothing may round its edges by a step)
    assert np.all(np.diff(flagged) == 1) and abs(len(flagged) - 300) <= 4
    t = frame["t"].to_numpy() - frame["t"].iloc[0]
    where = (f"1 stretch (t from the record's start: {t[flagged[0]]:.3f}-{t[flagged[-1]]:.3f} s "
             f"({len(flagged)} steps))")
    share = f"{100 * len(flagged) / 1000:.3g} %"
    assert (f"{len(flagged)} of 1000 steps flagged (leg length outside the stroke: "
            f"{len(flagged)}; {share} of the steps) in {where}") in kept.stderr
    out.unlink()
    result = _cli("simulate", "--trajectory", path, "--out", out, "--chunk", 400)
    assert result.exit_code == 1
    message = result.stderr.strip().splitlines()[-1]
    assert f"{len(flagged)} of 1000 steps ({share}) are flagged" in message and where in message
    assert f"limit of {100 * FLAGGED_LIMIT:.3g} %" in message and "--keep-flagged" in message
    assert not out.exists()


def test_a_few_flagged_steps_warn_with_their_time_ranges(tmp_path):
    path = _lifted(tmp_path / "few.csv", [(100, 150), (700, 720)])
    result = _cli("simulate", "--trajectory", path, "--out", tmp_path / "o.csv")
    assert result.exit_code == 0, result.output
    assert "70 of 1000 steps flagged (leg length outside the stroke: 70; 7 % of" in result.stderr
    assert ("2 stretches (t from the record's start: 1.000-1.490 s (50 steps), 7.000-7.190 s "
            "(20 steps))") in result.stderr
    # the peaks leave the flagged steps out
    frame = read_table(tmp_path / "o.csv")
    sound = np.abs(frame.loc[frame["flag"] == 0, [f"F{i}" for i in range(1, 7)]].to_numpy())
    np.testing.assert_allclose(_table(result.stdout)[:, 1], sound.max(axis=0), rtol=1e-3)


def test_an_unknown_figure_format_is_refused_before_any_work(tmp_path):
    path = _lifted(tmp_path / "t.csv", [])
    result = _cli("simulate", "--trajectory", path, "--out", tmp_path / "o.csv", "--plot",
                  tmp_path / "f.jpeg")
    assert result.exit_code == 2
    assert result.stderr.strip() == (f"gsfric: error: {tmp_path / 'f.jpeg'}: --plot: unknown "
                                     "figure format 'jpeg'; give a file ending in .png, .svg, "
                                     ".pdf")
    assert not (tmp_path / "o.csv").exists()

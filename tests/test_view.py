"""The 3-D view (gsfric.view, ``gsfric view``, ``Result.to_html``): one self-contained page,
bounded in size, whose embedded data are the Result's within the stated quantisation error;
the command writes atomically and fails in one line; in a browser the page draws, and draws
another picture at another time."""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import html
import re
import shutil
import socket
import subprocess
import tempfile
import threading
import urllib.parse
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import gsfric
from gsfric import models
from gsfric.cli import main
from gsfric.evaluation.flags import FLAG_STROKE
from gsfric.io.tables import write_table
from gsfric.signal.rotations import rotation_from_quaternion
from gsfric.sweep import sweep
from gsfric.sweep.workspace import Workspace
from gsfric.synth import synthesize
from gsfric.view import Curve, FrameCollector, Plot, decode, embedded, notebook_html, page
from gsfric.view.data import decode_entry, quantise
from gsfric.view.frames import OUTPUTS

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

VENDOR = Path(gsfric.view.__file__).parent / "vendor"
MB = 1_000_000


def evaluate(n: int, span: float, platform=None):
    motion = models.sinusoidal(np.linspace(0.0, span, n))
    return gsfric.evaluate(platform or gsfric.reference_platform(), motion)


@pytest.fixture(scope="module")
def flagged():
    """A result with some steps flagged: the legs' stroke ends below their longest length."""
    platform = gsfric.reference_platform()
    longest = float(evaluate(400, 4.0).D.max())          # leg lengths (N, 6), m
    short = dataclasses.replace(platform, geometry=dataclasses.replace(
        platform.geometry, stroke=(0.3, longest - 0.01)))
    with pytest.warns(UserWarning):
        result = evaluate(400, 4.0, short)
    assert result.flag.any() and not result.flag.all()
    return result


def page_of(result, tmp_path, **options) -> str:
    path = result.to_html(tmp_path / "view.html", **options)
    return path.read_text(encoding="utf-8")


def own_text(page: str) -> str:
    """The page without the two vendored three.js scripts."""
    return re.sub(r'(<script type="text/plain" id="three-(core|module)">).*?(</script>)',
                  r"\1\3", page, flags=re.S)


# -- self-contained and small ----------------------------------------------------------------


def assert_self_contained(page: str) -> None:
    """No address outside the page: no src or href to a network, no request in its own code."""
    assert not re.search(r"""\b(src|href)\s*=\s*["']?\s*(https?:)?//""", page, re.I)
    own = own_text(page)
    for word in ("http://", "https://", "fetch(", "XMLHttpRequest", "WebSocket", "EventSource",
                 "sendBeacon", "<link", "<iframe", "@import"):
        assert word not in own, word


def test_the_page_loads_nothing_from_outside(flagged, tmp_path):
    page = page_of(flagged, tmp_path)
    assert_self_contained(page)
    # three.js is inlined unchanged: the vendored files, whose hashes vendor/README.md records
    readme = (VENDOR / "README.md").read_text()
    for name in ("three.core.min.js", "three.module.min.js"):
        text = (VENDOR / name).read_text(encoding="utf-8")
        assert text in page
        assert hashlib.sha256(text.encode()).hexdigest() in readme
    assert (VENDOR / "LICENSE").read_text().startswith("The MIT License")


def test_ten_thousand_steps_fit_in_three_megabytes(tmp_path):
    result = evaluate(10_000, 10_000 / 50.0)        # 50 steps a second: every step a frame
    page = page_of(result, tmp_path)
    data = embedded(page)
    assert data["frames"] == 10_000
    assert len(page.encode()) <= 3 * MB


def test_ten_thousand_steps_of_measured_data_fit_in_three_megabytes(tmp_path):
    frame = models.sinusoidal(np.arange(10_000) / 50.0).to_frame()
    for i in range(1, 7):                                # load cells: any values will do
        frame[f"F{i}"] = np.random.default_rng(i).normal(50.0, 20.0, len(frame))
    write_table(frame, tmp_path / "measured.csv")
    out = tmp_path / "view.html"
    assert run("view", "--trajectory", tmp_path / "measured.csv", "--out", out).exit_code == 0
    assert embedded(out.read_text())["frames"] == 10_000
    assert out.stat().st_size <= 3 * MB


def test_a_long_record_is_thinned_to_the_most_frames(tmp_path):
    result = evaluate(30_000, 600.0)
    data = embedded(page_of(result, tmp_path))
    assert data["frames"] <= gsfric.view.MAX_FRAMES and data["steps"] == 30_000


# -- the data round-trip ---------------------------------------------------------------------


def test_the_embedded_data_are_the_result_within_the_quantisation(flagged, tmp_path):
    data = embedded(page_of(flagged, tmp_path, fps=25))
    got = decode(data)
    step = got["step"]
    assert step[0] == 0 and step[-1] == len(flagged) - 1 and np.all(np.diff(step) > 0)
    assert np.allclose(np.diff(got["t"]), 1 / 25, atol=0.011)   # 100 steps a second
    motion = flagged.source[1]
    expected = {"F": flagged.F, "R_E": flagged.R_E, "R_C": flagged.R_C, "Ffr": flagged.Ffr,
                "MfrE": np.linalg.norm(flagged.MfrE, axis=2),
                "MfrC": np.linalg.norm(flagged.MfrC, axis=2), "position": motion.position}
    for name, values in expected.items():
        scale = data["arrays"][name]["scale"]
        assert scale == pytest.approx(np.abs(values[step]).max() / 32767)
        assert np.abs(got[name] - values[step]).max() <= 0.5 * scale * (1 + 1e-9), name
    assert np.abs(got["t"] - flagged.t[step]).max() <= 2**-24 * flagged.t[-1]
    rotation = rotation_from_quaternion(got["quaternion"] / np.linalg.norm(
        got["quaternion"], axis=1, keepdims=True))
    assert np.abs(rotation - motion.rotation[step]).max() < 1e-4
    # a frame's flag is the OR of its steps since the previous frame
    starts = np.concatenate([[0], step[:-1] + 1])
    assert np.array_equal(got["flag"], np.bitwise_or.reduceat(flagged.flag, starts))
    assert got["flag"].any() and data["flag_names"][str(FLAG_STROKE)]


def test_chunks_give_the_frames_of_the_whole(flagged):
    motion = flagged.source[1]
    whole = FrameCollector(fps=30).add_result(flagged).finish()
    pieces = FrameCollector(fps=30)
    for s, e in ((0, 7), (7, 150), (150, 151), (151, 400)):
        arrays = {name: flagged.arrays[name][s:e] for name in OUTPUTS}
        pieces.add(s, flagged.t[s:e], motion.position[s:e], motion.rotation[s:e], arrays,
                   flagged.flag[s:e])
    chunked = pieces.finish()
    for field in dataclasses.fields(whole):
        assert np.array_equal(getattr(whole, field.name), getattr(chunked, field.name),
                              equal_nan=True), field.name


def test_non_finite_values_are_kept_as_nan():
    values = np.array([[1.0, np.nan, -2.0]])
    back = decode_entry(quantise(values))
    assert np.isnan(back[0, 1]) and back[0, 0] == pytest.approx(1.0, abs=1e-4)


def test_a_plot_of_the_wrong_shape_is_refused_by_name():
    result = evaluate(200, 2.0)
    frames = FrameCollector(fps=30).add_result(result).finish()
    with pytest.raises(ValueError, match=r"^measured: values must be \(frames, 6\)"):
        Curve("measured", np.zeros((len(frames), 5)))
    short = Plot("force", "N", (Curve("measured", np.zeros((len(frames) - 1, 6))),))
    with pytest.raises(ValueError, match=rf"^force: measured has {len(frames) - 1} rows for "
                                         rf"{len(frames)} frames$"):
        page(frames, gsfric.reference_platform(), plots=[short])
    # a curve naming one of the frames' arrays is drawn from it, not stored twice
    both = Plot("force", "N", (Curve("F", "F"), Curve("twice", np.asarray(frames.F))))
    data = embedded(page(frames, gsfric.reference_platform(), plots=[both]))
    assert [c["array"] for c in data["plots"][0]["curves"]] == ["F", "curve1"]


def test_the_notebook_frame_holds_the_page(tmp_path):
    page = page_of(evaluate(200, 2.0), tmp_path)
    frame = notebook_html(page)
    found = re.fullmatch(r'<iframe srcdoc="([^"]*)".*></iframe>', frame, flags=re.S)
    assert found and html.unescape(found.group(1)) == page


def test_show_displays_the_frame_in_jupyter(monkeypatch, recwarn):
    display = pytest.importorskip("IPython.display")
    shown = []
    monkeypatch.setattr(display, "display", shown.append)
    result = evaluate(200, 2.0)
    result.show(height=500)
    assert len(shown) == 1 and shown[0].data.startswith("<iframe srcdoc=")
    assert "height: 500px" in shown[0].data and not recwarn.list


# -- the command -----------------------------------------------------------------------------


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def one_error(result) -> str:
    assert result.exit_code == 2, (result.exit_code, result.output)
    lines = [line for line in result.stderr.splitlines()
             if line and "generated/ is stale" not in line]
    assert len(lines) == 1 and lines[0].startswith("gsfric: error: "), result.stderr
    return lines[0][len("gsfric: error: "):]


@pytest.fixture
def trajectory(tmp_path) -> Path:
    path = tmp_path / "motion.csv"
    write_table(models.sinusoidal(np.linspace(0.0, 3.0, 301)).to_frame(), path)
    return path


def leftovers(folder: Path) -> list[str]:
    return [p.name for p in folder.iterdir() if p.name.startswith(".")]


def test_the_command_writes_the_page(trajectory, tmp_path):
    out = tmp_path / "view.html"
    result = run("view", "--trajectory", trajectory, "--out", out, "--fps", 20)
    assert result.exit_code == 0, result.output
    assert "301 steps as 61 frames" in result.stdout
    data = embedded(out.read_text())
    assert data["steps"] == 301 and data["frames"] == 61 and not leftovers(tmp_path)


def test_a_measured_data_file_is_viewed_against_its_forces(tmp_path, trajectory):
    record = synthesize(effects=["seal_friction:force=2"], samples=600, seed=2)
    measured = tmp_path / "measured.csv"
    write_table(record.frame, measured)
    out = tmp_path / "measured.html"
    assert run("view", "--measured", measured, "--out", out).exit_code == 0
    data = embedded(out.read_text())
    got = decode(data)
    F = record.frame[[f"F{i}" for i in range(1, 7)]].to_numpy()[got["step"]]
    force = curves(data, got, "actuator force")
    assert within_quantisation(force["measured"], F)
    # the model's curve and the residual are drawn from the page's arrays, not stored again
    entries = [c for p in data["plots"] for c in p["curves"]]
    assert [(c["array"], c["minus"]) for c in entries] == [
        ("F_measured", None), ("F", None), ("F_measured", "F"), ("Ffr", None)]
    assert np.array_equal(force["model"], got["F"])
    residual = curves(data, got, "residual")["residual"]
    assert np.abs(residual - (F - got["F"])).max() < 1e-3 * np.abs(F).max()
    # a trajectory without forces gets the plots of F and of the prismatic friction
    plain = tmp_path / "plain.html"
    assert run("view", "--trajectory", trajectory, "--out", plain).exit_code == 0
    titles = [p["title"] for p in embedded(plain.read_text())["plots"]]
    assert titles == ["actuator force F (+ push, \u2212 pull)", "prismatic friction Ffr"]
    # --measured requires the forces; one of --trajectory and --measured
    message = one_error(run("view", "--measured", trajectory, "--out", tmp_path / "m.html"))
    assert message == f"{trajectory}: a measured-data file needs the force columns F1..F6; " \
                      "F1 is missing"
    both = run("view", "--measured", measured, "--trajectory", trajectory, "--out", plain)
    assert both.exit_code == 2 and "give one of --trajectory and --measured" in both.output


@pytest.mark.parametrize(("name", "text", "expected"), [
    ("missing.csv", None, "file not found"),
    ("empty.csv", "", "file is empty"),
    ("nan.csv", "nan", "row 17: column 'x' is empty or NaN"),
])
def test_bad_trajectory_one_line_and_the_old_page_kept(tmp_path, trajectory, name, text,
                                                         expected):
    path = tmp_path / name
    if text == "nan":
        frame = models.sinusoidal(np.linspace(0.0, 3.0, 301)).to_frame()
        frame.loc[16, "x"] = np.nan                       # data row 17
        write_table(frame, path)
    elif text is not None:
        path.write_text(text)
    out = tmp_path / "view.html"
    out.write_text("old")
    message = one_error(run("view", "--trajectory", path, "--out", out))
    assert message.startswith(f"{path}: ") and expected in message
    assert out.read_text() == "old" and not leftovers(tmp_path)


@pytest.mark.parametrize(("out", "expected"), [
    ("view.png", "unknown extension '.png'; use .html"),
    ("missing/view.html", "does not exist"),
])
def test_bad_output_one_line(tmp_path, trajectory, out, expected):
    message = one_error(run("view", "--trajectory", trajectory, "--out", tmp_path / out))
    assert message.startswith(f"{tmp_path / out}: ") and expected in message


def test_bad_platform_one_line(tmp_path, trajectory):
    platform = tmp_path / "p.toml"
    platform.write_text("[geometry\n")
    message = one_error(run("view", "--trajectory", trajectory, "--platform", platform,
                            "--out", tmp_path / "v.html"))
    assert message.startswith(f"{platform}: ")


def test_the_page_is_not_written_onto_the_trajectory(tmp_path):
    path = tmp_path / "motion.html"
    path.write_text("t,x\n")
    message = one_error(run("view", "--trajectory", path, "--out", path))
    assert message == f"{path}: is the trajectory file itself; choose another output"


# -- in a browser ----------------------------------------------------------------------------


def chromium(*args: str) -> None:
    """Headless Chromium with software WebGL and a fresh profile, showing a page for 10 s of
    virtual time; ``args``: what to do with it and the page."""
    profile = tempfile.mkdtemp()
    try:
        subprocess.run(["chromium", "--headless", "--no-sandbox", "--use-gl=angle",
                        "--use-angle=swiftshader", "--no-first-run",
                        "--disable-background-networking", "--disable-component-update",
                        "--disable-sync", f"--user-data-dir={profile}",
                        "--virtual-time-budget=10000", *args],
                       capture_output=True, timeout=180, check=False)
    finally:
        shutil.rmtree(profile, ignore_errors=True)


def screenshot(page: Path, time: float, out: Path) -> np.ndarray:
    """A 1000 x 800 picture of the page opened at ``#t=time`` by headless Chromium with
    software WebGL, as (800, 1000, 3) uint8."""
    image = pytest.importorskip("PIL.Image")
    chromium(f"--screenshot={out}", "--window-size=1000,800", f"{page.as_uri()}#t={time}")
    assert out.exists(), "chromium wrote no screenshot"
    return np.asarray(image.open(out).convert("RGB"))


NEEDS_CHROMIUM = pytest.mark.skipif(shutil.which("chromium") is None,
                                    reason="needs chromium (apt-get install chromium)")


@pytest.fixture(scope="module")
def pictures(tmp_path_factory):
    """A 5 s motion's page, and pictures of it at the step of the most loaded leg's largest and
    smallest |F| (N): (result, picture at the peak, picture at the quiet step)."""
    folder = tmp_path_factory.mktemp("browser")
    result = evaluate(1001, 5.0)
    page = result.to_html(folder / "view.html")
    largest = np.abs(result.F).max(axis=1)               # the most loaded leg's |F|, N
    at_peak = screenshot(page, result.t[np.argmax(largest)], folder / "peak.png")
    quiet = screenshot(page, result.t[np.argmin(largest)], folder / "quiet.png")
    return result, at_peak, quiet


@NEEDS_CHROMIUM
def test_the_page_draws_in_a_browser_and_moves_with_time(pictures):
    result, first, second = pictures
    largest = np.abs(result.F).max(axis=1)
    assert abs(result.t[np.argmax(largest)] - result.t[np.argmin(largest)]) > 0.5
    stage = first[60:560, 260:1000]              # the 3-D view, right of the legend
    background = np.array([0xF4, 0xF5, 0xF7])
    drawn = np.abs(stage.astype(int) - background).sum(axis=2) > 30
    assert drawn.mean() > 0.05, "the 3-D view is empty"
    moved = np.abs(first[60:560].astype(int) - second[60:560]).sum(axis=2) > 30
    assert moved.mean() > 0.002, "the pictures at two times half a second apart are the same"


BROWSER_OWN = re.compile(r"(^|\.)(google\.com|googleapis\.com|gstatic\.com|gvt1\.com)"
                         r"(:\d+)?$")
"""Hosts Chromium itself calls (its clock, updates and accounts), whatever the page."""


def requested_hosts(page: str) -> list[str]:
    """The hosts headless Chromium asks for while it shows ``page`` (a URI) for 10 s of virtual
    time: every http(s) request goes through a proxy that records it and answers nothing."""
    seen: list[str] = []
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)

    def record():
        while True:
            try:
                connection, _ = server.accept()
            except OSError:
                return
            with connection:
                connection.settimeout(2)
                with contextlib.suppress(OSError):
                    target = connection.recv(4096).split(b" ")[1].decode("latin-1")
                    seen.append(urllib.parse.urlsplit(target).netloc or target)

    threading.Thread(target=record, daemon=True).start()
    try:
        chromium(f"--proxy-server=http://127.0.0.1:{server.getsockname()[1]}",
                 "--proxy-bypass-list=<-loopback>", "--dump-dom", page)
    finally:
        server.close()
    return [host for host in seen if not BROWSER_OWN.search(host)]


@NEEDS_CHROMIUM
def test_no_request_leaves_the_page_in_a_browser(tmp_path):
    page = evaluate(401, 2.0).to_html(tmp_path / "view.html")
    assert requested_hosts(f"{page.as_uri()}#t=1") == []
    # the proxy sees what a page asks for: one that loads a script from elsewhere is caught
    leaky = tmp_path / "leaky.html"
    leaky.write_text('<script src="https://cdn.example.org/three.js"></script>')
    assert requested_hosts(leaky.as_uri()) == ["cdn.example.org:443"]


def deep_red(picture: np.ndarray) -> int:
    """Pixels of the 3-D view (right of the legend) near the pushing end of the force scale
    (a leg at the record's largest push), shaded by the light: red well above green and blue."""
    stage = picture[60:560, 260:1000].astype(int)
    r, g, b = stage[..., 0], stage[..., 1], stage[..., 2]
    return int(np.count_nonzero((r > 100) & (r > 1.6 * b) & (b > 1.2 * g) & (r - g > 60)))


@NEEDS_CHROMIUM
def test_leg_colours_follow_the_force_in_a_browser(pictures):
    result, at_peak, quiet = pictures
    largest = np.abs(result.F).max(axis=1)               # the most loaded leg's |F|, N
    assert largest.min() < 0.6 * largest.max()
    assert deep_red(at_peak) > 300, "the leg at the largest push is not drawn in deep red"
    assert deep_red(quiet) < 30, "deep red drawn while no leg pushes near the largest force"


# -- the views of discover and sweep ---------------------------------------------------------


def curves(data: dict, arrays: dict, title_start: str) -> dict[str, np.ndarray]:
    """The curves (label -> (M, 6)) of the plot whose title starts with ``title_start``."""
    plot = next(p for p in data["plots"] if p["title"].startswith(title_start))
    return {c["label"]: arrays[c["array"]] - (arrays[c["minus"]] if c["minus"] else 0)
            for c in plot["curves"]}


def within_quantisation(got: np.ndarray, expected: np.ndarray) -> bool:
    """Equal to within int16 quantisation of an array whose largest magnitude is that of
    ``expected``'s (its stored scale)."""
    return np.abs(got - expected).max() <= 0.5 * np.abs(expected).max() / 32767 * (1 + 1e-6)


@pytest.fixture(scope="module")
def discovered(tmp_path_factory):
    """A discovery of a hidden seal friction of 2 N, written with its report.html."""
    out = tmp_path_factory.mktemp("discover") / "out"
    record = synthesize(effects=["seal_friction:force=2"], samples=1200, seed=1)
    d = gsfric.discover(record.frame, candidates=["seal_friction", "sensor_bias"],
                        n_bootstrap=20, out=out)
    return d, out / "report.html"


def test_discover_writes_the_view_of_model_and_measurement(discovered):
    d, path = discovered
    page = path.read_text(encoding="utf-8")
    assert_self_contained(page)
    data = embedded(page)
    got = decode(data)
    rows = got["step"] - d.used.start                # the frames' samples among those used
    assert got["step"][0] == d.used.start and got["step"][-1] == d.used.stop - 1
    force = curves(data, got, "actuator force")
    assert within_quantisation(force["measured"], d.forces[rows])
    assert within_quantisation(force["as given"], d.result_before.F[d.used][rows])
    assert within_quantisation(force["final"], d.forces_after[rows])
    # the legs are drawn with the final model's forces: the fitted model's own evaluation
    assert within_quantisation(got["F"], d.forces_after[rows])
    residual = curves(data, got, "residual")
    assert within_quantisation(residual["final"], (d.forces - d.forces_after)[rows])
    # where the legs slide, the final residual is the workflow's
    sliding = d.sliding[rows]
    assert np.abs(residual["final"][sliding] - d.residual_after[rows][sliding]).max() < 1e-3
    # a seal friction adds its force against each leg's sliding: +-force, nothing else
    contribution = curves(data, got, "contribution")["seal_friction"]
    force_fitted = d.effects[0].parameters["force"]
    assert np.nanmax(np.abs(contribution)) == pytest.approx(force_fitted, rel=1e-3)
    assert force_fitted == pytest.approx(2.0, rel=0.05)


def sweep_inputs(folder: Path, workspace: bool) -> dict:
    """Two trajectory files, or a workspace of 20 poses: a small sweep's inputs."""
    if workspace:
        return {"workspace": Workspace.from_dict({
            "sampling": "lhs", "samples": 20, "states": 4, "seed": 3,
            "pose": {"x": [-0.04, 0.04], "y": [-0.04, 0.04], "z": [0.66, 0.74],
                     "roll": [-0.08, 0.08], "pitch": [-0.08, 0.08], "yaw": [-0.1, 0.1]},
            "bounds": {"velocity": 0.2, "omega": 0.4, "acceleration": 2.0, "alpha": 4.0}})}
    for k in range(2):
        motion = models.random_motion(np.random.default_rng(k), np.linspace(0, 4, 801))
        write_table(motion.to_frame(), folder / f"motion{k}.csv")
    return {"trajectories": [str(folder / "motion*.csv")]}


@pytest.mark.parametrize("workspace", [False, True], ids=["motions", "workspace"])
def test_sweep_writes_the_view_of_each_joints_worst_case(tmp_path, workspace):
    result = sweep(tmp_path / "out", scheduler="serial", plots=True,
                   vary={"platform.payload_mass": (0.0, 8.0)}, variants=2, seed=1,
                   **sweep_inputs(tmp_path, workspace))
    page = (tmp_path / "out" / "worst_cases.html").read_text(encoding="utf-8")
    assert_self_contained(page)
    data = embedded(page)
    got = decode(data)
    assert data["frames"] == 12 and len(data["captions"]) == 12
    assert data["focus"] == [0, 1, 2, 3, 4, 5] * 2           # each frame shows its joint's leg
    # frame k: the largest |R_E| of leg k + 1, then the largest |R_C| of each leg; the
    # state rebuilt and evaluated again gives the load the sweep found
    summary = result.summary.set_index(["quantity", "leg"])
    for k in range(12):
        quantity, leg = ("R_E", "R_C")[k // 6], k % 6 + 1
        row = summary.loc[(quantity, leg)]
        load = np.linalg.norm(got[quantity][k, leg - 1])
        scale = data["arrays"][quantity]["scale"]
        assert abs(load - row.value) <= np.sqrt(3) * 0.5 * scale * (1 + 1e-6), (quantity, leg)
        assert f"{row.value:.4g} N" in data["captions"][k]
        where = f"state {row.step}" if workspace else f"{row.motion}, step {row.step}"
        assert where in data["captions"][k]
    loads = curves(data, got, "joint loads")       # the plot's curves: the same loads
    largest = [summary.loc[("R_C", leg)].value for leg in range(1, 7)]
    assert np.allclose(np.diag(loads["|R_C|"][6:]), largest, rtol=1e-4)

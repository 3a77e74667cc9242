"""``gsfric export``: the C library of a platform builds strictly, matches Python, links twice."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner

from gsfric.cli import main
from gsfric.compiled.state import state_layout
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import FLAG_ROTATION
from gsfric.export import folded, source
from gsfric.export.verify import TOLERANCE, check_motions, verify_library
from gsfric.export.writer import export_library
from gsfric.models import reference_platform
from gsfric.trajectory import ROTATION_TOL

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1"]
STALE = "gsfric: warning: generated/ is stale"


@pytest.fixture(scope="module")
def exports(tmp_path_factory) -> dict[str, Path]:
    """One export per friction model of the reference platform (prefixes hexa, hexp), and
    the coupled model's generic build (hexg)."""
    root = tmp_path_factory.mktemp("export")
    export_library(reference_platform(), root / "coupled", model="coupled", prefix="hexa")
    export_library(reference_platform(), root / "paper", model="paper", prefix="hexp")
    export_library(reference_platform(), root / "generic", model="coupled", prefix="hexg",
                   code="generic")
    return {"coupled": root / "coupled", "paper": root / "paper", "generic": root / "generic"}


@pytest.fixture(scope="module")
def objects(exports, tmp_path_factory) -> dict[str, Path]:
    """Each export's library compiled once by ``cc`` with ``STRICT`` (an object file), for the
    tests that link a program of their own against it."""
    root = tmp_path_factory.mktemp("objects")
    built = {}
    for name, folder in exports.items():
        prefix = next(p.stem for p in folder.glob("*.h"))
        built[name] = root / f"{prefix}.o"
        run = subprocess.run(["cc", *STRICT, "-c", "-I", str(folder), "-o", str(built[name]),
                              str(folder / f"{prefix}.c")], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr[-3000:]
    return built


def _build(folder: Path, cc: str, flags, tmp: Path, extra=(), library: Path | None = None
           ) -> Path:
    """example of ``folder`` built by ``cc`` with ``flags`` into ``tmp``, with the library's
    source or, given, its object file ``library``."""
    prefix = next(p.stem for p in folder.glob("*.h"))
    target = tmp / f"example-{Path(cc).name}"
    source = library if library is not None else folder / f"{prefix}.c"
    run = subprocess.run([cc, *flags, *extra, "-I", str(folder), "-o", str(target),
                          str(folder / "example.c"), str(source), "-lm"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    return target


def _states(n: int = 5) -> np.ndarray:
    return state_array(check_motions(reference_platform(), 50, 1))[:n]


def _numbers(run: subprocess.CompletedProcess) -> np.ndarray:
    """The numbers a program printed, a row a line."""
    return np.array([[float(v) for v in line.split()] for line in run.stdout.splitlines()])


def _example(program: Path, x: np.ndarray, env=None) -> subprocess.CompletedProcess:
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in x) + "\n"
    return subprocess.run([str(program)], input=text, capture_output=True, text=True, env=env)


@pytest.mark.parametrize("cc", ["gcc", "clang"])
def test_builds_strictly_and_runs(exports, tmp_path, cc):
    if shutil.which(cc) is None:
        pytest.skip(f"{cc} is not installed")
    x = _states()
    run = _example(_build(exports["coupled"], cc, STRICT, tmp_path), x)
    assert run.returncode == 0, run.stderr
    got = _numbers(run)
    F = Evaluator(reference_platform()).actuator_forces(x)
    np.testing.assert_allclose(got[:, :6], F, rtol=1e-12, atol=1e-9)
    assert np.all(got[:, 6] == 0)


def test_generic_build_agrees(exports, objects, tmp_path):
    x = _states(20)
    runs = {}
    for code, folder in (("specialised", "coupled"), ("generic", "generic")):
        header = next(exports[folder].glob("*.h")).read_text()
        assert f'_CODE "{code}"' in header
        (tmp_path / code).mkdir()
        run = _example(_build(exports[folder], "cc", STRICT, tmp_path / code,
                              library=objects[folder]), x)
        assert run.returncode == 0, run.stderr
        runs[code] = _numbers(run)
    F = Evaluator(reference_platform()).actuator_forces(x)
    for got in runs.values():
        np.testing.assert_allclose(got[:, :6], F, rtol=1e-12, atol=1e-9)
    assert "PARAMETERS[" in (exports["generic"] / "hexg.c").read_text()
    assert "PARAMETERS[" not in (exports["coupled"] / "hexa.c").read_text()


def test_straight_line_c_matches_casadi(tmp_path):
    x = ca.SX.sym("x", 4)
    d = x[0] * x[0] + 1.5
    first = ca.vertcat(x[1] / d, x[2] / d, x[3] / 3.0, x[0] / (x[1] + 7.0))
    second = ca.vertcat(ca.sqrt(d), ca.exp(-x[2]), ca.fabs(x[3]),
                        ca.if_else(x[0] >= x[1], x[0], x[1]),
                        2.0 * x[1], -x[3], x[2] ** 2, ca.tanh(x[0]), ca.atan2(x[1], x[2]),
                        1.0 / x[0], ca.log(d) * x[3] - x[1])
    fn = ca.Function("probe", [x], [first, second])
    body = folded.statements(fn, ["0", "1"])
    only_first = folded.function_text(body, "first", {0})
    assert only_first.count("/") == 2  # one reciprocal of d, x[0] / (x[1] + 7); 1/3 a product
    assert "sqrt" not in only_first and "exp" not in only_first
    text = folded.function_text(body, "probe")
    program = tmp_path / "probe.c"
    program.write_text("#include <math.h>\n#include <stdio.h>\ntypedef double casadi_real;\n"
                       + source.helper_text(source.helpers_called(text)) + "\n" + text
                       + only_first + """
int main(void)
{
    double x[4], a[4], b[11], c[4], *res[2] = {a, b}, *part[1] = {c};
    while (scanf("%lf %lf %lf %lf", &x[0], &x[1], &x[2], &x[3]) == 4) {
        probe(x, res);
        first(x, part);
        for (int k = 0; k < 4; ++k) printf("%.17g %.17g ", a[k], c[k]);
        for (int k = 0; k < 11; ++k) printf("%.17g ", b[k]);
        printf("\\n");
    }
    return 0;
}
""")
    built = subprocess.run(["cc", *STRICT, "-o", str(tmp_path / "probe"), str(program), "-lm"],
                           capture_output=True, text=True)
    assert built.returncode == 0, built.stderr[-3000:]
    rows = np.random.default_rng(3).uniform(-2.0, 2.0, (25, 4))
    got = _numbers(_example(tmp_path / "probe", rows))
    for row, values in zip(rows, got):
        want = [np.asarray(v).ravel() for v in fn(row)]
        np.testing.assert_array_equal(values[0:8:2], values[1:8:2])
        np.testing.assert_allclose(values[0:8:2], want[0], rtol=4e-16)
        np.testing.assert_allclose(values[8:], want[1], rtol=4e-16)


def test_makefile_builds(exports, tmp_path):
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    folder = tmp_path / "copy"
    shutil.copytree(exports["paper"], folder)
    run = subprocess.run(["make", "-s", "CFLAGS=" + " ".join(STRICT)], cwd=folder,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (folder / "libhexp.a").is_file() and (folder / "example").is_file()


@pytest.mark.parametrize("model", ["coupled", "paper"])
def test_matches_python(exports, model):
    report = verify_library(exports[model], n_random=400, rounds=200)
    assert report.flag_mismatches == 0
    assert report.worst_error <= TOLERANCE, report.lines()
    assert report.pose_error <= 1e-15
    assert report.ok and report.model == model and report.latency_ns > 0


def test_sanitizers(exports, tmp_path):
    probe = tmp_path / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    flags = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O0"]
    if subprocess.run(["cc", *flags, "-o", str(tmp_path / "probe"), str(probe)],
                      capture_output=True).returncode:
        pytest.skip("no sanitizer runtime")
    program = _build(exports["coupled"], "cc", ["-std=c99", *flags], tmp_path)
    x = _states(3)
    x[1, 4] = np.nan
    run = _example(program, x)
    assert run.returncode == 0, run.stderr[-3000:]
    rows = run.stdout.splitlines()
    assert len(rows) == 3 and rows[1].split()[-1] == "1" and "nan" in rows[1]


def test_two_prefixes_in_one_program(exports, objects, tmp_path):
    main_c = tmp_path / "both.c"
    main_c.write_text("""#include <stdio.h>
#include <string.h>
#include "hexa.h"
#include "hexp.h"
int main(void)
{
    double x[HEXA_STATE_SIZE] = {0}, F[6], G[6];
    const double p[3] = {0, 0, 0.7}, q[4] = {1, 0, 0, 0}, z[3] = {0, 0, 0};
    const double v[3] = {0.1, 0.05, 0.2}, w[3] = {0.3, -0.2, 0.4};
    hexa_pose_state(p, q, v, w, z, z, x);
    int a = hexa_actuator_forces(x, F), b = hexp_actuator_forces(x, G);
    hexa_outputs out;
    hexa_evaluate(x, &out);
    printf("%d %d %d %.17g %.17g\\n", a, b, memcmp(F, out.F, sizeof F) == 0, F[0], G[0]);
    return 0;
}
""")
    target = tmp_path / "both"
    run = subprocess.run(["cc", *STRICT, "-I", str(exports["coupled"]), "-I",
                          str(exports["paper"]), "-o", str(target), str(main_c),
                          str(objects["coupled"]), str(objects["paper"]), "-lm"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    out = subprocess.run([str(target)], capture_output=True, text=True).stdout.split()
    assert out[:3] == ["0", "0", "1"]  # evaluate's F is actuator_forces' to the bit
    assert float(out[3]) > 0 and float(out[3]) != float(out[4])


def test_deterministic_and_force_scale(exports, tmp_path):
    again = tmp_path / "again"
    export_library(reference_platform(), again, model="coupled", prefix="hexa")
    for path in exports["coupled"].iterdir():
        assert (again / path.name).read_bytes() == path.read_bytes(), path.name
    scaled = reference_platform().with_effect("force_scale", g1=0.1, g4=-0.05)
    export_library(scaled, tmp_path / "scaled", prefix="scaled")
    assert verify_library(tmp_path / "scaled", n_random=100, rounds=100).ok


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def error_of(result, code: int = 2) -> str:
    assert result.exit_code == code, (result.exit_code, result.output)
    got = [line for line in result.stderr.splitlines() if line and not line.startswith(STALE)]
    assert len(got) == 1 and got[0].startswith("gsfric: error: "), result.stderr
    return got[0]


def test_time_offset_is_refused(tmp_path):
    platform = tmp_path / "delayed.toml"
    reference_platform().with_effect("time_offset", delay=0.01).to_toml(platform)
    message = error_of(run("export", "--platform", platform, "--out", tmp_path / "out"))
    assert "time_offset" in message
    assert not (tmp_path / "out").exists()


def test_bad_arguments(tmp_path):
    assert "no such file" in error_of(run("export", "--platform", tmp_path / "missing.toml",
                                          "--out", tmp_path / "out"))
    existing = tmp_path / "file.txt"
    existing.write_text("x")
    assert "not a directory" in error_of(run("export", "--out", existing))
    assert "C identifier" in error_of(run("export", "--out", tmp_path / "o", "--prefix", "1x"))
    assert "C identifier" in error_of(run("export", "--out", tmp_path / "o", "--prefix",
                                          "a-b"))
    assert "no library" in error_of(run("export", "--verify", tmp_path))


@pytest.mark.parametrize("prefix, why", [
    ("math", "C standard header <math.h>"), ("stdio", "C standard header <stdio.h>"),
    ("Stdlib", "C standard header <stdlib.h>"), ("all", "make or CMake target"),
    ("clean", "make or CMake target"), ("help", "make or CMake target"),
    ("ALL_BUILD", "make or CMake target"), ("m", "system library"),
    ("_Bool", "not a C identifier"), ("__hidden", "reserved in C"), ("_Hidden", "reserved in C"),
    ("_", "reserved in C"), ("_lower", "reserved in C"), ("main", "the example program's"),
    ("example", "the example program's"),
])
def test_prefixes_that_the_build_or_the_compiler_reserve(tmp_path, prefix, why):
    message = error_of(run("export", "--out", tmp_path / "o", "--prefix", prefix))
    assert message.strip().startswith(f"gsfric: error: --prefix: {prefix!r} is ")
    assert why in message and len(message.strip().splitlines()) == 1, message
    assert not (tmp_path / "o").exists()


def test_a_folder_holding_another_library_is_refused(tmp_path):
    """A second prefix into a folder that holds an export would leave two libraries, one
    Makefile and one manifest: refused, the first export untouched; the same prefix again
    replaces its own files."""
    folder = tmp_path / "e"
    assert run("export", "--out", folder).exit_code == 0
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    message = error_of(run("export", "--out", folder, "--prefix", "other"))
    assert "holds the library 'gsfric' (gsfric.h)" in message
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    assert run("export", "--out", folder).exit_code == 0


def test_pose_state_normalises_any_finite_quaternion(exports, objects, tmp_path):
    """A quaternion of norm 1e200 (its squared norm overflows) or 1e-200 (underflows) is the
    same rotation as the unit one: the components are scaled by the largest first."""
    main_c = tmp_path / "pose.c"
    main_c.write_text("""#include <stdio.h>
#include "hexa.h"
int main(void)
{
    const double p[3] = {0, 0, 0.7}, z[3] = {0, 0, 0};
    const double scales[3] = {1.0, 1e200, 1e-200};
    double x[HEXA_STATE_SIZE];
    for (int k = 0; k < 3; k++) {
        double q[4] = {0.5 * scales[k], 0.5 * scales[k], -0.5 * scales[k], 0.5 * scales[k]};
        hexa_pose_state(p, q, z, z, z, z, x);
        for (int i = 0; i < 9; i++)
            printf("%.17g ", x[HEXA_STATE_ROTATION + i]);
        printf("\\n");
    }
    return 0;
}
""")
    target = tmp_path / "pose"
    built = subprocess.run(["cc", *STRICT, "-I", str(exports["coupled"]), "-o", str(target),
                            str(main_c), str(objects["coupled"]), "-lm"],
                           capture_output=True, text=True)
    assert built.returncode == 0, built.stderr[-3000:]
    rows = [[float(v) for v in line.split()] for line in subprocess.run(
        [str(target)], capture_output=True, text=True).stdout.splitlines()]
    assert len(rows) == 3 and rows[0] != [1, 0, 0, 0, 1, 0, 0, 0, 1]
    np.testing.assert_allclose(rows[1], rows[0], atol=1e-15)
    np.testing.assert_allclose(rows[2], rows[0], atol=1e-15)


def test_a_rotation_block_that_is_not_a_rotation_is_flagged(exports, objects, tmp_path):
    """The library flags what ``Motion`` refuses: T scaled by 2, mirrored, or off by more than
    ROTATION_TOL, with F NaN; a rotation rounded within the tolerance is a sound step."""
    x = _states(5)
    rotation = state_layout().rotation
    changes = [np.diag([2.0, 2.0, 2.0]), np.diag([1.0, -1.0, 1.0]),
               np.diag([1.0 + 3 * ROTATION_TOL] * 3), np.eye(3) + 3 * ROTATION_TOL * np.eye(3, k=1),
               np.diag([1.0 + ROTATION_TOL / 4] * 3)]
    for row, change in zip(x, changes):
        row[rotation] = (row[rotation].reshape(3, 3) @ change).ravel()
    for name in ("coupled", "paper", "generic"):
        (tmp_path / name).mkdir()
        got = _numbers(_example(_build(exports[name], "cc", STRICT, tmp_path / name,
                                       library=objects[name]), x))
        assert list(got[:, 6]) == [FLAG_ROTATION] * 4 + [0], name
        assert np.isnan(got[:4, :6]).all() and np.isfinite(got[4, :6]).all()
    header = (exports["coupled"] / "hexa.h").read_text()
    assert f"#define HEXA_FLAG_ROTATION {FLAG_ROTATION}" in header


def test_verify_checks_the_library_its_manifest_names(exports, tmp_path):
    folder = tmp_path / "two"
    export_library(reference_platform(), folder, model="paper", prefix="first")
    manifest = json.loads((folder / "manifest.json").read_text())
    assert (manifest["prefix"], manifest["model"], manifest["code"]) == \
        ("first", "paper", "specialised")
    assert sorted(p.name for p in folder.iterdir()) == manifest["files"]
    # a second library copied in by hand (export itself refuses the folder)
    export_library(reference_platform(), tmp_path / "other", model="paper", prefix="second")
    for name in ("second.h", "second.c", "manifest.json"):
        shutil.copy(tmp_path / "other" / name, folder / name)
    message = error_of(run("export", "--verify", folder))
    assert "holds two libraries, second.h" in message and "first.h" in message
    (folder / "first.h").unlink()
    assert verify_library(folder, n_random=50, rounds=10).prefix == "second"
    (folder / "manifest.json").unlink()
    assert "no manifest.json" in error_of(run("export", "--verify", folder))
    (folder / "manifest.json").write_text("{}")
    assert "manifest.json is not the manifest" in error_of(run("export", "--verify", folder))


def test_verify_fails_a_library_with_a_wrong_stroke(exports, tmp_path):
    """States beyond the stroke are among the checked ones: a library whose stroke limit is
    wrong fails --verify, with its flags differing."""
    folder = tmp_path / "wrong"
    shutil.copytree(exports["paper"], folder)
    hi = reference_platform().geometry.stroke[1]
    code = (folder / "hexp.c").read_text()
    line = next(k for k in code.splitlines() if k.startswith("static const gsfric_flags FLAGS"))
    assert f", {hi!r}, " in line
    wrong = code.replace(line, line.replace(f", {hi!r}, ", f", {2 * hi!r}, "))
    (folder / "hexp.c").write_text(wrong)
    report = verify_library(folder, n_random=50, rounds=10)
    assert report.flag_mismatches > 0 and not report.ok
    assert report.worst_error <= TOLERANCE and report.flagged_states > 0

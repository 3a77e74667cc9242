"""Golden outputs of the `gsfric` command line, to prove a restructure changes no behaviour.

It drives only the command line, ``python -c "from gsfric.cli import main; main()" ...``, in
child processes, so the gsfric it exercises is the one PYTHONPATH selects (every child runs
with PYTHONSAFEPATH=1 and its working directory in OUT_DIR, so neither the working directory
nor the editable install can shadow it). ``record`` prints the ``gsfric.__file__`` it found.

    # 1. the earlier code (e.g. `git worktree add ../before <commit>`); generates OUT_DIR/inputs
    PYTHONPATH=../before .venv/bin/python benchmarks/goldens.py record ../goldens/base
    # 2. the new code on the SAME inputs (copied into OUT_DIR/inputs), since generating them
    #    imports gsfric.models and gsfric.io, whose layout may differ between the two
    PYTHONPATH=. .venv/bin/python benchmarks/goldens.py record ../goldens/after \
        --inputs ../goldens/base/inputs
    # 3. compare: one line per file that is not bit-identical, a summary, exit 1 on a difference
    .venv/bin/python benchmarks/goldens.py compare ../goldens/base ../goldens/after

Cases (one folder each, every command run from OUT_DIR with relative paths):

* ``simulate/<platform>_<friction>_<motion>``: ``simulate --columns all --breakdown`` on
  3 platforms (reference template, the paper's platform.toml, a heavier "modified" template)
  x 2 friction models ([friction] model = coupled / paper) x 3 motions (sinusoidal,
  point-to-point minimum-jerk, random); plus extras: the built-in default platform, a streamed
  run (--chunk), the paper's 40 steps in --mode paper, and a measured record (residuals).
* ``discover/<record>``: ``discover`` on 17 seeded ``synth`` records (null, singles, a pair,
  correlated/pose noise, a wrong true platform, the paper friction model, and three
  out-of-catalog disturbances added by a numpy snippet: a 3.1 Hz interference on one load
  cell, a dead band on another, crosstalk between two; the interference stays below
  detection, verdict no_discrepancy).
* ``sweep/<name>``: envelopes over two trajectories with --vary, and over a workspace with
  --tolerance (fixed seeds, --scheduler serial).
* ``paper/<name>``: ``paper`` tables in paper and kinematic mode, and on the reference platform.

Every case's commands, exit codes, stdout and stderr are kept in ``logs/<case>.txt`` (those
making the inputs in ``inputs/logs/``).

``compare`` checks that both folders hold the same files; CSV/Parquet column by column, JSON
structurally, Markdown/TOML/text line by line, numbers equal or within a relative difference
|a-b|/max(|a|,|b|,tiny) of 1e-12; PNG files are only listed. Ignored, because they are not
behaviour of gsfric: the file ``record-info.txt`` (gsfric's path, timings); log lines
matching IGNORED_LINES (the one-off "compiling the generated model" message of an empty
compiled-library cache); and in ``sweep.json`` the keys ``seconds`` (run time) and
``fingerprint`` (a hash of the trajectory files' absolute paths and mtimes, so it differs
between any two output folders). Everything else was bit-identical between two recordings.

Children run with OMP_NUM_THREADS=1 (and the BLAS equivalents), at most 2 at a time (--jobs);
a full record takes about 1.5-3.5 minutes on 2 cores (more when they are busy).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

GSFRIC = [sys.executable, "-c", "from gsfric.cli import main; main()"]
RTOL = 1e-12
TINY = 1e-300
IGNORED_FILES = {"record-info.txt"}
IGNORED_LINES = [re.compile(r"gsfric: compiling the generated model")]
IGNORED_KEYS = {"sweep.json": {"seconds", "fingerprint"}}   # top-level keys, by file name
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?|\bnan\b|\binf\b", re.I)

# ---------------------------------------------------------------------------------- inputs

MOTIONS_SNIPPET = """
import numpy as np
from gsfric import models, io
t = np.linspace(0.0, 10.0, 2001)
io.write_table(models.sinusoidal(t).to_frame(), 'inputs/motions/sinusoidal.csv')
io.write_table(models.point_to_point(np.random.default_rng(1), 2000).to_frame(),
               'inputs/motions/p2p.csv')
io.write_table(models.random_motion(np.random.default_rng(2), t, scale=1.2).to_frame(),
               'inputs/motions/random.csv')
io.write_table(models.paper_motion().to_frame(), 'inputs/motions/paper40.csv')
"""

DISTURB_SNIPPET = """
import sys
import numpy as np, pandas as pd
src, out, kind, seed = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
frame = pd.read_csv(src)
rng = np.random.default_rng(seed)
t = frame['t'].to_numpy()
if kind == 'interference':   # a 3.1 Hz interference of 1 N on load cell 3, random phase
    frame['F3'] += 1.0 * np.sin(2 * np.pi * 3.1 * t + rng.uniform(0.5, 2.5))
elif kind == 'crosstalk':    # load cell 3 also reads 3% (+-0.3%) of load cell 4's force
    frame['F3'] += rng.uniform(0.027, 0.033) * frame['F4']
elif kind == 'deadband':     # load cell 5 reads nothing within +-1.5 N of its offset
    f = frame['F5'].to_numpy()
    mid = np.median(f) + rng.normal(0, 0.1)
    frame['F5'] = np.where(np.abs(f - mid) < 1.5, mid, f - 1.5 * np.sign(f - mid))
frame.to_csv(out, index=False, float_format='%.17g')
"""

MODIFIED = {"platform": {"mass": "14", "payload_mass": "5"},
            "legs": {"lower_mass": "3.1", "upper_mass": "0.9", "lower_com": "0.24"},
            "friction": {"joint_radius": "0.08", "joint_coulomb": "0.06",
                         "prismatic_coulomb": "0.15", "prismatic_seal": "3"}}

LIMITS = """
[limits]
actuator_force = [-60.0, 110.0]
spherical_load = 145.0
universal_load = 100.0
universal_moment = 1.0
prismatic_load = 5.0
prismatic_moment = 5.0
"""

WORKSPACE = """sampling = "lhs"
samples = 60
states = 4
seed = 3
[pose]
x = [-0.05, 0.05]
y = [-0.05, 0.05]
z = [0.65, 0.75]
roll = [-0.1, 0.1]
pitch = [-0.1, 0.1]
yaw = [-0.15, 0.15]
[bounds]
velocity = 0.2
omega = 0.5
acceleration = 2.0
alpha = 5.0
"""

# (name, synth arguments, discover arguments, disturbance applied afterwards or None)
RECORDS = [
    ("null", [], [], None),
    ("stribeck", ["--effect", "stribeck:static=2,velocity=0.01"], [], None),
    ("seal", ["--effect", "seal_friction:force=1.5"], [], None),
    ("drag", ["--effect", "quadratic_drag:coefficient=30"], [], None),
    ("stroke", ["--effect", "stroke_friction:slope=8"], [], None),
    ("payload_offset", ["--effect", "payload_offset:x=0.03,z=0.02"], [], None),
    ("bias", ["--effect", "sensor_bias:b1=0.8,b4=-0.5"], [], None),
    ("gain", ["--effect", "force_scale:g2=0.02,g5=-0.015"], [], None),
    ("delay", ["--effect", "time_offset:delay=0.01"], [], None),
    ("pair_stribeck_bias", ["--effect", "stribeck:static=2", "--effect", "sensor_bias:b2=0.7"],
     [], None),
    ("seal_ar1_posenoise", ["--effect", "seal_friction:force=1", "--noise-correlation", "0.6",
                            "--pose-noise", "1e-5", "--rate", "250"], ["--seed", "7"], None),
    ("paper_joint_coupling", ["--platform", "inputs/platforms/reference_paper.toml",
                              "--effect", "joint_friction_coupling:scale=1"],
     ["--platform", "inputs/platforms/reference_paper.toml"], None),
    ("wrong_platform", ["--platform", "inputs/platforms/modified_coupled.toml"], [], None),
    ("null_seed2", [], [], None),
    ("outside_interference", [], [], "interference"),
    ("outside_deadband", ["--effect", "seal_friction:force=1"], [], "deadband"),
    ("outside_crosstalk", ["--effect", "stribeck:static=1.5"], [], "crosstalk"),
]


def set_keys(text: str, changes: dict[str, dict[str, str]]) -> str:
    """``key = value`` lines of a TOML text replaced per [section], comments kept."""
    lines, section, done = text.splitlines(keepends=True), None, set()
    for i, line in enumerate(lines):
        header = re.match(r"\s*\[([\w.]+)\]", line)
        if header:
            section = header.group(1)
            continue
        m = re.match(r"(\s*(\w+)\s*=\s*)([^#\n]*?)(\s*#.*)?(\n?)$", line)
        if m and m.group(2) in changes.get(section, {}):
            value = changes[section][m.group(2)]
            lines[i] = f"{m.group(1)}{value}{m.group(4) or ''}{m.group(5)}"
            done.add((section, m.group(2)))
    wanted = {(s, k) for s, keys in changes.items() for k in keys}
    if wanted - done:
        raise SystemExit(f"set_keys: not found in the TOML: {sorted(wanted - done)}")
    return "".join(lines)


def make_platforms(root: Path) -> None:
    """Six platform files: {reference, paper, modified} x {coupled, paper} friction."""
    folder = root / "inputs/platforms"
    template = (folder / "template.toml").read_text()
    paper = (root / "inputs/paper_run/platform.toml").read_text()
    bases = {"reference": template, "paper": paper, "modified": set_keys(template, MODIFIED)}
    for name, text in bases.items():
        for friction in ("coupled", "paper"):
            out = set_keys(text, {"friction": {"model": f'"{friction}"'}})
            (folder / f"{name}_{friction}.toml").write_text(out)
    (folder / "limits.toml").write_text(template + LIMITS)
    (folder / "workspace.toml").write_text(WORKSPACE)


def generate_inputs(root: Path, jobs: int) -> None:
    """OUT_DIR/inputs: platforms, trajectories and synthetic records, all seeded."""
    for sub in ("platforms", "motions", "records"):
        (root / "inputs" / sub).mkdir(parents=True, exist_ok=True)
    run(root, "inputs/platforms", GSFRIC + ["platform", "--template", "--out",
                                            "inputs/platforms/template.toml"])
    run(root, "inputs/paper_run", GSFRIC + ["paper", "--out", "inputs/paper_run", "--no-plots"])
    run(root, "inputs/motions", [sys.executable, "-c", MOTIONS_SNIPPET])
    make_platforms(root)
    tasks = []
    for k, (name, synth_args, _, disturbance) in enumerate(RECORDS):
        raw = f"inputs/records/{name}{'_raw' if disturbance else ''}.csv"
        cmds = [GSFRIC + ["synth", "--out", raw, "--samples", "3000", "--seed", str(100 + k)]
                + synth_args]
        if disturbance:
            cmds.append([sys.executable, "-c", DISTURB_SNIPPET, raw,
                         f"inputs/records/{name}.csv", disturbance, str(200 + k)])
        tasks.append((f"inputs/records/{name}", cmds))
    run_all(root, tasks, jobs)


# ----------------------------------------------------------------------------------- cases

def simulate_cases() -> list[tuple[str, list[list[str]]]]:
    cases = []
    for platform in ("reference", "paper", "modified"):
        for friction in ("coupled", "paper"):
            for motion in ("sinusoidal", "p2p", "random"):
                name = f"simulate/{platform}_{friction}_{motion}"
                args = ["--trajectory", f"inputs/motions/{motion}.csv", "--platform",
                        f"inputs/platforms/{platform}_{friction}.toml"]
                cases.append((name, args))
    cases += [
        ("simulate/default_sinusoidal", ["--trajectory", "inputs/motions/sinusoidal.csv"]),
        ("simulate/reference_coupled_sinusoidal_streamed",
         ["--trajectory", "inputs/motions/sinusoidal.csv", "--chunk", "600",
          "--platform", "inputs/platforms/reference_coupled.toml"]),
        ("simulate/measured_stribeck", ["--trajectory", "inputs/records/stribeck.csv"]),
    ]
    out = []
    for name, args in cases:
        breakdown = [] if "streamed" in name else ["--breakdown", f"{name}/breakdown.csv"]
        out.append((name, [GSFRIC + ["simulate", *args, "--columns", "all", "--out",
                                     f"{name}/result.parquet", *breakdown]]))
    for platform in ("paper_paper", "reference_coupled"):
        name = f"simulate/paper40_{platform}_modepaper"
        out.append((name, [GSFRIC + ["simulate", "--trajectory", "inputs/motions/paper40.csv",
                                     "--platform", f"inputs/platforms/{platform}.toml",
                                     "--mode", "paper", "--columns", "all",
                                     "--out", f"{name}/result.csv"]]))
    return out


def discover_cases() -> list[tuple[str, list[list[str]]]]:
    return [(f"discover/{name}",
             [GSFRIC + ["discover", "--measured", f"inputs/records/{name}.csv",
                        "--out", f"discover/{name}", *args]])
            for name, _, args, _ in RECORDS]


def sweep_cases() -> list[tuple[str, list[list[str]]]]:
    common = ["--platform", "inputs/platforms/limits.toml", "--scheduler", "serial",
              "--no-progress"]
    motions = ["--trajectories", "inputs/motions/sinusoidal.csv",
               "--trajectories", "inputs/motions/random.csv",
               "--vary", "platform.payload_mass=0:8", "--vary", "friction.joint_radius=0.03:0.07",
               "--variants", "4", "--seed", "5"]
    workspace = ["--workspace", "inputs/platforms/workspace.toml",
                 "--tolerance", "geometry.base_joints=0.0005", "--vary", "legs.lower_mass=2:3",
                 "--variants", "3", "--seed", "9"]
    return [(f"sweep/{name}", [GSFRIC + ["sweep", "--out", f"sweep/{name}", *common, *args]])
            for name, args in (("motions_vary", motions), ("workspace_tolerance", workspace))]


def paper_cases() -> list[tuple[str, list[list[str]]]]:
    runs = {"paper_mode": [], "kinematic_mode": ["--mode", "kinematic"],
            "reference_platform": ["--platform", "inputs/platforms/reference_coupled.toml"]}
    return [(f"paper/{name}", [GSFRIC + ["paper", "--out", f"paper/{name}", *args]])
            for name, args in runs.items()]


# ----------------------------------------------------------------------------------- running

def child_env() -> dict[str, str]:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONSAFEPATH="1", MPLBACKEND="Agg")
    env.pop("DASK_SCHEDULER_ADDRESS", None)
    return env


def show(cmd: list[str]) -> str:
    """The command as logged: gsfric's invocation shortened, a snippet named, not printed."""
    if cmd[:3] == GSFRIC:
        return "gsfric " + " ".join(cmd[3:])
    if cmd[:2] == [sys.executable, "-c"]:
        return "python -c <snippet> " + " ".join(cmd[3:])
    return " ".join(cmd)


def run(root: Path, case: str, *cmds: list[str]) -> float:
    """Run a case's commands in order from root, logged to logs/<case>.txt; raise on a failure.

    A simulate case's folder is made first (its outputs are files); the other commands make
    their output folders themselves (only the parent is made for them).
    """
    logs = "inputs/logs" if case.startswith("inputs/") else "logs"
    log_file = root / logs / f"{case.removeprefix('inputs/')}.txt"
    log_file.parent.mkdir(parents=True, exist_ok=True)
    (root / case).parent.mkdir(parents=True, exist_ok=True)
    if case.startswith("simulate/"):
        (root / case).mkdir(exist_ok=True)
    start, log = time.perf_counter(), []
    for cmd in cmds:
        proc = subprocess.run(cmd, cwd=root, env=child_env(), capture_output=True, text=True)
        log += [f"$ {show(cmd)}", f"exit code: {proc.returncode}", "--- stdout",
                proc.stdout.rstrip("\n"), "--- stderr", proc.stderr.rstrip("\n"), ""]
        if proc.returncode != 0:
            break
    log_file.write_text("\n".join(log) + "\n")
    if proc.returncode != 0:
        raise RuntimeError(f"{case}: exit code {proc.returncode}:\n{proc.stderr[-2000:]}")
    return time.perf_counter() - start


def run_all(root: Path, tasks: list[tuple[str, list[list[str]]]], jobs: int) -> dict:
    """Run the cases, ``jobs`` at a time; a line per case as it ends; their durations."""
    times, failures = {}, []
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {name: pool.submit(run, root, name, *cmds) for name, cmds in tasks}
        for name, future in futures.items():
            try:
                times[name] = future.result()
                print(f"  {times[name]:7.1f} s  {name}", flush=True)
            except RuntimeError as error:
                failures.append(str(error))
                print(f"  FAILED     {name}", flush=True)
    if failures:
        raise SystemExit("\n".join(failures))
    return times


def record(out: Path, inputs: Path | None, jobs: int) -> None:
    out = out.resolve()
    if out.exists():
        raise SystemExit(f"{out} exists; record into a new folder")
    out.mkdir(parents=True)
    probe = subprocess.run([sys.executable, "-c", "import gsfric; print(gsfric.__file__, "
                            "gsfric.__version__)"], cwd=out, env=child_env(),
                           capture_output=True, text=True, check=True).stdout.strip()
    print(f"gsfric: {probe}\nPYTHONPATH={os.environ.get('PYTHONPATH', '')}", flush=True)
    start = time.perf_counter()
    if inputs:
        shutil.copytree(inputs, out / "inputs")
        print(f"inputs copied from {inputs}")
    else:
        print("inputs:")
        generate_inputs(out, jobs)
    print("cases:")
    tasks = discover_cases() + sweep_cases() + simulate_cases() + paper_cases()
    times = run_all(out, tasks, jobs)
    total = time.perf_counter() - start
    (out / "record-info.txt").write_text(
        f"gsfric: {probe}\ninputs: {inputs or 'generated'}\ntotal: {total:.1f} s\n"
        + "".join(f"{t:8.1f} s  {name}\n" for name, t in times.items()))
    print(f"recorded {len(tasks)} cases into {out} in {total:.0f} s")


# ----------------------------------------------------------------------------------- compare

def relative(a: float, b: float) -> float:
    """|a-b| / max(|a|, |b|, tiny); 0 for equal values (NaN = NaN, inf = inf)."""
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b), TINY)


def compare_tables(a: pd.DataFrame, b: pd.DataFrame) -> tuple[float, str]:
    """Largest relative difference over the columns (inf: not comparable) and where."""
    if list(a.columns) != list(b.columns):
        return math.inf, f"columns differ: {sorted(set(a.columns) ^ set(b.columns)) or 'order'}"
    if len(a) != len(b):
        return math.inf, f"{len(a)} rows against {len(b)}"
    worst, where = 0.0, []
    for col in a.columns:
        x, y = a[col], b[col]
        if pd.api.types.is_numeric_dtype(x) and pd.api.types.is_numeric_dtype(y):
            x, y = x.to_numpy(np.float64), y.to_numpy(np.float64)
            if np.array_equal(x.view(np.uint64), y.view(np.uint64)):
                continue
            scale = np.maximum(np.maximum(np.abs(x), np.abs(y)), TINY)
            with np.errstate(invalid="ignore"):
                diff = np.abs(x - y) / scale
            same = (x == y) | (np.isnan(x) & np.isnan(y))
            diff = np.where(same, 0.0, np.where(np.isnan(diff), np.inf, diff))
            d = float(diff.max())
        else:
            d = 0.0 if x.astype(str).equals(y.astype(str)) else math.inf
        if d > 0:
            where.append(f"{col}: {d:.3g}")
        worst = max(worst, d)
    return worst, ", ".join(where[:8]) + (f" (+{len(where) - 8} columns)" if len(where) > 8 else "")


def compare_json(a, b, path: str = "$") -> tuple[float, str]:
    """Structural comparison; numbers by the relative rule, everything else equal."""
    number = (int, float)
    if isinstance(a, number) and isinstance(b, number) and not isinstance(a, bool) \
            and not isinstance(b, bool):
        d = relative(float(a), float(b))
        return d, (f"{path}: {a!r} vs {b!r}" if d else "")
    if type(a) is not type(b):
        return math.inf, f"{path}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, dict):
        if list(a) != list(b):
            return math.inf, f"{path}: keys differ: {sorted(set(a) ^ set(b)) or 'order'}"
        pairs = [(a[k], b[k], f"{path}.{k}") for k in a]
    elif isinstance(a, list):
        if len(a) != len(b):
            return math.inf, f"{path}: length {len(a)} vs {len(b)}"
        pairs = [(x, y, f"{path}[{i}]") for i, (x, y) in enumerate(zip(a, b))]
    else:
        return (0.0, "") if a == b else (math.inf, f"{path}: {a!r} vs {b!r}")
    worst, where = 0.0, ""
    for x, y, p in pairs:
        d, w = compare_json(x, y, p)
        if d > worst:
            worst, where = d, w
    return worst, where


def json_content(path: Path):
    """A JSON file's content without the keys IGNORED_KEYS names for its file name."""
    content = json.loads(path.read_text())
    if isinstance(content, dict):
        for key in IGNORED_KEYS.get(path.name, ()):
            content.pop(key, None)
    return content


def text_lines(path: Path) -> list[str]:
    lines = path.read_text(errors="replace").splitlines()
    return [line for line in lines if not any(p.search(line) for p in IGNORED_LINES)]


def compare_text(a: list[str], b: list[str]) -> tuple[float, str]:
    """Line by line: the text between numbers equal, the numbers by the relative rule."""
    if len(a) != len(b):
        return math.inf, f"{len(a)} lines against {len(b)}"
    worst, where = 0.0, ""
    for k, (x, y) in enumerate(zip(a, b), 1):
        if x == y:
            continue
        xs, ys = NUMBER.findall(x), NUMBER.findall(y)
        if NUMBER.split(x) != NUMBER.split(y) or len(xs) != len(ys):
            return math.inf, f"line {k}: {x.strip()[:80]!r} vs {y.strip()[:80]!r}"
        d = max(relative(float(p), float(q)) for p, q in zip(xs, ys))
        if d > worst:
            worst, where = d, f"line {k}: {d:.3g}"
    return worst, where


def compare_file(a: Path, b: Path) -> tuple[float, str]:
    """(largest relative difference, where) of two files of the same name."""
    if a.read_bytes() == b.read_bytes():
        return 0.0, ""
    suffix = a.suffix.lower()
    try:
        if suffix == ".csv":
            return compare_tables(*(pd.read_csv(p) for p in (a, b)))
        if suffix == ".parquet":
            return compare_tables(pd.read_parquet(a), pd.read_parquet(b))
        if suffix == ".json":
            return compare_json(*(json_content(p) for p in (a, b)))
        return compare_text(text_lines(a), text_lines(b))
    except Exception as error:   # unreadable: report it as a difference
        return math.inf, f"cannot compare: {type(error).__name__}: {error}"


def files(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")
            if p.is_file() and p.name not in IGNORED_FILES}


def compare(dir_a: Path, dir_b: Path) -> int:
    names_a, names_b = files(dir_a), files(dir_b)
    counts = {"identical": 0, "within": 0, "differing": 0, "png": 0}
    for name in sorted(names_a ^ names_b):
        print(f"DIFFER  {name}: only in {dir_a if name in names_a else dir_b}")
        counts["differing"] += 1
    for name in sorted(names_a & names_b):
        if name.lower().endswith(".png"):
            print(f"PNG     {name} (not compared)")
            counts["png"] += 1
            continue
        d, where = compare_file(dir_a / name, dir_b / name)
        if d == 0.0 and not where:
            counts["identical"] += 1
            continue
        kind = "within" if d <= RTOL else "differing"
        counts[kind] += 1
        label = "WITHIN " if kind == "within" else "DIFFER "
        print(f"{label} {name}: max relative difference {d:.3g} ({where})")
    compared = counts["identical"] + counts["within"] + counts["differing"]
    print(f"summary: {compared} files compared, {counts['identical']} bit-identical, "
          f"{counts['within']} within {RTOL:g}, {counts['differing']} differing "
          f"({counts['png']} PNG listed, not compared)")
    return 1 if counts["differing"] else 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="run every case, writing into OUT_DIR (must not exist)")
    rec.add_argument("out_dir", type=Path)
    rec.add_argument("--inputs", type=Path, help="reuse this inputs folder (copied into "
                     "OUT_DIR/inputs) instead of generating it: pass the base's when "
                     "recording after the restructure")
    rec.add_argument("--jobs", type=int, default=2, help="commands at a time [2]")
    cmp = sub.add_parser("compare", help="compare two recorded folders; exit 1 on a difference")
    cmp.add_argument("dir_a", type=Path)
    cmp.add_argument("dir_b", type=Path)
    args = parser.parse_args()
    if args.command == "record":
        record(args.out_dir, args.inputs, args.jobs)
    else:
        sys.exit(compare(args.dir_a, args.dir_b))


if __name__ == "__main__":
    main()

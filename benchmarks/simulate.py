"""``gsfric simulate`` end to end, Parquet to Parquet, timed in child processes.

``write_trajectory`` writes a long ``models.sinusoidal`` trajectory file; ``run_simulate`` runs
``gsfric simulate`` on it in a child process and reports its wall and CPU seconds and peak
resident set size (``benchmarks/memory_10M.py`` runs it at 10 million steps).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from benchmarks.cases import CHECKOUT, RATE
from gsfric import models
from gsfric._optional import optional

SIMULATE_STEPS = 1_000_000   # benchmarks/memory_10M.py runs the same at 10 million


def write_trajectory(path: Path, steps: int, group: int = 250_000) -> None:
    """A ``models.sinusoidal`` motion sampled every ``DT`` as a Parquet trajectory file
    (``t, x, y, z, qw, qx, qy, qz``), written in row groups of ``group`` rows."""
    pa, pq = optional("pyarrow"), optional("pyarrow.parquet")
    writer = None
    try:
        for start in range(0, steps, group):
            t = np.arange(start, min(steps, start + group)) / RATE
            motion = models.sinusoidal(t)
            q = motion.quaternion()
            table = pa.table({"t": t, "x": motion.position[:, 0], "y": motion.position[:, 1],
                              "z": motion.position[:, 2], "qw": q[:, 0], "qx": q[:, 1],
                              "qy": q[:, 2], "qz": q[:, 3]})
            if writer is None:
                writer = pq.ParquetWriter(path, table.schema)
            writer.write_table(table)
    finally:
        if writer is not None:
            writer.close()


def run_simulate(trajectory, out, chunk: int | None = None, threads: int | None = None,
                 extra: tuple[str, ...] = ()) -> dict:
    """Run ``gsfric simulate`` of ``trajectory`` to ``out`` in a child process (default chunk
    and threads unless given): its exit code, output, wall and CPU seconds (``cpu_s``, the sum
    of ``user_s`` and ``system_s``) and peak resident set size.

    ``peak_rss_mb`` is the child's own ``ru_maxrss`` (``os.wait4``); ``children_max_rss_mb`` is
    ``getrusage(RUSAGE_CHILDREN).ru_maxrss`` of this process afterwards, the largest of all its
    waited-for children. Run it from a small process: a child's peak RSS counts the copy of its
    parent's memory it starts as. ``benchmarks/memory_10M.py`` runs it at 10 million steps.
    """
    cmd = ["simulate", "--trajectory", str(trajectory), "--out", str(out), "--no-progress",
           *extra]
    if chunk is not None:
        cmd += ["--chunk", str(chunk)]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    run = run_gsfric(cmd)
    scale = 1 if sys.platform == "darwin" else 1024          # ru_maxrss: bytes or kB
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * scale
    return {**run, "children_max_rss_mb": children / 2**20}


_RUNNER = """
import json, os, subprocess, sys, time
start = time.perf_counter()
child = subprocess.Popen(sys.argv[2:])
_, status, usage = os.wait4(child.pid, 0)
with open(sys.argv[1], "w") as out:
    json.dump({"wall_s": time.perf_counter() - start, "status": status,
               "user_s": usage.ru_utime, "system_s": usage.ru_stime,
               "maxrss": usage.ru_maxrss}, out)
"""
"""Run by a small interpreter between the caller and the measured command: a child's peak RSS
counts the memory of the process it was forked from, which is then this one's (a few MB), not
the caller's (hundreds of MB by the end of a benchmark)."""


def run_gsfric(args: list[str]) -> dict:
    """``gsfric ARGS`` in a child process: its exit code (``returncode``), ``stdout`` and
    ``stderr``, wall and CPU seconds (``wall_s``; ``cpu_s``, the sum of ``user_s`` and
    ``system_s``) and its own peak resident set size (``peak_rss_mb``, ``os.wait4``, started
    from a small interpreter so that the caller's size does not count)."""
    cmd = [sys.executable, "-m", "gsfric.cli", *args]
    with tempfile.TemporaryDirectory(prefix="gsfric-bench-") as tmp, \
            tempfile.TemporaryFile("w+") as stdout, tempfile.TemporaryFile("w+") as stderr:
        usage_file = Path(tmp) / "usage.json"
        subprocess.run([sys.executable, "-I", "-c", _RUNNER, str(usage_file), *cmd],
                       stdout=stdout, stderr=stderr, text=True, check=False)
        stdout.seek(0)
        stderr.seek(0)
        out_text, err_text = stdout.read(), stderr.read()
        usage = json.loads(usage_file.read_text()) if usage_file.exists() else None
    if usage is None:
        return {"command": " ".join(["gsfric", *args]), "returncode": -1, "stdout": out_text,
                "stderr": err_text.strip(), "wall_s": float("nan"), "cpu_s": float("nan"),
                "user_s": float("nan"), "system_s": float("nan"), "peak_rss_mb": float("nan")}
    scale = 1 if sys.platform == "darwin" else 1024          # ru_maxrss: bytes or kB
    return {"command": " ".join(["gsfric", *args]),
            "returncode": os.waitstatus_to_exitcode(usage["status"]),
            "stdout": out_text.strip(), "stderr": err_text.strip(), "wall_s": usage["wall_s"],
            "cpu_s": usage["user_s"] + usage["system_s"], "user_s": usage["user_s"],
            "system_s": usage["system_s"], "peak_rss_mb": usage["maxrss"] * scale / 2**20}


def simulate_child(steps: int, trajectory: str, out: str) -> dict | None:
    """``run_simulate`` with the default columns and chunk: wall and CPU seconds, steps per
    second, peak RSS, the output's size; None when it failed."""
    run = run_simulate(trajectory, out, extra=("--quiet",))
    if run["returncode"] != 0:
        return None
    wall, cpu = run["wall_s"], run["cpu_s"]
    return {"steps": steps, "wall_s": wall, "cpu_s": cpu, "user_s": run["user_s"],
            "system_s": run["system_s"], "steps_per_s": steps / wall,
            "steps_per_cpu_s": steps / max(cpu, 1e-9),
            "peak_rss_gb": run["peak_rss_mb"] * 2**20 / 1e9,
            "output_gb": Path(out).stat().st_size / 1e9}


def simulate_case(steps: int, folder: Path) -> dict | None:
    """The trajectory written, then ``simulate_child`` run, each in a fresh process (this one
    is large by now); the files are removed."""
    trajectory, out = folder / "trajectory.parquet", folder / "forces.parquet"
    try:
        subprocess.run([sys.executable, "-c", "import sys; from pathlib import Path; "
                        "from benchmarks.simulate import write_trajectory; "
                        "write_trajectory(Path(sys.argv[1]), int(sys.argv[2]))",
                        str(trajectory), str(steps)], check=True, cwd=CHECKOUT)
        run = subprocess.run([sys.executable, "-c", "import json, sys; "
                              "from benchmarks.simulate import simulate_child; print(json.dumps("
                              "simulate_child(int(sys.argv[1]), sys.argv[2], sys.argv[3])))",
                              str(steps), str(trajectory), str(out)],
                             capture_output=True, text=True, cwd=CHECKOUT)
        if run.returncode != 0:
            return None
        return json.loads(run.stdout.strip().splitlines()[-1])
    finally:
        trajectory.unlink(missing_ok=True)
        out.unlink(missing_ok=True)

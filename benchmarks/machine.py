"""The machine a benchmark runs on: CPU, compiler, source version, load and free cores."""

from __future__ import annotations

import json
import os
import platform as _platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from gsfric.compiled import native
from gsfric.compiled.manifest import function, manifest
from gsfric.evaluation.parameters import model_function


def parallel_capacity(iterations: int = 3_000_000) -> float:
    """How many cores two CPU-bound processes get together: 2.0 with two idle cores.

    The wall time of one pure-Python loop alone, over that of two copies started together,
    times two. Other load on the machine lowers it; two-thread figures are bounded by it.
    """
    code = f"s = 0\nfor i in range({iterations}): s += i"

    def wall(copies: int) -> float:
        start = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(copies)]
        for proc in procs:
            proc.wait()
        return time.perf_counter() - start

    wall(1)
    return 2 * wall(1) / wall(2)


def describe_machine() -> dict:

    model = _platform.processor() or _platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass

    # the actuator map the reference platform runs (its friction model's, derive/build.py)
    simd = bool(function(model_function("actuator", "coupled")).get("simd", False))
    return {"cpu": model, "cores": os.cpu_count(), "python": _platform.python_version(),
            "numpy": np.__version__, "os": _platform.platform(),
            "build": native.chosen_build(),
            "actuator_entry": (f"SIMD over steps, {_lanes()} lanes" if simd
                               else "one step per call"),
            "source": _source_version(),
            "instructions": {f["name"].removeprefix("gsfric_model_"): f.get("n_instructions")
                             for f in manifest()["functions"]},
            "load_average_start": load_average()}


def _lanes() -> int:
    return native.lanes(native.library())


def _source_version() -> str | None:
    """``git describe`` of the source tree (``-dirty`` with uncommitted changes), if any."""
    try:
        run = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True,
                             text=True, cwd=Path(__file__).resolve().parent, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return run.stdout.strip() or None if run.returncode == 0 else None


def load_average() -> list[float] | None:
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return None


def publish(text: str, data: dict, out: str | Path | None) -> None:
    """Print a benchmark's table and, with ``out``, write its figures there as JSON."""
    print(text)
    if out is not None:
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(data, indent=2) + "\n")
        print(f"wrote {out}")

"""Latency of one step of the exported C library (``gsfric export``), measured in C.

For each friction model and build of the model (``--code``: specialised, generic), exports the
reference platform, builds the export with the system compiler (``CC``) and each set of flags
(the Makefile's, then ``-march=native``: the instructions of the machine it runs on), checks it
against ``Evaluator`` and prints the median time of one ``<prefix>_actuator_forces`` call (the
goal: at most 1 us for the coupled model), the worst relative error and, with valgrind, the
instructions one call executes (callgrind; repeatable on a loaded machine, unlike the time)::

    .venv/bin/python benchmarks/export_latency.py
    .venv/bin/python benchmarks/export_latency.py --rounds 100000 --no-callgrind
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from gsfric.export.verify import build, check_motions, compiler, verify_library, write_inputs
from gsfric.export.writer import CFLAGS, CODES, MODELS, export_library
from gsfric.models import reference_platform

FLAGS = {"Makefile": list(CFLAGS), "native": [*CFLAGS, "-march=native"]}
"""The sets of compiler flags timed."""
GROUP = 16
"""Calls per timed group of the driver (templates/verify.c.in)."""


def instructions_per_call(folder: Path, prefix: str, flags: list[str], work: Path) -> float:
    """Instructions of one ``<prefix>_actuator_forces`` call: callgrind's count of the check
    driver with 2000 timed rounds less that with 1000, per call (each run times
    ``rounds * 1.1`` groups of 16 calls)."""
    driver = build(folder, prefix, work, compiler(), flags)
    args = write_inputs(work, check_motions(reference_platform(), 50, 0))
    counts = []
    for rounds in (1000, 2000):
        run = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                              str(driver), *args, str(rounds)], cwd=work, capture_output=True,
                             text=True)
        found = re.search(r"Collected : (\d+)", run.stderr)
        if run.returncode or found is None:  # e.g. instructions valgrind does not know
            return float("nan")
        counts.append(int(found.group(1)))
    return (counts[1] - counts[0]) / (1000 * 1.1 * GROUP)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=50_000,
                        help="timed groups of 16 calls (the median is reported)")
    parser.add_argument("--no-callgrind", action="store_true",
                        help="do not count instructions (valgrind)")
    args = parser.parse_args()
    callgrind = not args.no_callgrind and shutil.which("valgrind") is not None
    with tempfile.TemporaryDirectory(prefix="gsfric-export-latency-") as tmp:
        for model in MODELS:
            for code in CODES:
                folder = Path(tmp) / f"{model}-{code}"
                prefix = f"bench_{model}"
                export_library(reference_platform(), folder, model=model, prefix=prefix,
                               code=code)
                for name, flags in FLAGS.items():
                    report = verify_library(folder, n_random=500, rounds=args.rounds,
                                            flags=flags)
                    line = (f"{model:8s} {code:12s} {name:9s} median {report.latency_ns:6.0f} ns"
                            f" per call, worst relative error {report.worst_error:.1e}")
                    if callgrind:
                        work = Path(tmp) / f"work-{model}-{code}-{name}"
                        work.mkdir()
                        ir = instructions_per_call(folder, prefix, flags, work)
                        line += (f", {ir:6.0f} instructions per call" if math.isfinite(ir)
                                 else ", instructions not counted (valgrind failed)")
                    print(f"{line}  ({report.compiler})", flush=True)


if __name__ == "__main__":
    main()

"""Latency of one step of the exported C library (``gsfric export``), measured in C.

Exports the reference platform with each friction model, builds the export with the system
compiler (``CC``) and the flags of its Makefile, checks it against ``Evaluator`` and prints
the median time of one ``<prefix>_actuator_forces`` call (the goal: at most 1 us for the
coupled model) and the worst relative error::

    .venv/bin/python benchmarks/export_latency.py
    .venv/bin/python benchmarks/export_latency.py --rounds 100000
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from gsfric.export.verify import verify_library
from gsfric.export.writer import MODELS, export_library
from gsfric.models import reference_platform


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=50_000,
                        help="timed groups of 16 calls (the median is reported)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="gsfric-export-latency-") as tmp:
        for model in MODELS:
            folder = Path(tmp) / model
            export_library(reference_platform(), folder, model=model, prefix=f"bench_{model}")
            report = verify_library(folder, n_random=500, rounds=args.rounds)
            print(f"{model:8s} median {report.latency_ns:7.0f} ns per call "
                  f"(worst relative error {report.worst_error:.1e}; {report.compiler})")


if __name__ == "__main__":
    main()

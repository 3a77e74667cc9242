"""Throughput of the compiled combined map against vectorised NumPy and a per-step loop.

Usage::

    python benchmarks/bench_throughput.py [--quick] [--out results.json]

The same as ``gsfric bench``; see ``gsfric.bench`` for what is measured and how.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from gsfric.bench.throughput import run_bench


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only N = 40 and 1e3")
    parser.add_argument("--out", type=Path, help="also write the report as JSON")
    args = parser.parse_args(argv)
    run_bench(quick=args.quick, out=args.out)


if __name__ == "__main__":
    main()

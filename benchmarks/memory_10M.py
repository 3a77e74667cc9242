"""Peak memory and time of `gsfric simulate` on a 10-million-step trajectory.

Writes a long Parquet trajectory (a smooth 6-DoF motion sampled at 1 kHz, quaternion
orientation, written row group by row group, in a child process), then runs
``gsfric simulate`` on it in a subprocess and reports that child's peak resident set size
(``ru_maxrss``, from ``os.wait4``; ``resource.getrusage(RUSAGE_CHILDREN).ru_maxrss`` is printed
too), the wall time and the user and system CPU time::

    .venv/bin/python benchmarks/memory_10M.py                       # 10M steps, chunk 100000
    .venv/bin/python benchmarks/memory_10M.py --steps 200000 --chunk 5000

The figures of a run are in docs/explanation/performance.md (``simulate``) and docs/explanation/robustness.md. Not
part of the test suite (it takes minutes and several GB of disk); tests/test_robustness.py
runs the same functions on 200k steps.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks import simulate  # noqa: E402
from gsfric._optional import optional  # noqa: E402

ROWS_PER_GROUP = 250_000


def write_trajectory(path: Path, steps: int, rows_per_group: int = ROWS_PER_GROUP) -> None:
    """A ``models.sinusoidal`` motion of ``steps`` samples at 1 kHz as a Parquet trajectory
    file (``t, x, y, z, qw, qx, qy, qz``), in row groups of ``rows_per_group``: the file of
    ``gsfric bench``'s simulate case."""
    simulate.write_trajectory(path, steps, group=rows_per_group)


def run_simulate(trajectory: Path, out: Path, chunk: int, threads: int = 1,
                 extra: tuple[str, ...] = ()) -> dict:
    """``gsfric simulate`` in a subprocess (``benchmarks.simulate.run_simulate``, the runner of
    ``gsfric bench``'s simulate case): exit code, output, wall and CPU time, peak RSS."""
    return simulate.run_simulate(trajectory, out, chunk=chunk, threads=threads, extra=extra)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000_000)
    parser.add_argument("--chunk", type=int, default=100_000)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--dir", type=Path, default=None,
                        help="Working directory (default: a temporary one, removed after).")
    parser.add_argument("--keep", action="store_true", help="Keep the files.")
    parser.add_argument("--json", type=Path, help="Also write the figures as JSON.")
    parser.add_argument("--columns", default=None,
                        help="simulate's --columns (default: its default columns).")
    parser.add_argument("--generate", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.generate:
        write_trajectory(args.generate, args.steps)
        return 0

    folder = args.dir or Path(tempfile.mkdtemp(prefix="gsfric-mem-"))
    folder.mkdir(parents=True, exist_ok=True)
    trajectory = folder / f"trajectory_{args.steps}.parquet"
    out = folder / f"forces_{args.steps}.parquet"
    try:
        start = time.perf_counter()
        if not trajectory.exists():
            # in a child process: this process stays small, so that the simulate child (whose
            # RSS starts as a copy of this one's when forked) is measured alone
            subprocess.run([sys.executable, __file__, "--generate", str(trajectory),
                            "--steps", str(args.steps)], check=True)
        written = time.perf_counter() - start
        extra = () if args.columns is None else ("--columns", args.columns)
        figures = run_simulate(trajectory, out, args.chunk, args.threads, extra)
        if figures["returncode"] != 0:
            print(figures["stderr"], file=sys.stderr)
            return 1
        rows = optional("pyarrow.parquet").ParquetFile(out).metadata.num_rows
        figures.update(steps=args.steps, chunk=args.chunk, threads=args.threads,
                       rows_written=rows, trajectory_mb=trajectory.stat().st_size / 2**20,
                       output_mb=out.stat().st_size / 2**20, generate_s=written,
                       steps_per_s=args.steps / figures["wall_s"],
                       steps_per_cpu_s=args.steps / max(figures["cpu_s"], 1e-9),
                       cpus=os.cpu_count())
        for key in ("command", "steps", "chunk", "threads", "rows_written", "peak_rss_mb",
                    "children_max_rss_mb", "wall_s", "cpu_s", "user_s", "system_s",
                    "steps_per_s", "steps_per_cpu_s", "trajectory_mb",
                    "output_mb", "cpus"):
            value = figures[key]
            print(f"{key:20s} {value:.1f}" if isinstance(value, float) else f"{key:20s} {value}")
        if args.json:
            args.json.write_text(json.dumps(figures, indent=2))
        return 0 if rows == args.steps else 1
    finally:
        if not args.keep and args.dir is None:
            for path in (trajectory, out):
                path.unlink(missing_ok=True)
            folder.rmdir()


if __name__ == "__main__":
    sys.exit(main())

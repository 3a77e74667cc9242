"""No result changes: this checkout's command-line outputs against a base's, bit for bit or
within 1e-12 relative (``goldens.py``'s comparison).

Record the base once, from a checkout of the base commit (it generates the inputs)::

    PYTHONPATH=../base .venv/bin/python benchmarks/goldens.py record ../goldens/base

then, after any change, on this checkout::

    PYTHONPATH=. .venv/bin/python benchmarks/compare_outputs.py ../goldens/base

It records every case of ``goldens.py`` (simulate on three platforms, two friction models and
three motions and the extras, discover on 17 seeded records, sweeps, paper tables) with the
base's inputs into ``--out`` (default: a temporary folder, removed afterwards unless there was
a difference), compares it with the base and exits 1 on a difference, printing one line per
file that differs. Discovery outputs compare with the base commit only: a later commit that
changes verdicts on purpose gives differences there.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from goldens import compare, record  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("base", type=Path, help="goldens recorded from the base commit")
    parser.add_argument("--out", type=Path, help="where to record this checkout's outputs "
                        "(must not exist; default: a temporary folder)")
    parser.add_argument("--jobs", type=int, default=2, help="commands at a time [2]")
    args = parser.parse_args()
    inputs = args.base / "inputs"
    if not inputs.is_dir():
        parser.error(f"{args.base}: no inputs folder; record the base with goldens.py first")
    temporary = args.out is None
    out = Path(tempfile.mkdtemp(prefix="gsfric-compare-")) / "after" if temporary else args.out
    record(out, inputs, args.jobs)
    status = compare(args.base, out)
    if temporary and status == 0:
        shutil.rmtree(out.parent)
    elif temporary:
        print(f"this checkout's outputs kept in {out}")
    sys.exit(status)


if __name__ == "__main__":
    main()

"""Fault cases of reading controller and data-acquisition logs: time gaps and dropouts,
counter resets and wraps, the unit of the sampling rate, repeated keys, contradictory pose
columns, implausible units of forces and speeds, mostly unusable data before any physics.

This is the place for those cases: add them to ``log_cases`` as ``Case`` rows (the makers of
``makers.py`` build the files); ``test_fault_table.py`` collects them with the others.
"""

from __future__ import annotations

from makers import csv_edit
from runner import ERROR, Case


def _gap(lines):
    header = lines[0].split(",")
    k = header.index("t")
    out = [lines[0]]
    for n, line in enumerate(lines[1:], 1):
        cells = line.split(",")
        if n > 50:
            cells[k] = repr(float(cells[k]) + 5.0)
        out.append(",".join(cells))
    return out



def log_cases() -> list[Case]:
    return [
        Case(id="log-discover-t-gap", expect=ERROR, code=2,
             argv=("discover", "--measured", "{data}", "--out", "{tmp}/dd", "--quiet"),
             message=r"t: dropout of about 500 samples .* first after row 50",
             files={"data": csv_edit("t.csv", _gap)}, absent=("dd",)),
    ]

"""Fault cases of reading controller and data-acquisition logs: time gaps and dropouts,
counter resets and wraps, the unit of the sampling rate, repeated keys, contradictory pose
columns, implausible units of forces and speeds, mostly unusable data before any physics.

This is the place for those cases: add them to ``log_cases`` as ``Case`` rows (the makers of
``makers.py`` build the files); ``test_fault_table.py`` collects them with the others.
"""

from __future__ import annotations

import numpy as np
from makers import cell, content, csv_edit, frame_edit, trajectory
from runner import ERROR, OK, WARN, Case


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



def _at_rest(frame, travel: float = 0.0):
    """The base frame held at its first pose (plus a drift of ``travel`` m along x)."""
    for name in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        frame[name] = frame[name].iloc[0]
    frame["x"] = frame["x"] + np.linspace(0.0, travel, len(frame))
    return frame


def _noise_cases() -> list[Case]:
    """The load cells' noise, by class: a value implausible against the measured forces'
    spread from every source (the option, the column map, a noise record in other units),
    and noise records that move."""
    argv = ("discover", "--measured", "{data}", "--out", "{tmp}/dd", "--quiet")
    spread = r"implausible against the measured channel's spread"
    scaled = frame_edit("n.csv", lambda f: _at_rest(f).assign(
        **{f"F{i}": f[f"F{i}"] * 1e3 for i in range(1, 7)}))
    cases = [Case(id=f"log-discover-force-noise-{value}", expect=ERROR, code=2,
                  argv=(*argv, "--force-noise", value),
                  message=rf"^--force-noise: F\d: .*{spread}",
                  files={"data": csv_edit("t.csv", lambda lines: lines)}, absent=("dd",))
             for value in ("1e9", "1e-300", "0.1,0.1,0.1,0.1,0.1,1e12")]
    cases += [
        Case(id="log-discover-force-noise-column-map", expect=ERROR, code=2,
             argv=(*argv, "--column-map", "{map}"), message=rf"force_noise .*{spread}",
             files={"data": csv_edit("t.csv", lambda lines: lines),
                    "map": content("map.toml", 'force_noise = 1e9\n[columns]\nt = "t"\n')},
             absent=("dd",)),
        Case(id="log-discover-noise-record-in-mn", expect=ERROR, code=2,
             argv=(*argv, "--noise-record", "{noise}"), message=rf"n\.csv: F\d: .*{spread}",
             files={"data": csv_edit("t.csv", lambda lines: lines), "noise": scaled},
             absent=("dd",)),
        Case(id="log-discover-noise-record-moves", expect=ERROR, code=2,
             argv=(*argv, "--noise-record", "{noise}"),
             message=r"n\.csv: not at rest: the platform moves 0\.0\d+ m and turns .* rad "
                     r"from its first sample \(a noise record must stay within 0\.001 m",
             files={"data": csv_edit("t.csv", lambda lines: lines),
                    "noise": frame_edit("n.csv", lambda f: f)}, absent=("dd",)),
        Case(id="log-discover-noise-record-drifts", expect=ERROR, code=2,
             argv=(*argv, "--noise-record", "{noise}"), message=r"n\.csv: not at rest",
             files={"data": csv_edit("t.csv", lambda lines: lines),
                    "noise": frame_edit("n.csv", lambda f: _at_rest(f, 0.01))},
             absent=("dd",)),
    ]
    return cases


def _zero_quaternion(lines):
    for column in ("qw", "qx", "qy", "qz"):
        lines = cell(51, column, "0")(lines)
    return lines


POSE_READINGS = [
    ("x-inf", cell(51, "x", "inf"), r"row 51: column 'x' is infinite"),
    ("x-1e200", cell(51, "x", "1e200"),
     r"row 51: column 'x' = 1e\+200 .*farther than 100 m from the origin"),
    ("qw-minus-inf", cell(51, "qw", "-inf"), r"row 51: column 'qw' is infinite"),
    ("quaternion-zero", _zero_quaternion, r"row 51: quaternion of zero length"),
]
"""One pose reading no rig can have (a glitch of the log): an error naming the row and the
column, from every command that reads a log's poses (``LOG_READERS``)."""

LOG_READERS = {
    "log-inspect": ("log", "inspect", "{data}", "--out", "{tmp}/o"),
    "simulate": ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv", "--no-progress"),
}


def _pose_cases() -> list[Case]:
    cases = [Case(id=f"log-{command}-pose-{fault}", argv=argv, expect=ERROR, code=2,
                  message=message, files={"data": csv_edit("t.csv", edit)},
                  absent=("o", "o.csv"))
             for fault, edit, message in POSE_READINGS if fault != "x-1e200"
             for command, argv in LOG_READERS.items()]
    cases.append(Case(id="log-log-inspect-pose-x-1e200", argv=LOG_READERS["log-inspect"],
                      expect=ERROR, code=2, message=POSE_READINGS[1][2],
                      files={"data": csv_edit("t.csv", POSE_READINGS[1][1])}, absent=("o",)))
    # a quaternion of length 1e200 is a direction, normalised without overflow: one flip
    cases += [Case(id=f"log-{command}-pose-quaternion-1e200", argv=argv, expect=expect,
                   message=message, files={"data": csv_edit("t.csv", cell(51, "qx", "1e200"))})
              for command, argv, expect, message in (
                  ("log-inspect", LOG_READERS["log-inspect"], OK, ""),
                  ("simulate", LOG_READERS["simulate"], WARN, r"1 of 100 steps flagged"))]
    return cases


MEASURED_READERS = {
    "simulate": ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv", "--no-progress"),
    "view": ("view", "--measured", "{data}", "--out", "{tmp}/o.html"),
    "view-trajectory": ("view", "--trajectory", "{data}", "--out", "{tmp}/o.html"),
}
"""The commands that read a measured-data file's forces F1..F6 and evaluate it: each checks
the forces' unit against the platform's weight before any physics."""


def _measured_force_cases() -> list[Case]:
    scaled = {"kn-as-n": (1e3, r"forces in N declared as kN"),
              "one-1e200": (None, r"their load .* 1e\+198 N")}
    cases = []
    for fault, (factor, message) in scaled.items():
        edit = (frame_edit("t.csv", lambda f, k=factor: f.assign(
            **{f"F{i}": f[f"F{i}"] * k for i in range(1, 7)})) if factor else
            csv_edit("t.csv", cell(31, "F3", "1e200")))
        cases += [Case(id=f"log-{command}-forces-{fault}", argv=argv, expect=ERROR, code=2,
                       message=rf"t\.csv: forces: .*{message}", files={"data": edit},
                       absent=("o.csv", "o.html"))
                  for command, argv in MEASURED_READERS.items()]
    return cases


def log_cases() -> list[Case]:
    dialects = [Case(id=f"log-log-inspect-{name}", argv=LOG_READERS["log-inspect"],
                     expect=ERROR, code=2, message=rf"t\.csv: the header .* separated by {name}",
                     files={"data": csv_edit("t.csv", lambda ls, m=mark: [
                         x.replace(",", m) for x in ls])}, absent=("o",))
                for name, mark in (("semicolons", ";"), ("tabs", "\t"))]  # as TABLE_FAULTS
    not_a_time = [Case(id=f"log-log-inspect-time-is-{column}",
                       argv=(*LOG_READERS["log-inspect"], "--time", column), expect=ERROR,
                       code=2, message=rf"t\.csv: (row \d+: )?column '{column}'",
                       files={"data": trajectory()}, absent=("o",))
                  for column in ("F1", "x", "qw")]        # a force, a position, a quaternion
    return [*_noise_cases(), *_pose_cases(), *_measured_force_cases(), *dialects, *not_a_time,
        Case(id="log-discover-t-gap", expect=ERROR, code=2,
             argv=("discover", "--measured", "{data}", "--out", "{tmp}/dd", "--quiet"),
             message=r"t: dropout of about 500 samples .* first after row 50",
             files={"data": csv_edit("t.csv", _gap)}, absent=("dd",)),
    ]

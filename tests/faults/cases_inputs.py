"""Fault cases of the input files: trajectory and measured-data tables (simulate, sweep,
discover) and platform files (every command that reads one)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from makers import (
    base_csv,
    base_frame,
    cell,
    column_map,
    content,
    csv_edit,
    folder,
    frame_edit,
    missing,
    platform,
    rig,
    set_key,
    symlink,
    trajectory,
)
from runner import ERROR, OK, WARN, Case

# -- trajectory and measured-data tables --------------------------------------------------------


def _drop(column: str):
    return lambda f: f.drop(columns=[column])


def _rows(n: int):
    return lambda lines: lines[:n + 1]


def _scale(columns, factor: float):
    def edit(f):
        f[list(columns)] = f[list(columns)] * factor
        return f
    return edit


def _euler_degrees(f: pd.DataFrame) -> pd.DataFrame:
    f = f.drop(columns=["qw", "qx", "qy", "qz"])
    f["alpha"] = np.degrees(0.1 * np.sin(f["t"]))
    f["beta"] = np.degrees(0.2 + 0.05 * np.cos(f["t"]))
    f["gamma"] = np.degrees(-0.1 * np.sin(f["t"]))
    return f


def _ns_time(f: pd.DataFrame) -> pd.DataFrame:
    f["t"] = (f["t"] * 1e9).round().astype(np.int64)
    return f


def _truncated_parquet(folder_path):
    path = frame_edit("t.parquet", lambda f: f)(folder_path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    return path


def _swap_rows(a: int, b: int):
    def edit(lines):
        lines = list(lines)
        lines[a], lines[b] = lines[b], lines[a]
        return lines
    return edit


TABLE_FAULTS = [
    # (id, maker, expect, code, message)
    ("missing", missing("t.csv"), ERROR, 2, r"t\.csv'?:? .*(not found|not exist|matches no)"),
    ("directory", folder("t.csv"), ERROR, 2, r"t\.csv'?:? .*(directory|matches no)"),
    ("empty", content("t.csv", ""), ERROR, 2, r"t\.csv"),
    ("header-only", csv_edit("t.csv", _rows(0)), ERROR, 2, r"t\.csv"),
    ("one-row", csv_edit("t.csv", _rows(1)), ERROR, 2, r"t\.csv"),
    ("two-rows", csv_edit("t.csv", _rows(2)), ERROR, 2, r"t\.csv"),
    ("binary", content("t.csv", bytes(range(256)) * 8), ERROR, 2, r"t\.csv"),
    ("not-utf8", content("t.csv", lambda: base_csv().encode() + b"\xff\xfe,\x80\n"), ERROR, 2,
     r"t\.csv"),
    ("no-x", frame_edit("t.csv", _drop("x")), ERROR, 2, r"t\.csv.*'?x'?"),
    ("no-t", frame_edit("t.csv", _drop("t")), ERROR, 2, r"t\.csv.*'?t'?"),
    ("nan-cell", csv_edit("t.csv", cell(5, "x", "nan")), ERROR, 2, r"t\.csv.*row 5"),
    ("inf-cell", csv_edit("t.csv", cell(5, "y", "inf")), ERROR, 2, r"t\.csv.*row 5"),
    ("empty-cell", csv_edit("t.csv", cell(7, "z", "")), ERROR, 2, r"t\.csv.*row 7"),
    ("text-cell", csv_edit("t.csv", cell(9, "x", "abc")), ERROR, 2, r"t\.csv.*row 9"),
    ("huge-cell", csv_edit("t.csv", cell(9, "x", "1e999")), ERROR, 2, r"t\.csv.*row 9"),
    ("t-repeated", csv_edit("t.csv", cell(6, "t", "0.04")), ERROR, 2, r"t\.csv.*row [56]"),
    ("t-backwards", csv_edit("t.csv", _swap_rows(10, 11)), ERROR, 2, r"t\.csv.*row 1[01]"),
    ("zero-quaternion", csv_edit("t.csv", lambda ls: cell(4, "qz", "0")(cell(4, "qy", "0")(
        cell(4, "qx", "0")(cell(4, "qw", "0")(ls))))), ERROR, 2, r"t\.csv.*row 4"),
    ("semicolons", csv_edit("t.csv", lambda ls: [x.replace(",", ";") for x in ls]), ERROR, 2,
     r"t\.csv: the header 't;x;.* is one column separated by semicolons"),
    ("tabs", csv_edit("t.csv", lambda ls: [x.replace(",", "\t") for x in ls]), ERROR, 2,
     r"t\.csv: the header .* is one column separated by tabs"),
    ("duplicate-column", csv_edit("t.csv", lambda ls: [x + "," + x.split(",")[1]
                                                       for x in ls[:1]] + [
        x + "," + x.split(",")[1] for x in ls[1:]]), ERROR, 2, r"t\.csv"),
    ("dangling-link", symlink("t.csv", "gone.csv"), ERROR, 2, r"t\.csv"),
    ("parquet-garbage", content("t.parquet", b"PAR1" + bytes(300) + b"PAR1"), ERROR, 2,
     r"t\.parquet"),
    ("parquet-truncated", _truncated_parquet, ERROR, 2, r"t\.parquet"),
    ("unknown-extension", content("t.xyz", base_csv), ERROR, 2, r"t\.xyz"),
    ("crlf", csv_edit("t.csv", lambda ls: ls, newline="\r\n"), OK, 0, ""),
    ("trailing-blank-lines", csv_edit("t.csv", lambda ls: ls + ["", ""]), OK, 0, ""),
    ("parquet", trajectory("t.parquet"), OK, 0, ""),
    ("extra-column", frame_edit("t.csv", lambda f: f.assign(note=1.0)), WARN, 0,
     r"t\.csv: 1 column ignored"),
    ("negative-start", frame_edit("t.csv", lambda f: f.assign(t=f["t"] - 10.0)), OK, 0, ""),
    ("time-in-ns", frame_edit("t.csv", _ns_time), ERROR, 2, r"t\.csv: time column 't'.*looks like ns"),
    ("euler-in-degrees", frame_edit("t.csv", _euler_degrees), ERROR, 2,
     r"t\.csv: \d+ of 100 steps have a leg outside the stroke"),
    ("positions-in-mm", frame_edit("t.csv", _scale("xyz", 1000.0)), ERROR, 2,
     r"t\.csv: 100 of 100 steps have a leg outside the stroke.*look like mm"),
]
"""Faults of a table file: each becomes a case of every command that reads one."""

TABLE_COMMANDS = {
    "simulate": ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv", "--no-progress"),
    "sweep": ("sweep", "--trajectories", "{data}", "--out", "{tmp}/sw", "--no-plots",
              "--no-progress", "--scheduler", "serial"),
    "discover": ("discover", "--measured", "{data}", "--out", "{tmp}/dd", "--quiet"),
}
"""The commands reading a table, with ``{data}`` the faulty file; outputs absent on error."""

SWEEP_KEEPS = {
    "euler-in-degrees": (WARN, 0, r"degree"),
    "positions-in-mm": (WARN, 0, r"mm|flagged|no load envelope"),
}
"""Faults that ``sweep`` reads with a warning where the other commands stop: a sweep checks its
motions against the platform's stroke step by step (flagged steps leave the envelope) instead
of refusing a motion that is mostly outside it."""

TOO_SHORT_FOR_DISCOVER = r"samples.*needs at least"
"""What ``discover`` says about the 100 rows of a table it could read: too short for its
block cross-validation (a correct one-line error, before any physics)."""


def table_cases() -> list[Case]:
    cases = []
    for fault, maker, expect, code, message in TABLE_FAULTS:
        for command, argv in TABLE_COMMANDS.items():
            if command == "sweep" and fault in ("unknown-extension",):
                message_here = r"t\.xyz|no (trajectory|file)"
            else:
                message_here = message
            if command == "sweep" and fault in SWEEP_KEEPS:
                expect_here, code_here, message_here = SWEEP_KEEPS[fault]
            elif command == "discover" and expect != ERROR:
                expect_here, code_here, message_here = ERROR, 2, TOO_SHORT_FOR_DISCOVER
            else:
                expect_here, code_here = expect, code
            out = {"simulate": "o.csv", "sweep": "sw", "discover": "dd"}[command]
            cases.append(Case(
                id=f"table-{command}-{fault}", argv=argv, expect=expect_here, code=code_here,
                message=message_here, files={"data": maker},
                absent=(out,) if expect_here == ERROR else (),
                check=None if expect_here == ERROR else _output_exists(out)))
    return cases


def _output_exists(name: str):
    def check(paths):
        assert (paths["tmp"] / name).exists()
    return check


# -- platform files -----------------------------------------------------------------------------

PLATFORM_FAULTS = [
    ("missing", missing("p.toml"), r"p\.toml'?\.?:? .*(not found|not exist|no such file)"),
    ("directory", folder("p.toml"), r"p\.toml'?:? .*directory"),
    ("empty", content("p.toml", ""), r"p\.toml: .*geometry"),
    ("binary", content("p.toml", bytes(range(256))), r"p\.toml"),
    ("syntax", platform(edit=lambda t: t.replace("gravity = 9.81", "gravity = = 9.81")),
     r"p\.toml"),
    ("repeated-key", platform(edit=lambda t: "gravity = 9.81\n" + t), r"p\.toml"),
    ("unknown-key", platform(edit=lambda t: "gravitee = 9.81\n" + t), r"p\.toml: gravitee"),
    ("gravity-nan", platform(edit=set_key("gravity", "nan")), r"p\.toml: gravity: .*finite"),
    ("gravity-inf", platform(edit=set_key("gravity", "inf")), r"p\.toml: gravity: .*finite"),
    ("gravity-2^70", platform(edit=set_key("gravity", str(2**70))),
     r"p\.toml: gravity: integer too large"),
    ("gravity-1e308", platform(edit=set_key("gravity", "1e308")),
     r"p\.toml: gravity: .*valid range 0 to 100"),
    ("gravity-negative", platform(edit=set_key("gravity", "-9.81")), r"p\.toml: gravity: .*>= 0"),
    ("gravity-text", platform(edit=set_key("gravity", '"9.81"')), r"p\.toml: gravity: .*number"),
    ("mass-negative", platform(edit=set_key("mass", "-10.0")), r"p\.toml: platform\.mass"),
    ("mass-2^70", platform(edit=set_key("mass", str(2**70))),
     r"p\.toml: platform\.mass: integer too large"),
    ("mass-nan", platform(edit=set_key("mass", "nan")), r"p\.toml: platform\.mass: .*finite"),
    ("payload-inf", platform(edit=set_key("payload_mass", "-inf")),
     r"p\.toml: platform\.payload_mass"),
    ("lower-mass-array", platform(edit=set_key("lower_mass", "[1, 2]")),
     r"p\.toml: legs\.lower_mass"),
    ("not-utf8", content("p.toml", lambda: b"\xff\xfe" + b"gravity = 9.81\n"), r"p\.toml"),
]
"""Faults of a platform file: each becomes a case of every command that reads one; all are
one-line errors (exit 2) naming the file and the key."""

PLATFORM_COMMANDS = {
    "simulate": ("simulate", "--trajectory", "{data}", "--platform", "{p}", "--out",
                 "{tmp}/o.csv", "--no-progress"),
    "synth": ("synth", "--platform", "{p}", "--out", "{tmp}/o.csv", "--samples", "50"),
    "paper": ("paper", "--platform", "{p}", "--out", "{tmp}/o", "--no-plots"),
    "sweep": ("sweep", "--trajectories", "{data}", "--platform", "{p}", "--out", "{tmp}/o",
              "--no-plots", "--no-progress", "--scheduler", "serial"),
    "export": ("export", "--platform", "{p}", "--out", "{tmp}/o"),
    "discover": ("discover", "--measured", "{data}", "--platform", "{p}", "--out", "{tmp}/o",
                 "--quiet"),
    "identify": ("identify", "--measured", "{data}", "--platform", "{p}", "--out", "{tmp}/o"),
    "excite": ("excite", "--platform", "{p}", "--out", "{tmp}/o.csv", "--duration", "4"),
}


def platform_cases() -> list[Case]:
    cases = []
    for fault, maker, message in PLATFORM_FAULTS:
        for command, argv in PLATFORM_COMMANDS.items():
            cases.append(Case(id=f"platform-{command}-{fault}", argv=argv, expect=ERROR,
                              code=2, message=message, absent=("o", "o.csv"),
                              files={"data": trajectory(), "p": maker}))
    return cases


def _rig_with(line: str):
    """The base rig file (``makers.rig``) with ``line`` added, or replacing the line of its
    key when the file has one."""
    def make(folder):
        path = rig()(folder)
        key = line.split("=")[0].strip()
        lines = [x for x in path.read_text().splitlines() if x.split("=")[0].strip() != key]
        path.write_text("\n".join([*lines, line]) + "\n")
        return path
    return make


RIG_FAULTS = [
    ("inertia-negative", "platform_inertia = [-0.2, 0.2, 0.4]", ERROR,
     r"r\.toml: platform_inertia\[0\]: must be >= 0"),
    ("inertia-nan", "lower_inertia = [0.05, nan, 0.001]", ERROR,
     r"r\.toml: lower_inertia\[1\]: must be finite"),
    ("inertia-inf", "upper_inertia = [0.01, 0.01, inf]", ERROR,
     r"r\.toml: upper_inertia\[2\]: must be finite"),
    ("inertia-two", "platform_inertia = [0.2, 0.4]", ERROR,
     r"r\.toml: platform_inertia: expected the three principal moments"),
    ("inertia-matrix", "platform_inertia = [[0.2, 0, 0], [0, 0.2, 0], [0, 0, 0.4]]", ERROR,
     r"r\.toml: platform_inertia\[0\]: expected a number"),
    ("inertia-text", 'platform_inertia = "0.2"', ERROR,
     r"r\.toml: platform_inertia: expected the three principal moments"),
    ("com-beyond-leg", "lower_com = 5.0", ERROR, r"r\.toml: lower_com: .*\(0, 1\.1\] m"),
    ("repeated-key", "platform_mass = 3.0\nplatform_mass = 3.0", ERROR,
     r"r\.toml: .*'platform_mass' given twice"),
    ("unknown-key", "platfrom_inertia = [0.2, 0.2, 0.4]", ERROR,
     r"r\.toml: platfrom_inertia: unknown key \(did you mean 'platform_inertia'\?\)"),
    ("radius-1e200", "base_radius = 1e200", ERROR,
     r"r\.toml: base_radius: must be a positive length in m, at most 1000 m"),
    ("stroke-1e300", "stroke = [0.5, 1e300]", ERROR, r"r\.toml: stroke: d_max must be at most"),
    ("home-1e300", "home_height = 1e300", ERROR, r"r\.toml: home_height: must be at most"),
    ("inertia-impossible", "platform_inertia = [0.1, 0.1, 0.5]", WARN,
     r"platform_inertia: principal moments 0\.1, 0\.1, 0\.5 kg m\^2 violate the triangle"),
]
"""Faults of a rig file (its explicit keys): each becomes a case of every command that reads
one (``RIG_COMMANDS``); an error names the file and the key, a warning the key."""

RIG_COMMANDS = {
    "show": ("platform", "--show", "--rig", "{r}"),
    "template": ("platform", "--template", "--rig", "{r}", "--out", "{tmp}/o.toml"),
    "log-inspect": ("log", "inspect", "{data}", "--rig", "{r}", "--out", "{tmp}/o"),
}


def rig_cases() -> list[Case]:
    return [Case(id=f"rig-{command}-{fault}", argv=argv, expect=expect,
                 code=2 if expect == ERROR else 0, message=message,
                 absent=("o", "o.toml") if expect == ERROR else (),
                 files={"data": trajectory(), "r": _rig_with(line)})
            for fault, line, expect, message in RIG_FAULTS
            for command, argv in RIG_COMMANDS.items()]


def _bom(maker):
    """``maker``'s file with a UTF-8 byte order mark in front (as Windows editors write)."""
    def make(folder):
        path = maker(folder)
        path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
        return path
    return make


BOM_TOML = {
    "rig": (("platform", "--template", "--rig", "{f}", "--out", "{tmp}/o.toml"), rig()),
    "column-map": (("simulate", "--trajectory", "{data}", "--column-map", "{f}", "--out",
                    "{tmp}/o.csv", "--no-progress"), column_map()),
}
"""The TOML inputs besides the platform file (its commands: ``PLATFORM_COMMANDS``)."""


def good_platform_cases() -> list[Case]:
    """A valid platform file with each command: a correct result; also with a UTF-8 byte
    order mark, as every other TOML input (accepted and skipped)."""
    cases = [Case(id=f"platform-{command}-{how}", argv=argv, expect=OK,
                  files={"data": trajectory(), "p": make(platform())})
             for command, argv in PLATFORM_COMMANDS.items()
             if command not in ("discover", "identify")
             for how, make in (("valid", lambda m: m), ("bom", _bom))]
    cases += [Case(id=f"toml-{kind}-bom", argv=argv, expect=OK,
                   files={"data": trajectory(), "f": _bom(maker)})
              for kind, (argv, maker) in BOM_TOML.items()]
    return cases


def base_rows() -> int:
    return len(base_frame())

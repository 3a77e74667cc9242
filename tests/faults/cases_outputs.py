"""Fault cases of the outputs: an output that is an input (same path, symbolic or hard link),
devices (/dev/null, /dev/full), directories, missing folders, full disks (ENOSPC)."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from makers import (
    column_map,
    content,
    folder,
    inside,
    old_output,
    platform,
    rig,
    trajectory,
    workspace,
)
from runner import ERROR, OK, Case

FILE_COMMANDS = {
    "simulate": (("simulate", "--trajectory", "{data}", "--platform", "{p}", "--no-progress",
                  "--column-map", "{map}"), ("data", "p", "map")),
    "synth": (("synth", "--samples", "40", "--platform", "{p}"), ("p",)),
    "template": (("platform", "--template", "--rig", "{rig}"), ("rig",)),
}
"""Commands writing one file: argv before ``--out``, the inputs an output may alias."""

KINDS = {"data": ("trajectory", "t.csv"), "p": ("platform", "p.toml"),
         "map": ("column-map", "map.toml"), "rig": ("rig", "r.toml"),
         "noise": ("noise-record", "n.csv"), "ws": ("workspace", "ws.toml")}
"""What each input placeholder is (as the messages name it) and its file name."""

FOLDER_COMMANDS = {
    "paper": (("paper", "--no-plots", "--platform", "{p}"), "p", "platform"),
    "sweep": (("sweep", "--trajectories", "{data}", "--no-plots", "--no-progress",
               "--scheduler", "serial"), "data", "trajectory"),
    "export": (("export", "--platform", "{p}"), "p", "platform"),
    "discover": (("discover", "--measured", "{data}", "--quiet"), "data", "measured-data"),
}
"""Commands writing a folder, as ``FILE_COMMANDS``."""

INPUTS = {"data": trajectory(), "p": platform(), "map": column_map(), "rig": rig()}

MAKERS = {"data": trajectory, "p": platform, "map": column_map, "rig": rig,
          "noise": lambda: trajectory("n.csv"), "ws": workspace}

FOLDER_READS = {
    "paper": {"p": ()},
    "sweep": {"data": (), "p": ("--platform", "{p}"), "ws": ("--workspace", "{ws}")},
    "export": {"p": ()},
    "discover": {"data": (), "p": ("--platform", "{p}"), "noise": ("--noise-record", "{noise}"),
                 "map": ("--column-map", "{map}")},
}
"""What each folder command reads (placeholders, as ``KINDS``) and the options adding those
that its ``FOLDER_COMMANDS`` command line leaves out: every one must lie outside the output
folder."""

FURTHER_OUTPUTS = {
    "simulate": (FILE_COMMANDS["simulate"][0] + ("--out", "{tmp}/o.csv"), "o.csv",
                 {"--plot": "p.png", "--breakdown": "b.csv"}),
}
"""Commands writing several files: argv with the main ``--out``, the main output's name, and
each option of a further file with a name it may take. All the files or none: a further one
that cannot be written leaves no output of the run."""


def _hardlink(name: str, target: str):
    def make(base: Path) -> Path:
        os.link(base / target, base / name)
        return base / name
    return make


def _symlink(name: str, target: str):
    def make(base: Path) -> Path:
        (base / name).symlink_to(base / target)
        return base / name
    return make


def full_disk(monkeypatch, paths) -> None:
    """Every fsync of a regular file fails with ENOSPC, as on a full disk."""
    real = os.fsync

    def fsync(fd):
        if stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)


def full_disk_after(count: int):
    """``full_disk`` from the ``count``-th fsync of a regular file on (those before succeed):
    a disk that fills while a run writes its later files."""
    def patch(monkeypatch, paths) -> None:
        real, seen = os.fsync, []

        def fsync(fd):
            if stat.S_ISREG(os.fstat(fd).st_mode):
                seen.append(fd)
                if len(seen) >= count:
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            real(fd)

        monkeypatch.setattr(os, "fsync", fsync)
    return patch


def _still_a_device(path: str):
    def check(paths):
        assert stat.S_ISCHR(os.lstat(path).st_mode)
    return check


def _file_cases(command: str, argv, aliases: tuple[str, ...]) -> list[Case]:
    name = {"template": "o.toml"}.get(command, "o.csv")
    out = f"{{tmp}}/{name}"
    cases = [
        Case(id=f"out-{command}-ok", argv=(*argv, "--out", out), expect=OK, files=dict(INPUTS),
             check=lambda paths, n=name: _nonempty(paths["tmp"] / n)),
        Case(id=f"out-{command}-dev-null", argv=(*argv, "--out", "/dev/null"), expect=OK,
             files=dict(INPUTS), check=_still_a_device("/dev/null")),
        Case(id=f"out-{command}-dev-full", argv=(*argv, "--out", "/dev/full"), expect=ERROR,
             code=3, message=r"/dev/full: .*No space left on device", files=dict(INPUTS)),
        Case(id=f"out-{command}-directory", argv=(*argv, "--out", "{tmp}/d"), expect=ERROR,
             code=2, message=r"/d'?:? .*directory", files={**INPUTS, "d": folder("d")}),
        Case(id=f"out-{command}-missing-folder", argv=(*argv, "--out", "{tmp}/no/" + name),
             expect=ERROR, code=2, message=r"no", files=dict(INPUTS)),
        Case(id=f"out-{command}-through-a-file", argv=(*argv, "--out", "{tmp}/f/" + name),
             expect=ERROR, code=2, message=r"not a directory|does not exist",
             files={**INPUTS, "f": content("f", "a file")}),
        Case(id=f"out-{command}-full-disk", argv=(*argv, "--out", out), expect=ERROR, code=3,
             message=rf"{name}: cannot write \(No space left on device\); nothing was written",
             files={**INPUTS, "old": old_output(name)}, patch=full_disk),
        Case(id=f"out-{command}-empty-path", argv=(*argv, "--out", ""), expect=ERROR, code=2,
             message=r".", files=dict(INPUTS)),
    ]
    if command != "template":
        cases.append(Case(id=f"out-{command}-unknown-extension",
                          argv=(*argv, "--out", "{tmp}/o.xyz"), expect=ERROR, code=2,
                          message=r"o\.xyz", files=dict(INPUTS), absent=("o.xyz",)))
    if command == "simulate":
        cases.append(Case(id="out-simulate-full-disk-parquet", argv=(*argv, "--out",
                                                                     "{tmp}/o.parquet"),
                          expect=ERROR, code=3, message=r"o\.parquet: cannot write \(No space "
                          r"left on device\)", files=dict(INPUTS), patch=full_disk,
                          absent=("o.parquet",)))
    for alias in aliases:
        kind, source = KINDS[alias]
        cases += [
            Case(id=f"out-{command}-is-{kind}", argv=(*argv, "--out", f"{{{alias}}}"),
                 expect=ERROR, code=2, message=rf"^{source}: is the {kind} file itself; "
                 "choose another output$".replace(source, f".*/{source}"), files=dict(INPUTS)),
            Case(id=f"out-{command}-symlink-to-{kind}", argv=(*argv, "--out", "{tmp}/l.csv"),
                 expect=ERROR, code=2, message=rf"l\.csv: is the same file as the {kind} "
                 rf"file .*/{source}; choose another output$",
                 files={**INPUTS, "l": _symlink("l.csv", source)}),
            Case(id=f"out-{command}-hardlink-to-{kind}", argv=(*argv, "--out", "{tmp}/h.csv"),
                 expect=ERROR, code=2, message=rf"h\.csv: is the same file as the {kind} "
                 rf"file .*/{source}; choose another output$",
                 files={**INPUTS, "h": _hardlink("h.csv", source)}),
        ]
    return cases


def _nonempty(path: Path) -> None:
    assert path.is_file() and path.stat().st_size > 0


def _folder_cases(command: str, argv, alias: str, kind: str) -> list[Case]:
    cases = [
        Case(id=f"out-{command}-onto-a-file", argv=(*argv, "--out", "{tmp}/f"), expect=ERROR,
             code=2, message=r"/f'?:? .*(not a directory|is a file)",
             files={**INPUTS, "f": content("f", "a file")}),
        Case(id=f"out-{command}-dev-null", argv=(*argv, "--out", "/dev/null"), expect=ERROR,
             code=2, message=r"/dev/null: exists and is not a directory", files=dict(INPUTS)),
        Case(id=f"out-{command}-dev-full", argv=(*argv, "--out", "/dev/full"), expect=ERROR,
             code=2, message=r"/dev/full: exists and is not a directory", files=dict(INPUTS)),
        Case(id=f"out-{command}-is-input", argv=(*argv, "--out", f"{{{alias}}}"),
             expect=ERROR, code=2, message=rf"is the {kind} file itself|is a file",
             files=dict(INPUTS)),
        Case(id=f"out-{command}-symlink-to-input", argv=(*argv, "--out", "{tmp}/l"),
             expect=ERROR, code=2, message=rf"same file as the {kind} file|is a file",
             files={**INPUTS, "l": _symlink("l", "t.csv" if alias == "data" else "p.toml")}),
    ]
    creates = command in ("paper", "export")     # a missing parent folder is created
    message = {"sweep": r"no/o'?:? .*does not exist",
               "discover": "needs at least"}.get(command, "")   # 100 rows: too short
    cases.append(Case(id=f"out-{command}-missing-parent", argv=(*argv, "--out", "{tmp}/no/o"),
                      expect=OK if creates else ERROR, code=0 if creates else 2,
                      message=message, files=dict(INPUTS)))
    if command != "discover":
        cases += [
            Case(id=f"out-{command}-ok", argv=(*argv, "--out", "{tmp}/o"), expect=OK,
                 files=dict(INPUTS), check=lambda paths: _nonempty_folder(paths["tmp"] / "o")),
            Case(id=f"out-{command}-full-disk", argv=(*argv, "--out", "{tmp}/o"), expect=ERROR,
                 code=3, message=r"No space left on device", files=dict(INPUTS),
                 patch=full_disk, absent=("o",)),
        ]
    return cases


def _nonempty_folder(path: Path) -> None:
    assert path.is_dir() and any(path.iterdir())


def _inside_cases(command: str, argv, data_kind: str) -> list[Case]:
    """Each input of a folder command inside the output folder (named directly, or through a
    symbolic link to the folder) is refused before anything is read or written."""
    reads = FOLDER_READS[command]
    extra = tuple(a for option in reads.values() for a in option)
    cases = []
    for alias in reads:
        kind, source = KINDS[alias]
        kind = data_kind if alias == "data" else kind
        files = {**INPUTS, **{a: MAKERS[a]() for a in reads}, alias: inside("o", MAKERS[alias]())}
        message = rf"o: holds the {kind} file .*/o/{source}, an input of the run; choose "
        cases += [
            Case(id=f"out-{command}-holds-{kind}", argv=(*argv, *extra, "--out", "{tmp}/o"),
                 expect=ERROR, code=2, message=message, files=files),
            Case(id=f"out-{command}-link-holds-{kind}",
                 argv=(*argv, *extra, "--out", "{tmp}/lo"), expect=ERROR, code=2,
                 message=message.replace("o: holds", "lo: holds"),
                 files={**files, "lo": _symlink("lo", "o")}),
        ]
    return cases


def _further_cases(command: str, argv, main: str, options: dict[str, str]) -> list[Case]:
    """Each further output of a command writing several files, by class: in a missing folder,
    under a file, a directory, the main output, an input, and a disk that fills after the
    main output: an error naming it, and neither it nor the main output written (an earlier
    main output unchanged)."""
    cases = []
    for option, name in options.items():
        tag = f"out-{command}-{option.lstrip('-')}"
        absent = (main, name)
        cases += [
            Case(id=f"{tag}-missing-folder", argv=(*argv, option, "{tmp}/no/" + name),
                 expect=ERROR, code=2, message=rf"no/{name}: directory .* does not exist",
                 files=dict(INPUTS), absent=absent),
            Case(id=f"{tag}-through-a-file", argv=(*argv, option, "{tmp}/f/" + name),
                 expect=ERROR, code=2, message=rf"f/{name}: .*/f' is not a directory",
                 files={**INPUTS, "f": content("f", "a file")}, absent=(main,)),
            Case(id=f"{tag}-directory", argv=(*argv, option, "{tmp}/d"), expect=ERROR,
                 code=2, message=r"/d: is a directory", files={**INPUTS, "d": folder("d")},
                 absent=(main,)),
            Case(id=f"{tag}-is-out", argv=(*argv, option, "{tmp}/" + main), expect=ERROR,
                 code=2, message=rf"{main}: is the same file as the output", files=dict(INPUTS),
                 absent=(main,)),
            Case(id=f"{tag}-is-trajectory", argv=(*argv, option, "{data}"), expect=ERROR,
                 code=2, message=r"t\.csv: is the trajectory file itself", files=dict(INPUTS),
                 absent=(main,)),
            Case(id=f"{tag}-full-disk", argv=(*argv, option, "{tmp}/" + name), expect=ERROR,
                 code=3, message=rf"{name}: cannot write \(No space left on device\); nothing "
                 "was written", files={**INPUTS, "old": old_output(main)},
                 patch=full_disk_after(2), absent=(name,)),
        ]
    return cases


def output_cases() -> list[Case]:
    cases = []
    for command, (argv, main, options) in FURTHER_OUTPUTS.items():
        cases += _further_cases(command, argv, main, options)
    for command, (argv, aliases) in FILE_COMMANDS.items():
        cases += _file_cases(command, argv, aliases)
    for command, (argv, alias, kind) in FOLDER_COMMANDS.items():
        cases += _folder_cases(command, argv, alias, kind)
        cases += _inside_cases(command, argv, kind)
    return cases

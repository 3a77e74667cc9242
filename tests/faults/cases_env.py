"""Fault cases of the environment and the command line: no compiler, the build chosen
(GSFRIC_ISA), threads, usage mistakes and interruptions (Ctrl-C, SIGTERM, SIGHUP arriving while
the outputs are written)."""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
from click.testing import CliRunner
from makers import long_trajectory, old_output, platform, trajectory
from runner import ERROR, OK, Case

from gsfric.cli import main
from gsfric.errors import Interrupted

SIMULATE = ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv", "--no-progress")


@functools.cache
def reference_output(rows: int | None = None) -> pd.DataFrame:
    """``simulate`` of the base trajectory (or of a long one of ``rows`` rows) by the
    compiled library in one thread, in this process."""
    with tempfile.TemporaryDirectory() as folder:
        data = (trajectory() if rows is None else long_trajectory("t.csv", rows))(Path(folder))
        out = Path(folder) / "o.csv"
        result = CliRunner().invoke(main, ["simulate", "--trajectory", str(data), "--out",
                                           str(out), "--no-progress"])
        assert result.exit_code == 0, result.output
        return pd.read_csv(out)


def same_as_reference(rtol: float, rows: int | None = None):
    def check(paths):
        got = pd.read_csv(paths["tmp"] / "o.csv")
        want = reference_output(rows)
        assert list(got.columns) == list(want.columns)
        np.testing.assert_allclose(got.to_numpy(), want.to_numpy(), rtol=rtol, atol=1e-9)
    return check


# -- the compiled model and its build (fresh processes: a build is loaded once per process) -----


def compiler_cases() -> list[Case]:
    """Nothing is compiled at run time: no compiler is needed, and the build is chosen by the
    CPU or by ``GSFRIC_ISA``."""
    base = {"data": trajectory()}
    return [
        Case(id="cc-simulate-missing", argv=SIMULATE, expect=OK, process=True,
             env={"CC": "/nonexistent/cc"}, files=dict(base), check=same_as_reference(0)),
        Case(id="isa-simulate-baseline", argv=SIMULATE, expect=OK, process=True,
             env={"GSFRIC_ISA": "baseline"}, files=dict(base), check=same_as_reference(1e-9)),
        Case(id="isa-simulate-unknown", argv=SIMULATE, expect=ERROR, code=2, process=True,
             env={"GSFRIC_ISA": "avx9000"}, files=dict(base),
             message=r"^GSFRIC_ISA='avx9000': expected one of baseline, x86-64-v3, x86-64-v4$",
             absent=("o.csv",)),
    ]


# -- threads ------------------------------------------------------------------------------------


def thread_cases() -> list[Case]:
    cases = [Case(id=f"threads-simulate-{name}", argv=(*SIMULATE, "--threads", value),
                  expect=ERROR, code=2, message=r"--threads", files={"data": trajectory()},
                  absent=("o.csv",))
             for name, value in (("zero", "0"), ("negative", "-5"), ("text", "abc"),
                                 ("fraction", "1.5"), ("too-many", "65"), ("empty", ""))]
    cases += [Case(id=f"threads-simulate-{n}", argv=(*SIMULATE, "--threads", str(n)),
                   expect=OK, files={"data": long_trajectory()},
                   check=same_as_reference(0, rows=5000))
              for n in (2, 3, 64)]
    return cases


# -- usage mistakes -----------------------------------------------------------------------------

USAGE = {
    "simulate": ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv"),
    "synth": ("synth", "--out", "{tmp}/o.csv"),
    "platform": ("platform", "--template", "--out", "{tmp}/o.toml"),
    "paper": ("paper", "--out", "{tmp}/o"),
    "sweep": ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o"),
    "export": ("export", "--out", "{tmp}/o"),
    "discover": ("discover", "--measured", "{data}", "--out", "{tmp}/o"),
    "columns": ("columns",),
    "effects": ("effects",),
    "derive": ("derive", "--check"),
    "bench": ("bench",),
    "view": ("view", "--trajectory", "{data}", "--out", "{tmp}/o.html"),
    "log": ("log", "inspect", "{data}", "--out", "{tmp}/o"),
}
"""A valid command line of each command (the usage cases add one mistake to it)."""

REPEATABLE = {"--vary": ("platform.payload_mass=0:8", "platform.payload_mass=1:2"),
              "--tolerance": ("platform.payload_mass=0.1", "platform.payload_mass=0.2")}
"""Every option that names a parameter and may be repeated: a name given twice is an error
(the later value would silently replace the first)."""

MISSING = {"simulate": ("--trajectory", "{data}"), "discover": ("--measured", "{data}"),
           "paper": ("--out", "{tmp}/o"), "sweep": ("--out", "{tmp}/o"),
           "synth": ("--out", "{tmp}/o.csv")}
"""A required option of each command that has one (left out by a case)."""

BAD_VALUES = [
    ("simulate-mode", ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv", "--mode",
                       "fast"), r"--mode"),
    ("simulate-chunk", ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv",
                        "--chunk", "0"), r"chunk"),
    ("simulate-columns", ("simulate", "--trajectory", "{data}", "--out", "{tmp}/o.csv",
                          "--columns", "nonsense"), r"nonsense"),
    ("synth-samples", ("synth", "--out", "{tmp}/o.csv", "--samples", "-3"), r"--samples"),
    ("synth-rate", ("synth", "--out", "{tmp}/o.csv", "--rate", "1e9"), r"--rate"),
    ("synth-effect", ("synth", "--out", "{tmp}/o.csv", "--effect", "warp_drive"),
     r"warp_drive"),
    ("export-out-empty", ("export", "--out", ""), r"^--out: an empty path"),
    ("synth-seed", ("synth", "--out", "{tmp}/o.csv", "--seed", "-1"), r"--seed.*x>=0"),
    ("excite-seed", ("excite", "--out", "{tmp}/o.csv", "--seed", "-1"), r"--seed.*x>=0"),
    ("sweep-seed", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o", "--vary",
                    "platform.payload_mass=0:2", "--seed", "-1"), r"--seed.*x>=0"),
    ("sweep-vary-one-value", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                              "--vary", "platform.payload_mass=2:2"),
     r"vary: platform\.payload_mass: 2:2 is one value"),
    ("sweep-variants-alone", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                              "--variants", "5"), r"^--variants: .* --vary .* --tolerance"),
    # noise that makes a record gsfric's readers refuse: refused before anything is written
    ("synth-noise-absurd", ("synth", "--out", "{tmp}/o.csv", "--samples", "60", "--noise",
                            "1e12"), r"noise = 1e\+12 N.*refused when read.*plausible actuator"),
    ("synth-pose-noise-absurd", ("synth", "--out", "{tmp}/o.csv", "--samples", "60",
                                 "--pose-noise", "10"),
     r"pose_noise = 10 m.*refused when read.*outside the stroke"),
    ("paper-mode", ("paper", "--out", "{tmp}/o", "--mode", "fast"), r"--mode"),
    ("export-prefix", ("export", "--out", "{tmp}/o", "--prefix", "1 bad"), r"prefix"),
    ("export-model", ("export", "--out", "{tmp}/o", "--model", "magic"), r"--model"),
    ("sweep-vary-unknown", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                            "--vary", "base_scale=0:1"), r"base_scale: unknown parameter"),
    ("sweep-vary-degenerate", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                               "--vary", "geometry.base_scale=0:0"),
     r"vary: geometry\.base_scale: 0:0 leaves the valid range 0\.1:10"),
    ("sweep-vary-absurd", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                           "--vary", "gravity=0:1e308"),
     r"vary: gravity: 0:1e\+308 leaves the valid range 0:100"),
    ("sweep-vary-mass", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                         "--vary", "platform.mass=1:1e30"), r"platform\.mass: .*valid range"),
    ("sweep-vary-mu", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                       "--vary", "friction.prismatic_coulomb=0:50"),
     r"prismatic_coulomb: .*valid range 0:2"),
    ("sweep-vary-reversed", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                             "--vary", "gravity=9:1"), r"gravity"),
    ("sweep-vary-nan", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                        "--vary", "gravity=nan:1"), r"gravity"),
    ("sweep-vary-syntax", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                           "--vary", "gravity"), r"--vary"),
    ("sweep-tolerance-negative", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                                  "--tolerance", "gravity=-1"), r"gravity"),
    ("sweep-scheduler", ("sweep", "--trajectories", "{data}", "--out", "{tmp}/o",
                         "--scheduler", "cloud9"), r"scheduler"),
    ("sweep-no-match", ("sweep", "--trajectories", "{tmp}/none*.csv", "--out", "{tmp}/o"),
     r"matches no file"),
]


def usage_cases() -> list[Case]:
    files = {"data": trajectory()}
    cases = [Case(id="usage-unknown-command", argv=("simulat",), expect=ERROR, code=2,
                  message=r"No such command 'simulat'", files=files)]
    for command, argv in USAGE.items():
        cases.append(Case(id=f"usage-{command}-unknown-option", argv=(*argv, "--bogus"),
                          expect=ERROR, code=2,
                          # click's wording: "No such option '--bogus'" (8.5),
                          # "No such option: --bogus" (8.2)
                          message=r"No such option:? '?--bogus'?",
                          files=files, absent=("o", "o.csv", "o.toml")))
    for command, option in MISSING.items():
        argv = list(USAGE[command])
        k = argv.index(option[0])
        del argv[k:k + 2]
        cases.append(Case(id=f"usage-{command}-missing-option", argv=tuple(argv), expect=ERROR,
                          code=2, message=rf"Missing option '{option[0]}'", files=files))
    for option, values in REPEATABLE.items():
        cases.append(Case(id=f"usage-sweep-repeated{option}", expect=ERROR, code=2,
                          argv=(*USAGE["sweep"], option, values[0], option, values[1]),
                          message=rf"^{option}: 'platform\.payload_mass' given twice; give each "
                          "parameter once$", files=files, absent=("o",)))
    for command, argv in USAGE.items():      # one value each: a second would replace it
        if "--out" in argv:
            help_of = " ".join(argv[:2] if command == "log" else argv[:1])
            cases.append(Case(id=f"usage-{command}-out-without-value",
                              argv=(*argv, "--out"), expect=ERROR, code=2,
                              message=rf"'--out' requires an argument.* \(see `gsfric "
                                      rf"{help_of} --help`\)$", files=files))
            out = argv[argv.index("--out") + 1]
            cases.append(Case(id=f"usage-{command}-repeated-out", expect=ERROR, code=2,
                              argv=(*argv, "--out", out.replace("/o", "/o2")),
                              message=r"^--out: given more than once; give it once",
                              files=files, absent=("o", "o.csv", "o.toml", "o.html", "o2",
                                                   "o2.csv", "o2.toml", "o2.html")))
    for name, argv, message in BAD_VALUES:
        cases.append(Case(id=f"usage-{name}", argv=argv, expect=ERROR, code=2,
                          message=message, files=files, absent=("o", "o.csv")))
    return cases


# -- interruptions while the outputs are written ------------------------------------------------


def stop_while_writing(stop: BaseException, nth: int = 1):
    """The ``nth`` fsync of a file raises ``stop`` (those before succeed): the signal arrives
    mid-write (of a later file of the run, ``nth`` > 1)."""
    def patch(monkeypatch, paths):
        real, calls = os.fsync, []

        def fsync(fd):
            calls.append(fd)
            if len(calls) >= nth:
                raise stop
            real(fd)

        monkeypatch.setattr(os, "fsync", fsync)
    return patch


STOPS = [("ctrl-c", KeyboardInterrupt(), 130, r"^interrupted; no output was left half-written"),
         ("sigterm", Interrupted(signal.SIGTERM), 143,
          r"^stopped by SIGTERM; no output was left half-written"),
         ("sighup", Interrupted(signal.SIGHUP), 129,
          r"^stopped by SIGHUP; no output was left half-written")]

WRITERS = {
    "simulate": (SIMULATE, "o.csv"),
    "synth": (("synth", "--out", "{tmp}/o.csv", "--samples", "40"), "o.csv"),
    "template": (("platform", "--template", "--out", "{tmp}/o.toml"), "o.toml"),
    "paper": (("paper", "--out", "{tmp}/o", "--no-plots"), "o"),
    "export": (("export", "--out", "{tmp}/o"), "o"),
}


LATER_FILES = {
    "simulate-plot": ((*SIMULATE, "--plot", "{tmp}/p.png"), "o.csv", "p.png"),
    "simulate-breakdown": ((*SIMULATE, "--breakdown", "{tmp}/b.csv"), "o.csv", "b.csv"),
}
"""Commands writing several files: a stop while the second is written leaves none of them
(the earlier main output unchanged)."""


def interrupt_cases() -> list[Case]:
    cases = [Case(id=f"stop-{command}-{name}", argv=argv, expect=ERROR, code=code,
                  message=message, files={"data": trajectory(), "old": old_output(out)},
                  patch=stop_while_writing(stop, nth=2), absent=(later,))
             for command, (argv, out, later) in LATER_FILES.items()
             for name, stop, code, message in STOPS]
    for command, (argv, out) in WRITERS.items():
        for name, stop, code, message in STOPS:
            earlier = {} if out == "o" else {"old": old_output(out)}
            cases.append(Case(id=f"stop-{command}-{name}", argv=argv, expect=ERROR, code=code,
                              message=message, files={"data": trajectory(), **earlier},
                              patch=stop_while_writing(stop),
                              absent=("o",) if out == "o" else ()))
    return cases + sweep_stop_cases()


def _stop_task(after: int):
    """The sweep's ``after + 1``-th task is interrupted (Ctrl-C), once."""
    def patch(monkeypatch, paths):
        import gsfric.sweep.run as sweep_run
        real, calls = sweep_run.run_task, []

        def run_task(task):
            calls.append(task)
            if len(calls) == after + 1:
                raise KeyboardInterrupt
            return real(task)

        monkeypatch.setattr(sweep_run, "run_task", run_task)
    return patch


def _partial_kept_and_resumed(paths):
    """One finished task kept; the same command then resumes (computing only the other)."""
    partial = paths["tmp"] / "o.partial"
    assert len(list((partial / "chunks").glob("*.parquet"))) == 1
    assert not (paths["tmp"] / "o").exists()
    argv = [a.format(tmp=paths["tmp"]) for a in SWEEP]
    result = CliRunner().invoke(main, argv)
    assert result.exit_code == 0, result.output
    assert json.loads((paths["tmp"] / "o" / "sweep.json").read_text())["computed_tasks"] == 1
    assert not partial.exists()


SWEEP = ("sweep", "--trajectories", "{tmp}/*.csv", "--out", "{tmp}/o", "--no-plots",
         "--no-progress", "--scheduler", "serial")


def sweep_stop_cases() -> list[Case]:
    files = {"a": trajectory("a.csv"), "b": trajectory("b.csv")}
    return [
        Case(id="stop-sweep-first-task", argv=SWEEP, expect=ERROR, code=130,
             message=r"^interrupted", files=files, patch=_stop_task(0), absent=("o",)),
        Case(id="stop-sweep-second-task-kept", argv=SWEEP, expect=ERROR, code=130,
             message=r"^interrupted", files=files, patch=_stop_task(1), kept=("o.partial",),
             check=_partial_kept_and_resumed, warning=r"o\.partial: the unfinished sweep is kept \(1 of 2 "
                                         r"tasks done\); run the same command again to resume"),
    ]


def platform_file() -> dict:
    return {"p": platform()}


# -- what a killed run left: removed by the next run ---------------------------------------------


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def stale_temporary(output: str, folder_like: bool = False):
    """The 0-byte temporary (or temporary folder) that a SIGKILLed run writing ``output``
    left beside it."""
    def make(base: Path) -> Path:
        path = base / f".{output}.gsfric-{_dead_pid()}-k1ll3d.tmp"
        if folder_like:
            path.mkdir()
            (path / "table1.csv").write_bytes(b"")
        else:
            path.write_bytes(b"")
        return path
    return make


def stale_cases() -> list[Case]:
    cases = []
    for command, (argv, out) in WRITERS.items():
        stale = stale_temporary(out, folder_like=out == "o")
        cases.append(Case(id=f"stale-{command}-next-run-cleans", argv=argv, expect=OK,
                          files={"data": trajectory(), "stale": stale}, mutable=("*.gsfric-*",)))
    cases.append(Case(id="stale-simulate-failing-run-cleans", expect=ERROR, code=2,
                      argv=("simulate", "--trajectory", "{tmp}/none.csv", "--out",
                            "{tmp}/o.csv"), message=r"none\.csv: file not found",
                      files={"stale": stale_temporary("o.csv")}, mutable=("*.gsfric-*",)))
    return cases

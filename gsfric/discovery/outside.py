"""Every structure outside the catalog that discovery looks for, in one table (``OUTSIDE``).

A residual that no catalog effect explains can have many forms; three mechanisms look for
them, each for the forms it can state as a test:

* ``basis`` (``lackfit.test``): a regression on generic signals of a fixed shape, each shared
  by the six legs (one coefficient: the load cells of a rig are alike). It runs in each round
  as the winner's generic competitor and on the final residual.
* ``test`` (``final_tests.STRUCTURE_TESTS``): tests of the final residual for forms without a
  fixed shape: a friction level that changes over the record, a repeatable function of a
  state variable, a filter of the motion, a function of the travel since each reversal, a
  transient at the rests.
* ``dictionary`` (``dictionary.find``): groups of per-leg columns, taken by forward selection
  and described in a rig engineer's words (a cell's own trouble is one cell's).

The mechanisms overlap on purpose where one form has several shapes: a drift is a slow
common level (``basis``), a friction level changing in time (``test``) and per-leg levels
and steps (``dictionary``); the report says which test found what.

Each entry's ``name`` is its key in summary.json (a basis signal's in ``lack_of_fit.signals``
and ``main_signal``, a test's under ``lack_of_fit``, a group's as a structure's ``kind``) and
``looks_like`` what it suggests, as the report says it.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Outside:
    """One structure discovery looks for outside the catalog.

    Attributes
    ----------
    name : str
        Its name in summary.json and the report.
    by : {"basis", "test", "dictionary"}
        The mechanism that looks for it.
    shows : str
        What the structure is, in a few words (a test's ``main_signal``).
    looks_like : str
        What it suggests about the rig.
    """

    name: str
    by: str
    shows: str
    looks_like: str


OUTSIDE: tuple[Outside, ...] = (
    Outside("dF/dt", "basis", "follows the rate of change of the force",
            "correlated with the rate of change of the force: a delay between the pose and "
            "force channels, or a dynamic sensor"),
    Outside("F|F|", "basis", "grows with the square of the force",
            "growing with the square of the force: a nonlinear load cell"),
    Outside("F^3", "basis", "grows with the cube of the force",
            "growing with the cube of the force: a nonlinear (saturating) load cell"),
    Outside("F", "basis", "proportional to the force",
            "proportional to the force: a gain error of the load cells"),
    Outside("sgn(v)", "basis", "follows the sign of the leg speed",
            "friction-like, following the sign of the leg speed with a law outside the "
            "catalog"),
    Outside("acceleration", "basis", "follows the legs' acceleration",
            "correlated with the legs' acceleration: an inertia or timing error"),
    Outside("drift", "basis", "a slow cubic in time, common to the legs",
            "a slow drift in time: a thermal drift or a zero shift of the load cells"),
    Outside("dF/dt between legs", "basis", "follows the force's rate differently on each leg",
            "correlated with the rate of change of the force, differently on each leg: a "
            "delay that differs between the force channels"),
    Outside("pose scale", "basis", "what a scaled position axis makes of the forces",
            "what a scale error of the recorded position (x, y or z) makes of the "
            "rigid-body force: a calibration error of the pose measurement"),
    Outside("drift", "test", "drifts over the record",
            "a friction that changes over the record (the friction-like part of the "
            "residual grows or shrinks with time): a seal or lubricant warming up or "
            "wearing in"),
    Outside("state", "test", "repeats with a state variable",
            "a function of the leg's state, the same at every visit"),
    Outside("dynamic", "test", "driven by the motion",
            "driven by the motion through a filter (it follows the force's rate or the legs' "
            "acceleration beyond the residual's own past): a resonance of the structure, "
            "a delay or the dynamics of the sensor"),
    Outside("reversal", "test", "follows the travel since each reversal",
            "a friction-like force that depends on the travel since the last reversal, "
            "not on the speed: play in a joint, a pre-sliding (Dahl-like) friction, or "
            "a friction that builds up after each reversal"),
    Outside("rest", "test", "transient at the rests",
            "largest just after each stop and dying out during the rest: a mode of the "
            "structure ringing after the stop, a creep or relaxation of the load cells, or "
            "the controller settling"),
    Outside("line", "dictionary", "a sine at a spectral peak of the residual",
            "interference on the load cells: mains, a drive's switching, a pump"),
    Outside("coupling", "dictionary", "the other legs' model forces",
            "cross-talk between the load cells' channels"),
    Outside("sensor memory", "dictionary", "a reading with a dead band or hysteresis",
            "a load cell with play or a reading that depends on the direction of the force "
            "change"),
    Outside("drift", "dictionary", "time polynomials and steps, per leg",
            "a zero drifting, or a step over the record, of one load cell"),
    Outside("state", "dictionary", "the leg's stroke, speed and the platform's position",
            "a dependence on speed, stroke or pose that no candidate removed"),
)
"""The structures, by mechanism, each mechanism's in the order it uses them."""

STATE_MEANING = {
    "leg length": "a function of the stroke position, the same at every visit: a spring or "
                  "cable force, a screw's ripple, a position-dependent friction",
    "leg speed": "a function of the leg speed, the same at every visit: a friction or damping "
                 "law outside the catalog",
    "model force": "a function of the leg's own force: a nonlinear or hysteretic load cell",
}
"""What the ``state`` test's finding suggests for each state variable it bins by; the force
of another leg means crosstalk between the load cells' channels."""


def names(by: str) -> tuple[str, ...]:
    """The names of the structures ``by`` looks for, in its order."""
    return tuple(o.name for o in OUTSIDE if o.by == by)


def entry(by: str, name: str) -> Outside:
    """The structure ``name`` that ``by`` looks for (KeyError: none)."""
    for o in OUTSIDE:
        if o.by == by and o.name == name:
            return o
    raise KeyError(f"{by}: {name}")


def looks_like(by: str, name: str | None) -> str:
    """What the structure ``name`` found by ``by`` suggests ("" for None or an unknown
    name)."""
    try:
        return entry(by, name).looks_like if name is not None else ""
    except KeyError:
        return ""


def state_meaning(variable: str) -> str:
    """What a repeatable residual in bins of ``variable`` suggests."""
    if variable.startswith("force of leg"):
        return ("a function of another leg's force: crosstalk between the load cells' channels "
                "or a load path the model does not have")
    return STATE_MEANING.get(variable, "")


def markdown_table() -> str:
    """The table as the documentation shows it (Markdown)."""
    mechanism = {"basis": "generic basis", "test": "test of the final residual",
                 "dictionary": "per-leg dictionary"}
    rows = ["| name | found by | what it is | what it suggests |", "|---|---|---|---|"]
    rows += [f"| `{o.name}` | {mechanism[o.by]} | {o.shows} | {o.looks_like} |".replace(
        "F|F|", "F\\|F\\|") for o in OUTSIDE]
    return "\n".join(rows) + "\n"

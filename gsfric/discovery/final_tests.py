"""The lack-of-fit tests of the final residual, run from one registry: is structure left that
no catalog effect explains, and what does it look like?

Each test (``STRUCTURE_TESTS``) is a unit with one signature, ``run(data) -> Structure``, on
the final residual and what the tests read of the record (``FinalResidual``). The registry's
order is the order of precedence: the first test that
finds structure says what it is (``main_signal``) and what it suggests (``looks_like``):
structure in a form of the generic basis says most about what it is; else a friction that
drifts over the record; else structure that repeats with the state; else structure that
follows the motion; else after each reversal; else what happens at the rests.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gsfric.discovery import lackfit, outside, structure, transients
from gsfric.discovery import statistics as st
from gsfric.discovery.evidence import Structure
from gsfric.discovery.residuals import Problem
from gsfric.discovery.selection import low_band_of


@dataclass(frozen=True)
class FinalResidual:
    """The final residual and what the structure tests read of the record (M used samples).

    Attributes
    ----------
    problem : Problem
    theta : ndarray, shape (n_theta,)
        The final parameters.
    residual : ndarray, shape (M, 6)
        The final residual, N (not-sliding pairs zero).
    in_model : tuple of str
        Effects of the final model (their signals are not structure outside it).
    t : ndarray, shape (M,)
        Sample times, s.
    F : ndarray, shape (M, 6)
        The final model's forces, N.
    speed, D : ndarray, shape (M, 6)
        Leg speeds (m/s) and lengths (m) of the model as given.
    dF, acceleration : ndarray, shape (M, 6)
        dF/dt (N/s) and the legs' acceleration (m/s^2) (``lackfit.rates``).
    """

    problem: Problem
    theta: np.ndarray
    residual: np.ndarray
    in_model: tuple[str, ...]
    t: np.ndarray
    F: np.ndarray
    speed: np.ndarray
    D: np.ndarray
    dF: np.ndarray
    acceleration: np.ndarray

    @classmethod
    def of(cls, problem: Problem, theta: np.ndarray, residual: np.ndarray,
           in_model: Sequence[str]) -> FinalResidual:
        """The tests' data at the final parameters theta."""
        used = problem.used
        F = problem.model.forces(theta)[used]
        t = np.asarray(problem.model.t[used])
        speed = problem.result.D_dot[used]
        dF, acceleration = lackfit.rates(t, F, speed)     # once: the basis and the dynamic test
        return cls(problem, theta, residual, tuple(in_model), t, F, speed,
                   problem.result.D[used], dF, acceleration)


def _basis(d: FinalResidual) -> Structure:
    """``lackfit.test`` against the generic basis outside the final model, prewhitened with
    the noise model of the residual left by the basis fit (the largest model, as in each
    round)."""
    s, sliding = d.problem.settings, d.problem.sliding
    # a signal that an effect of the final model reproduces (a delay's dF/dt once time_offset
    # is in it) is that effect's parameter, refitted already: not a structure outside the model
    X, names = lackfit.basis_outside(d.t, d.F, d.speed, sliding, d.problem.weight, d.in_model,
                                     derivatives=(d.dF, d.acceleration))
    whitener = lackfit.whitener_beyond(d.residual, X, sliding, s)
    return lackfit.test(d.residual, X, whitener, alpha=s.alpha, min_gap=s.min_gap,
                        n_blocks=s.n_blocks, n_folds=s.n_folds, ridge=s.ridge, names=names,
                        low=low_band_of(d.problem, whitener))


def _drift(d: FinalResidual) -> Structure:
    """``lackfit.parameter_drift``, with the friction level per third of the record."""
    s, sliding = d.problem.settings, d.problem.sliding
    X = lackfit.drift_basis(d.t, d.speed, sliding) * d.problem.weight[:, :, None]
    out = lackfit.parameter_drift(d.residual, X, sliding, d.t, s)
    out.details["levels"] = lackfit.friction_levels(d.t, d.residual, d.speed, sliding)
    out.keys = out.keys + ("levels",)
    return out


def _state(d: FinalResidual) -> Structure:
    """``structure.state_structure`` over the legs' lengths, speeds and forces."""
    s = d.problem.settings
    return structure.state_structure(d.residual, structure.state_features(d.D, d.speed, d.F),
                                     d.problem.sliding, n_folds=s.n_folds, min_gap=s.min_gap,
                                     n_bins=s.state_bins)


def _dynamic(d: FinalResidual) -> Structure:
    """``structure.dynamic_structure`` driven by dF/dt and the legs' acceleration."""
    s = d.problem.settings
    inputs = {"dF/dt": d.dF, "acceleration": d.acceleration}
    return structure.dynamic_structure(d.residual, inputs, d.problem.sliding, alpha=s.alpha,
                                       min_gap=max(s.min_gap, s.dynamic_min_gap),
                                       order=s.dynamic_order, lags=s.dynamic_lags)


def _reversal(d: FinalResidual) -> Structure:
    """``structure.reversal_structure`` on the travel since each reversal."""
    s, sliding = d.problem.settings, d.problem.sliding
    direction, travel = structure.travel_since_reversal(d.D, d.speed, sliding)
    return structure.reversal_structure(d.residual, direction, travel, sliding,
                                        n_folds=s.n_folds, alpha=s.alpha, min_gap=s.min_gap,
                                        edges=np.asarray(s.travel_edges, float))


def _rest(d: FinalResidual) -> Structure:
    """``transients.rest_transients`` on the rest cores: the measured force less the final
    model's frictionless force, where friction is static. The load cells' gains and delay
    are not applied: at rest the force is constant, a gain changes it by a constant and a
    delay (shorter than the differentiator's reach cut from the cores) not at all, while a
    delay fitted to imitate something else would put its own transients into the rests."""
    problem = d.problem
    s = problem.settings
    runs = transients.rest_runs(problem.sliding, problem.move_reach, min_run=s.rest_min_run)
    if len(runs) < 4:
        runs, residual = [], np.zeros_like(problem.y)
    else:
        residual = problem.y - problem.model.evaluate(d.theta, keep=("F0",)).F0[problem.used]
    return transients.rest_transients(residual, runs, alpha=s.alpha, min_gap=s.min_gap,
                                      window=s.rest_window, lags=s.rest_lags,
                                      min_rests=s.rest_min_rests)


def _basis_signal(result: Structure) -> str | None:
    """The generic signal that carries most of the basis's structure (None: no signal)."""
    signals = result.details["signals"]
    return max(signals, key=signals.get) if signals else None


def _basis_words(result: Structure) -> tuple[str | None, str]:
    signal = _basis_signal(result)
    return signal, outside.looks_like("basis", signal)


def _state_words(result: Structure) -> tuple[str, str]:
    variable = result.details["variable"]
    return f"repeats with {variable}", outside.state_meaning(variable)


def _words(name: str) -> Callable[[Structure], tuple[str, str]]:
    found = outside.entry("test", name)
    return lambda result: (found.shows, found.looks_like)


@dataclass(frozen=True)
class StructureTest:
    """One lack-of-fit test of the final residual.

    Attributes
    ----------
    name : str
        Its key in summary.json's ``lack_of_fit`` (the basis's result is ``lack_of_fit``
        itself); the others' entries in ``outside.OUTSIDE``.
    run : callable
        ``run(data: FinalResidual) -> Structure``.
    words : callable
        ``words(result) -> (main_signal, looks_like)``: what the structure is and what it
        suggests, when this test is the first to find it.
    """

    name: str
    run: Callable[[FinalResidual], Structure]
    words: Callable[[Structure], tuple[str | None, str]]


STRUCTURE_TESTS: tuple[StructureTest, ...] = (
    StructureTest("basis", _basis, _basis_words),
    StructureTest("drift", _drift, _words("drift")),
    StructureTest("state", _state, _state_words),
    StructureTest("dynamic", _dynamic, _words("dynamic")),
    StructureTest("reversal", _reversal, _words("reversal")),
    StructureTest("rest", _rest, _words("rest")),
)
"""The tests, in their order of precedence."""

SUMMARY_ORDER = ("state", "dynamic", "reversal", "rest", "drift")
"""The order of the tests' results after the basis's own entries in summary.json."""


@dataclass
class LackOfFit:
    """The lack-of-fit tests of the final residual, and what they say together.

    Attributes
    ----------
    basis : Structure
        The test against the generic basis (``lackfit.test``).
    tests : dict[str, Structure]
        The other tests of ``STRUCTURE_TESTS``, by name.
    significant, gap, structure_rms, per_leg_rms
        Of the first test that found structure (the basis's when none did), as in
        ``Structure``.
    time_rms : dict[str, float]
        RMS of that test's fitted structure (the basis's but for the drift test) per third of
        the record, N, by its time span.
    frequency : float
        Frequency of the largest peak of the residual's power spectrum, Hz.
    looks_like : str
        What the structure suggests.
    main_signal : str or None
        What the structure is.
    source : str or None
        Where it was found: "final residual", "round k" (a round's generic competitor) or
        None (nowhere).
    """

    basis: Structure
    tests: dict[str, Structure]
    significant: bool
    gap: float
    structure_rms: float
    per_leg_rms: list[float]
    time_rms: dict[str, float]
    frequency: float
    looks_like: str
    main_signal: str | None
    source: str | None = None

    def to_json(self) -> dict:
        """summary.json's ``lack_of_fit``: the basis's entries, with the combined size, each
        other test's under its name, then the rest."""
        out = self.basis.to_json()
        out.update(significant=self.significant, gap=self.gap,
                   structure_rms=self.structure_rms, per_leg_rms=self.per_leg_rms)
        for name in SUMMARY_ORDER:
            out[name] = self.tests[name].to_json()
        out.update(time_rms=self.time_rms, frequency=self.frequency,
                   looks_like=self.looks_like, main_signal=self.main_signal,
                   source=self.source)
        return out


def lack_of_fit(problem: Problem, theta: np.ndarray, residual: np.ndarray,
                in_model: Sequence[str] = ()) -> LackOfFit:
    """Every test of ``STRUCTURE_TESTS`` on the final residual (M, 6) at theta, and what the
    first that finds structure says of it (``LackOfFit``)."""
    data = FinalResidual.of(problem, theta, residual, in_model)
    results = {test.name: test.run(data) for test in STRUCTURE_TESTS}
    basis = results.pop("basis")
    by = next((test for test in STRUCTURE_TESTS if test.name == "basis" and basis.significant
               or test.name != "basis" and results[test.name].significant), None)
    first = basis if by is None or by.name == "basis" else results[by.name]
    fitted = results["drift"].fitted if by is not None and by.name == "drift" else basis.fitted
    t = data.t
    thirds = np.array_split(np.arange(len(t)), 3)
    time_rms = {f"{t[g[0]]:.4g}-{t[g[-1]]:.4g} s": st.rms(fitted[g]) for g in thirds}
    basis.fitted = results["drift"].fitted = None
    shown = by or STRUCTURE_TESTS[0]
    found = basis if shown.name == "basis" else results[shown.name]
    main_signal, looks_like = shown.words(found)
    return LackOfFit(basis, results, first.significant, first.gap, first.structure_rms,
                     first.per_leg_rms, time_rms, lackfit.dominant_frequency(t, residual),
                     looks_like, main_signal)

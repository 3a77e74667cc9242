"""What the discrepancy workflow found (rounds, findings, the whole result), and summary.json."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from gsfric.discovery.candidates import separating_motion
from gsfric.discovery.dictionary import Unexplained
from gsfric.discovery.final_tests import LackOfFit
from gsfric.discovery.floor import NoiseFloor
from gsfric.discovery.refine import Stability
from gsfric.discovery.regimes import hotspots
from gsfric.discovery.selection import CandidateTest, GenericCompetitor, NoiseModel
from gsfric.discovery.settings import Settings
from gsfric.platform import catalog
from gsfric.platform.description import Platform


@dataclass
class Round:
    """One round: the tests, the winner and its competitors.

    Attributes
    ----------
    index : int
    tests : list[CandidateTest]
    winner : str or None
    indistinguishable : list[str]
        Significant candidates that the data cannot tell apart from the winner.
    bootstrap_share : dict[str, float]
        Share of block-bootstrap draws in which each significant candidate reduced the error
        most.
    level : float
        The per-candidate test level ``alpha / K``.
    noise_model : NoiseModel
        AR orders and lag-one autocorrelations of the residual of each leg.
    rms_before, rms_after : float
        RMS of the residual (N) before and after the round.
    preferred_over : str or None
        The candidate with the largest held-out gain, when a simpler one it cannot be told
        apart from was chosen instead.
    """

    index: int
    tests: list[CandidateTest]
    winner: str | None
    indistinguishable: list[str] = field(default_factory=list)
    bootstrap_share: dict[str, float] = field(default_factory=dict)
    level: float = 0.0
    noise_model: NoiseModel | None = None
    rms_before: float = 0.0
    rms_after: float = 0.0
    preferred_over: str | None = None
    generic: GenericCompetitor | None = None
    """The winner against the generic out-of-model structure (``generic_competitor``)."""
    blocked: str | None = None
    """A winner not named: a generic out-of-catalog structure explains the data better and the
    winner adds nothing to it (``generic.blocked``), or refined on the compiled model it
    does not lower the residual."""
    slow: str | None = None
    """Without a winner: the candidate accepted by every rule but the test on the slowest
    components (``CandidateTest.slow_only``) that a generic out-of-catalog structure explains
    as well or better (``generic`` holds that comparison): not slow noise but a structure."""

    def __repr__(self) -> str:
        what = f"{self.winner} added" if self.winner else "nothing added"
        return (f"<Round {self.index}: {what}, {len(self.tests)} candidates tested, RMS "
                f"{self.rms_before:.4g} -> {self.rms_after:.4g} N>")

    @property
    def imitates(self) -> bool:
        """Whether the generic competitor found that the round's winner only imitates it."""
        return self.generic is not None and self.generic.imitates

    @property
    def blocked_by_generic(self) -> bool:
        """Whether the generic competitor blocked the round's winner (or its slow part)."""
        return self.generic is not None and self.generic.blocked


@dataclass
class RefitTest:
    """Is the refit of the model's own parameters significant (``workflow``)?

    Attributes
    ----------
    p_value : float
        F-test of all the refitted parameters against none, on the prewhitened data.
    p_bands : float
        The same test on the record's slowest components alone or on the rest alone.
    significant : bool
        Both below ``alpha`` (``evidence.accept``).
    """

    p_value: float
    p_bands: float
    significant: bool


@dataclass
class RefitParameter:
    """One of the model's own parameters, refitted.

    Attributes
    ----------
    model : float
        The model's value.
    refit : float
        The value after the refit alone (within the plausible range).
    unbounded : float or None
        The value an unbounded refit would need (None: a parameter of an effect the model
        already has).
    plausible : list of float
        The range ``[lower, upper]`` it is refitted within.
    plausible_refit : bool
        Whether ``unbounded`` lies within it.
    own_effect : bool
        A parameter of an effect the model already has (refitted within its physical bounds).
    alternatives : list of str or None
        Candidates that explain its refitted change as well (None: not tested).
    final : float or None
        The value in the final model.
    interval : (float, float) or None
        Its 95% block-bootstrap interval in the final fit.
    """

    model: float
    refit: float
    unbounded: float | None
    plausible: list[float]
    plausible_refit: bool
    own_effect: bool = False
    alternatives: list[str] | None = None
    final: float | None = None
    interval: tuple[float, float] | None = None

    def to_json(self, name: str = "") -> dict:
        """summary.json's entry (a parameter of an effect gets its refit value last), with
        the unit of parameter ``name`` (``catalog.unit``)."""
        keys = (("model", "unbounded", "plausible", "plausible_refit", "refit")
                if self.own_effect else
                ("model", "refit", "unbounded", "plausible", "plausible_refit"))
        out = {k: getattr(self, k) for k in keys}
        if self.alternatives is not None:
            out["alternatives"] = self.alternatives
        out["final"], out["interval"] = self.final, self.interval
        out["unit"] = catalog.unit(name)
        return out


@dataclass
class RefitReport:
    """The refit of the model's own parameters.

    Attributes
    ----------
    parameters : dict[str, RefitParameter]
        The refitted parameters, the plausible ones (``REFIT``) first.
    implausible : list of str
        Those whose unbounded refit lies outside their plausible range.
    test : RefitTest or None
    """

    parameters: dict[str, RefitParameter] = field(default_factory=dict)
    implausible: list[str] = field(default_factory=list)
    test: RefitTest | None = None

    def to_json(self) -> dict:
        """summary.json's ``refit``."""
        return {"parameters": {n: p.to_json(n) for n, p in self.parameters.items()},
                "implausible": self.implausible,
                "test": dataclasses.asdict(self.test) if self.test is not None else None}


NOISE_METHOD = ("high_frequency: residual of a local cubic fit of each force channel "
                "(robust scale), independent of the model; residual_corrected: final "
                "residual corrected for the parameters fitted")
"""How the noise levels of ``NoiseEstimate`` are measured (summary.json's noise.method)."""


@dataclass
class NoiseEstimate:
    """The noise of the record, as the workflow measured it.

    Attributes
    ----------
    high_frequency : float
        RMS over the legs of ``high_frequency_per_leg``, N.
    high_frequency_per_leg : list of float
        Each force channel's white noise from the channel alone
        (``gsfric.signal.noise.high_frequency_std``),
        N: independent of the model.
    residual_corrected : float
        RMS of the final residual corrected for the parameters fitted, N.
    innovation_std : list of float
        Innovation standard deviation of each leg's AR noise model of the final residual, N.
    method : str
        ``NOISE_METHOD``.
    speed_uncertainty : list of float
        Each leg's standard deviation of the differentiated speed due to pose noise, m/s.
    not_sliding_share : float
        Share of the used (sample, leg) pairs that are not known to slide.
    floor : NoiseFloor or None
        The noise floor the verdict compares the residual with: the force noise (and its
        source: ``specified``, ``noise record`` or ``estimated``) and the pose noise
        propagated into the model's forces. ``high_frequency`` reads the force channels'
        fast changes (friction steps at the reversals, a fast motion) as noise as well; the
        floor's force part does not.
    """

    high_frequency: float
    high_frequency_per_leg: list[float]
    residual_corrected: float
    innovation_std: list[float]
    method: str
    speed_uncertainty: list[float]
    not_sliding_share: float
    floor: NoiseFloor | None = None


@dataclass
class FindingEvidence:
    """Why an effect was named: its test in the round it won, and its size in the final fit.

    Attributes
    ----------
    round : int
        The round it was found in.
    F, p_value : float
        Its nested F-test on the prewhitened data against the refitted model.
    dof : int
        Parameters tested.
    level : float
        The round's per-candidate test level ``alpha / K``.
    cv_gain, fold_share : float
        Held-out gain and share of folds improved (block cross-validation).
    bootstrap_share : float
        Share of block-bootstrap draws it won.
    indistinguishable_from : list of str
        Candidates the data cannot tell it apart from.
    preferred_over : str or None
        The candidate it was preferred over as the simpler explanation.
    p_value_beyond : dict[str, float]
        p-value of it added to each other significant candidate of its round.
    rms_before, rms_after : float
        RMS residual (N) before and after its round.
    signature : str
        Where the effect shows in the residuals.
    stability : Stability or None
        The effect across the halves of the record (``refine.half_stability``).
    effect_size : float
        RMS of its contribution to F over the noise level of the final residual.
    contribution_rms : float
        RMS of its contribution to F, N.
    """

    round: int
    F: float
    p_value: float
    dof: int
    level: float
    cv_gain: float
    fold_share: float
    bootstrap_share: float
    indistinguishable_from: list[str]
    preferred_over: str | None
    p_value_beyond: dict[str, float]
    rms_before: float
    rms_after: float
    signature: str
    stability: Stability | None = None
    effect_size: float = 0.0
    contribution_rms: float = 0.0


@dataclass
class Finding:
    """An effect named by the workflow.

    Attributes
    ----------
    name : str
        Catalog effect name.
    parameters : dict[str, float]
        Fitted values (fixed parameters included).
    interval : dict[str, tuple[float, float]]
        95% block-bootstrap intervals of the fitted parameters.
    evidence : FindingEvidence
        Test statistics, cross-validation, bootstrap share, effect size, the round it was found
        in, the candidates it cannot be told apart from, where it shows.
    """

    name: str
    parameters: dict[str, float]
    interval: dict[str, tuple[float, float]]
    evidence: FindingEvidence

    def __repr__(self) -> str:
        values = ", ".join(f"{k} = {catalog.with_unit(v, catalog.unit(f'{self.name}.{k}'))}"
                           for k, v in self.parameters.items())
        return (f"<Finding {self.name} ({values}): round {self.evidence.round}, effect size "
                f"{self.evidence.effect_size:.3g} x noise>")


@dataclass
class Discovery:
    """Everything the workflow found.

    Attributes
    ----------
    effects : list[Finding]
        Effects named, in the order found (empty: nothing significant is missing).
    refit : RefitReport
        The model's own parameters: model value, refitted value, plausible range, the value an
        unbounded refit would need, and alternative explanations.
    rounds : list[Round]
    rms_before, rms_refit, rms_after : float
        RMS residual (N, all legs, trimmed samples) of the model as given, after the refit
        alone, and of the final model.
    noise_rms_estimate : float
        RMS of the final residual corrected for the parameters fitted: the noise level, if the
        final model is right.
    t : ndarray, shape (M,)
        Times of the samples used, s.
    residual_before, residual_after : ndarray, shape (M, 6)
        Residuals of the model as given and of the final model, N.
    used : slice
        The samples used, of the data's N.
    model : Platform
        The model as given.
    platform : Platform
        The final model: refitted parameters, named effects switched on.
    result_before : gsfric.Result
        Full evaluation of the given model over the used samples (speeds, lengths, loads).
    noise_model : NoiseModel
        AR model of the final residual.
    regimes : list of Band
        The residual before and after per band of speed, load, stroke, pose and time.
    settings : Settings
    evaluations : int
        Calls of the compiled model.
    notes : list[str]
        Remarks for the report (implausible refits, flagged steps, ...).
    verdict : str
        ``explained``, ``no_discrepancy`` or ``unexplained_discrepancy``.
    lack_of_fit : LackOfFit
        The lack-of-fit tests of the final residual (``final_tests.lack_of_fit``).
    noise : NoiseEstimate
    rms_after_all : float
        RMS residual (N) of the final model over every used pair, sliding or not.
    sliding : ndarray of bool, shape (M, 6)
        The (sample, leg) pairs known to slide.
    structures : list of Unexplained
        The generic dictionary's structures found in the final residual
        (``dictionary.find``).
    verdict_reason : str
        Why the verdict (``verdict.decide``): the evidence that decided, and the residual
        against the noise floor.
    verdict_decided_by : str
        ``dictionary``, ``lack of fit``, ``floor``, ``effects``, ``refit`` or ``none``.

    Examples
    --------
    >>> result = gsfric.discover("measured.csv", out="out")         # doctest: +SKIP
    >>> result                                                      # doctest: +SKIP
    <Discovery explained: stribeck (static = 2 N, velocity = 0.00998 m/s) ...>
    >>> print(result.summary()["answer"])                           # doctest: +SKIP
    """

    effects: list[Finding]
    refit: RefitReport
    rounds: list[Round]
    rms_before: float
    rms_refit: float
    rms_after: float
    noise_rms_estimate: float
    t: np.ndarray
    residual_before: np.ndarray
    residual_after: np.ndarray
    used: slice
    model: Platform
    platform: Platform
    result_before: object
    noise_model: NoiseModel
    regimes: list = field(default_factory=list)
    settings: Settings = field(default_factory=Settings)
    evaluations: int = 0
    notes: list[str] = field(default_factory=list)
    verdict: str = "no_discrepancy"
    lack_of_fit: LackOfFit | None = None
    noise: NoiseEstimate | None = None
    rms_after_all: float = 0.0
    sliding: np.ndarray | None = None
    structures: list[Unexplained] = field(default_factory=list)
    verdict_reason: str = ""
    verdict_decided_by: str = ""

    @property
    def names(self) -> list[str]:
        """Names of the effects found."""
        return [f.name for f in self.effects]

    def __repr__(self) -> str:
        n = self.used.stop - self.used.start
        effects = ", ".join(self.names) or "no effect named"
        return (f"<Discovery {self.verdict}: {effects}; residual {self.rms_before:.4g} N -> "
                f"{self.rms_after:.4g} N RMS over {n} samples, {len(self.rounds)} rounds; "
                "summary() for summary.json's content>")

    def summary(self) -> dict:
        """The summary.json content (SPEC), plus the refit, rounds and per-leg gaps."""
        return summary(self)


# -- summary.json ------------------------------------------------------------------------------


def _clean(value):
    """JSON-safe copy: NumPy scalars to Python, non-finite floats to None, tuples to lists."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def _asdict(value) -> dict:
    """A dataclass's fields as a dict ({} for None)."""
    return dataclasses.asdict(value) if value is not None else {}


def per_leg_rms(r: np.ndarray) -> list[float]:
    """RMS of each leg's residual (6,), N, of r (M, 6)."""
    return [float(v) for v in np.sqrt(np.mean(r ** 2, axis=0))]


def summary(d: Discovery) -> dict:
    """The content of summary.json (SPEC), plus the refit, rounds and per-leg gaps."""
    n = d.used.stop - d.used.start
    duration = float(d.t[-1] - d.t[0]) if len(d.t) > 1 else 0.0
    s = d.settings
    lof = d.lack_of_fit
    out = {
        "verdict": d.verdict,
        "verdict_reason": d.verdict_reason,
        "verdict_decided_by": d.verdict_decided_by,
        "unexplained": _unexplained(d, lof),
        "lack_of_fit": lof.to_json(),
        "noise": _asdict(d.noise),
        "rms_after_all_samples": d.rms_after_all,
        "effects": _effects(d),
        "rms_before": d.rms_before,
        "rms_after": d.rms_after,
        "noise_rms_estimate": d.noise_rms_estimate,
        "rms_after_refit": d.rms_refit,
        "per_leg": {"rms_before": per_leg_rms(d.residual_before),
                    "rms_after": per_leg_rms(d.residual_after)},
        "refit": d.refit.to_json(),
        "ambiguous": _ambiguous(d),
        "rounds": _rounds(d),
        "regimes": [vars(b) for b in d.regimes],
        "hotspots": [f"{b.regime}: {b.name}" for b in hotspots(d.regimes)],
        "noise_model": dataclasses.asdict(d.noise_model),
        "data": {"samples_used": n, "first_used": d.used.start,
                 "duration": duration, "rate": (n - 1) / duration if duration > 0 else None},
        "settings": {"alpha": s.alpha, "min_fold_share": s.min_fold_share,
                     "min_gap": s.min_gap, "n_blocks": s.n_blocks, "n_folds": s.n_folds,
                     "n_bootstrap": s.n_bootstrap, "candidates": list(s.candidates),
                     "refit": list(s.refit), "floor_ratio": s.floor_ratio,
                     "dictionary_min_gap": s.dictionary_min_gap},
        "notes": d.notes,
        "evaluations": d.evaluations,
    }
    return _clean(out)


def _effects(d: Discovery) -> list[dict]:
    """summary.json's ``effects``: each named effect's parameters and evidence."""
    effects = []
    for f in d.effects:
        evidence = dataclasses.asdict(f.evidence)
        evidence["interval_95"] = {k: list(v) for k, v in f.interval.items()}
        # with structure left that the catalog does not explain, a named effect is the best
        # candidate for a part of the gap, not a confident explanation of it
        effects.append({"name": f.name, "parameters": dict(f.parameters),
                        "units": {k: catalog.unit(f"{f.name}.{k}") for k in f.parameters},
                        "partial": d.verdict == "unexplained_discrepancy",
                        "evidence": evidence})
    return effects


def _ambiguous(d: Discovery) -> list[dict]:
    """summary.json's ``ambiguous``: the winners the data cannot tell from other candidates,
    and the refitted changes that a candidate explains as well."""
    ambiguous = []
    for rnd in d.rounds:
        if rnd.winner and rnd.indistinguishable:
            why = ("the simpler explanation" if rnd.preferred_over
                   else "the largest held-out gain")
            ambiguous.append({
                "round": rnd.index, "effects": [rnd.winner] + list(rnd.indistinguishable),
                "indistinguishable": True, "chosen": rnd.winner,
                "separating_motion": [separating_motion(rnd.winner, o)
                                      for o in rnd.indistinguishable],
                "message": f"the data cannot tell {rnd.winner} apart from "
                           f"{', '.join(rnd.indistinguishable)}: either explains the same "
                           f"part of the gap; {rnd.winner} was added ({why})"})
    for name, entry in d.refit.parameters.items():
        for alt in entry.alternatives or []:
            ambiguous.append({"round": 0, "effects": [f"refit:{name}", alt],
                              "message": f"the change of {name} could equally be {alt}"})
    return ambiguous


def _rounds(d: Discovery) -> list[dict]:
    """summary.json's ``rounds``: each round's tests and decision."""
    rounds = []
    for rnd in d.rounds:
        rounds.append({
            "round": rnd.index, "winner": rnd.winner, "level": rnd.level,
            "indistinguishable": rnd.indistinguishable,
            "bootstrap_share": rnd.bootstrap_share, "noise_model": _asdict(rnd.noise_model),
            "rms_before": rnd.rms_before, "rms_after": rnd.rms_after,
            "generic": _asdict(rnd.generic),
            "blocked": rnd.blocked, "slow": rnd.slow,
            "tests": [{"name": t.name, "F": t.F, "p_value": t.p_value, "dof": t.dof,
                       "cv_gain": t.cv_gain, "fold_share": t.fold_share,
                       "sse_gain": t.sse_gain, "gap": t.gap, "p_bands": t.p_bands,
                       "significant": t.significant, "slow_only": t.slow_only,
                       "reason": t.reason, "parameters": t.parameters,
                       "units": {k: catalog.unit(f"{t.name}.{k}") for k in t.parameters}}
                      for t in rnd.tests]})
    return rounds


def _unexplained(d: Discovery, lof: LackOfFit) -> dict | None:
    """summary.json's ``unexplained``: the structure left, for an ``unexplained_discrepancy``."""
    unexplained = None
    if d.verdict == "unexplained_discrepancy":
        unexplained = {
            "size_rms": lof.structure_rms, "size_over_noise": lof.gap,
            "per_leg_rms": lof.per_leg_rms, "time_rms": lof.time_rms,
            "dominant_frequency": lof.frequency, "main_signal": lof.main_signal,
            "looks_like": lof.looks_like,
            "partial_effects": [f.name for f in d.effects],
            "speed_bands": {b.name: b.rms_after for b in d.regimes if b.regime == "speed"},
            "source": lof.source,
            "message": _unexplained_message(lof),
            "structures": [dataclasses.asdict(s) for s in d.structures],
            "decided_by": d.verdict_decided_by}
        if d.verdict_decided_by in ("dictionary", "floor"):
            unexplained["message"] = (
                "the catalog does not explain the data: "
                + ("; ".join(s.description for s in d.structures) if d.structures
                   else d.verdict_reason))
    return unexplained


def _unexplained_message(lof: LackOfFit) -> str:
    """One sentence on an ``unexplained_discrepancy``: the structure left in the final
    residual, or the round whose generic competitor found it (``lof.source``)."""
    source = lof.source or "final residual"
    if source == "final residual":
        return ("the catalog does not explain the data: a structured residual of "
                f"{lof.structure_rms:.4g} N RMS remains, {lof.looks_like}")
    return (f"the catalog does not explain the data: in {source}, a generic structure outside "
            f"the catalog ({lof.main_signal}) explains the gap as well as the catalog's "
            f"best candidate or better, {lof.looks_like}")

"""What the discrepancy workflow found: rounds, findings and the fields of the whole result
(``DiscoveryRecord``; ``gsfric.discovery.outcome.Discovery`` adds its summary and report)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gsfric.discovery.dictionary import Unexplained
from gsfric.discovery.final_tests import LackOfFit
from gsfric.discovery.floor import NoiseFloor
from gsfric.discovery.refine import Stability
from gsfric.discovery.selection import CandidateTest, GenericCompetitor, NoiseModel
from gsfric.discovery.settings import Settings
from gsfric.platform import catalog
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion


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
    contribution : ndarray, shape (M, 6), or None
        Its contribution to each leg's F at the used samples, N: F of the final model minus
        F of the final model with this effect switched off.
    """

    name: str
    parameters: dict[str, float]
    interval: dict[str, tuple[float, float]]
    evidence: FindingEvidence
    contribution: np.ndarray | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        values = ", ".join(f"{k} = {catalog.with_unit(v, catalog.unit(f'{self.name}.{k}'))}"
                           for k, v in self.parameters.items())
        return (f"<Finding {self.name} ({values}): round {self.evidence.round}, effect size "
                f"{self.evidence.effect_size:.3g} x noise>")


@dataclass
class DiscoveryRecord:
    """Everything the workflow found: the fields of a ``gsfric.Discovery`` (documented there),
    which adds its summary and report.
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
    source: str = ""
    platform_source: str = ""
    forces: np.ndarray | None = field(default=None, repr=False)
    forces_after: np.ndarray | None = field(default=None, repr=False)
    motion: Motion | None = field(default=None, repr=False)
    written: list[Path] = field(default_factory=list)

    @property
    def names(self) -> list[str]:
        """Names of the effects found."""
        return [f.name for f in self.effects]

    def __repr__(self) -> str:
        n = self.used.stop - self.used.start
        effects = ", ".join(self.names) or "no effect named"
        return (f"<Discovery {self.verdict}: {effects}; residual {self.rms_before:.4g} N -> "
                f"{self.rms_after:.4g} N RMS over {n} samples, {len(self.rounds)} rounds; "
                "summary() and report() for summary.json's and report.md's content>")

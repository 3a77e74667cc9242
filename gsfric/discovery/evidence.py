"""The one acceptance rule of the workflow (is what a test measured enough to count?), and the
one result type of the lack-of-fit tests (``Structure``).

Every decision of ``gsfric discover`` that accepts an explanation of the gap (a candidate
effect in a round, the refit of the model's own parameters, the generic basis of the
lack-of-fit test and its competitor of a round's winner, the structure tests of the final
residual) asks the same questions of what its test measured (``Evidence``), each against its
own bound (``Rule``), in this order:

1. ``p_value`` below the level (an F-test, or the test of its kind);
2. ``p_bands`` below the same level (the same test on the record's slowest components alone
   or on the rest alone, ``statistics.band_p_value``: slow noise is not a structure);
3. ``cv_gain`` above ``min_cv_gain`` (the held-out error of the block cross-validation falls);
4. ``fold_share`` at least ``min_fold_share`` (it falls in most folds: a stable effect);
5. ``gap`` at least ``min_gap`` (the part of the residual it explains, over the RMS left).

A rule leaves out a question by leaving its bound None; evidence by leaving its number None.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Evidence:
    """What one test measured of one explanation of the gap.

    Attributes
    ----------
    p_value : float or None
        p-value of the test; None: a test without one (a held-out gap alone).
    p_bands : float or None
        p-value of the same test on the slowest components alone or on the rest alone (the
        smaller, times two); None: not tested.
    cv_gain : float or None
        Relative fall of the held-out squared error (block cross-validation); None: not
        cross-validated.
    fold_share : float or None
        Share of the folds in which the held-out error fell; None: not counted.
    gap : float or None
        RMS of what the explanation fits over the RMS of the residual left (1: as large as the
        noise); None: not measured.
    """

    p_value: float | None = None
    p_bands: float | None = None
    cv_gain: float | None = None
    fold_share: float | None = None
    gap: float | None = None


@dataclass(frozen=True)
class Rule:
    """The bounds that evidence must pass (None: the question is not asked).

    Attributes
    ----------
    level : float or None
        ``p_value`` and ``p_bands`` must lie below it.
    min_gap : float or None
        Smallest ``gap``.
    min_cv_gain : float or None
        ``cv_gain`` must exceed it (strictly).
    min_fold_share : float or None
        Smallest ``fold_share``.
    """

    level: float | None = None
    min_gap: float | None = None
    min_cv_gain: float | None = None
    min_fold_share: float | None = None


def failures(evidence: Evidence, rule: Rule) -> list[str]:
    """The criteria (``CRITERIA``, in order) that the evidence fails under the rule."""
    e, out = evidence, []
    if e.p_value is not None and rule.level is not None and not e.p_value < rule.level:
        out.append("p_value")
    if e.p_bands is not None and rule.level is not None and not e.p_bands < rule.level:
        out.append("p_bands")
    if e.cv_gain is not None and rule.min_cv_gain is not None and not e.cv_gain > rule.min_cv_gain:
        out.append("cv_gain")
    if (e.fold_share is not None and rule.min_fold_share is not None
            and not e.fold_share >= rule.min_fold_share):
        out.append("fold_share")
    if e.gap is not None and rule.min_gap is not None and not e.gap >= rule.min_gap:
        out.append("gap")
    return out


def accept(evidence: Evidence, rule: Rule) -> bool:
    """Whether the evidence passes every question of the rule."""
    return not failures(evidence, rule)


@dataclass
class Structure:
    """What one lack-of-fit test found in a residual (every such test returns one).

    Attributes
    ----------
    significant : bool
        Whether the test accepts the structure (``accept``).
    gap : float
        The structure's RMS over the RMS of the residual left (1: as large as the noise).
    structure_rms : float
        RMS of the structure, N.
    per_leg_rms : list of float
        RMS of the structure on each leg, N.
    p_value : float or None
        p-value of the test (None: a test without one).
    details : dict
        The test's own numbers, by name (documented by each test), as summary.json has them.
    fitted : ndarray, shape (M, 6), or None
        The fitted structure, N, where a test has one (not written to summary.json).
    keys : tuple of str
        The order of the entries in summary.json, where a test's differs from the common
        numbers followed by ``details``.
    """

    significant: bool
    gap: float
    structure_rms: float
    per_leg_rms: list[float]
    p_value: float | None = None
    details: dict = field(default_factory=dict)
    fitted: np.ndarray | None = None
    keys: tuple[str, ...] = ()

    def to_json(self) -> dict:
        """summary.json's entry: the common numbers, then ``details`` (in the order ``keys``)."""
        out: dict = {"significant": self.significant}
        if self.p_value is not None:
            out["p_value"] = self.p_value
        out.update(gap=self.gap, structure_rms=self.structure_rms,
                   per_leg_rms=self.per_leg_rms)
        out.update(self.details)
        return {k: out[k] for k in self.keys} if self.keys else out

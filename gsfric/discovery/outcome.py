"""The result of ``gsfric.discover``: the fields the workflow found (``DiscoveryRecord``) with
their summary (summary.json's content) and report (report.md's text)."""

from __future__ import annotations

from gsfric.discovery import markdown
from gsfric.discovery.results import DiscoveryRecord
from gsfric.discovery.summary import summary


class Discovery(DiscoveryRecord):
    """Everything the workflow found, its summary and report.

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
    source : str
        The measured-data file ("" for data given as arrays or a DataFrame).
    platform_source : str
        The platform file of the model as given ("": a Platform or the reference platform).
    forces : ndarray, shape (M, 6), or None
        The measured forces F1..F6 at the used samples, N.
    forces_after : ndarray, shape (M, 6), or None
        F of the final model at the used samples, N (``forces - forces_after`` is the final
        residual at every sample, sliding or not; ``result_before.F[used]`` is the model's as
        given).
    motion : Motion or None
        The measured motion, all N samples (``used`` selects those fitted).
    written : list of Path
        The files ``gsfric.discover(..., out=...)`` wrote (empty without ``out``).

    Examples
    --------
    A record of 6 s with a hidden seal friction of 2 N, two candidates tested:

    >>> from gsfric.synth import synthesize
    >>> record = synthesize(effects=["seal_friction:force=2"], samples=1200, seed=1)
    >>> result = gsfric.discover(record.frame, candidates=["seal_friction", "sensor_bias"],
    ...                          n_bootstrap=20)
    >>> result
    <Discovery explained: seal_friction; residual ... N RMS over 1080 samples, 2 rounds; ...>
    >>> print(result.summary()["answer"])
    explained: seal_friction (force = 2 N) closes ... of the gap; residual ... vs noise floor ...
    >>> print(result.report().splitlines()[0])
    # Discrepancy discovery
    """

    def summary(self) -> dict:
        """summary.json's content (``summary.summary``): SPEC's entries, the refit, rounds,
        per-leg gaps and the answer in one line (``answer``)."""
        return summary(self)

    def report(self, figures: bool = True) -> str:
        """report.md's text (``markdown.report``): the result for a reader, in Markdown;
        ``figures``: with the list of the plots that ``discover`` writes beside it (False:
        as ``--no-plots`` writes it)."""
        return markdown.report(self, figures)

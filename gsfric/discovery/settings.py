"""Settings of the discrepancy workflow (its own module: every other module may import it)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from gsfric.discovery.candidates import CANDIDATE_NAMES, REFIT

DEFAULT_TRIM = 100
"""Samples left out at each end of the record by default (a twentieth of it when that is
fewer): there the motion's filters fit one polynomial to the first or last window instead of
centring one on each sample. Half the longest filter window was the default while that was
201 samples; at 1601 it would leave out a tenth of a record of 8000 samples."""


@dataclass(frozen=True)
class Settings:
    """Settings of the workflow.

    Attributes
    ----------
    alpha : float
        Family-wise level of each round's tests (Bonferroni over the candidates).
    max_effects : int
        Most effects added.
    n_blocks : int
        Contiguous blocks, each holding an equal share of the used (sample, leg) pairs (the
        generic basis of the lack-of-fit test: of equal length): the unit of cross-validation
        folds and bootstrap draws.
    n_folds : int
        Cross-validation folds (contiguous groups of blocks).
    min_fold_share : float
        Share of folds in which a candidate must lower the held-out error.
    min_gap : float
        Smallest gap a candidate must close beyond the refitted model: the RMS change of the
        fitted residual, as a multiple of the RMS of the residual left (the noise level).
    n_bootstrap : int
        Block-bootstrap draws of the parameter intervals (half as many for the share of draws
        each accepted candidate wins).
    trim : int or None
        Samples left out at each end (None: ``min(DEFAULT_TRIM, N // 20)``).
    candidates : tuple of str
        Candidate effects tested (default: the whole catalog).
    refit : tuple of str
        Model parameters refitted (see ``candidates.REFIT``).
    plausible : mapping or None
        Plausible ranges ``{name: (lower, upper)}`` replacing the defaults of ``REFIT``.
    gauss_newton : int
        Most Gauss-Newton iterations of a refinement.
    n_threads : int
        Threads of the compiled evaluation (0: every core).
    """

    alpha: float = 0.01
    max_effects: int = 4
    n_blocks: int = 40
    n_folds: int = 8
    min_fold_share: float = 0.75
    min_gap: float = 0.3
    n_bootstrap: int = 200
    trim: int | None = None
    candidates: tuple[str, ...] = CANDIDATE_NAMES
    refit: tuple[str, ...] = tuple(r.name for r in REFIT)
    plausible: Mapping[str, tuple[float, float]] | None = None
    gauss_newton: int = 4
    n_threads: int = 0

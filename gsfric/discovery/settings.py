"""Settings of the discrepancy workflow: every setting and numeric threshold in one place (its
own module: every other module may import it)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from gsfric.discovery.candidates import CANDIDATE_NAMES, REFIT
from gsfric.platform.usable import HELD_RUN
from gsfric.signal.noise import HIGH_FREQUENCY_WINDOW, PLAUSIBLE_SPREAD


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
        Samples left out at each end (None: ``min(default_trim, N // 20)``).
    candidates : tuple of str
        Candidate effects tested (default: the whole catalog).
    refit : tuple of str
        Model parameters refitted (see ``candidates.REFIT``).
    plausible : mapping or None
        Plausible ranges ``{name: (lower, upper)}`` replacing the defaults of ``REFIT``.
    gauss_newton : int
        Most evaluations of the model's forces in a refinement (the trust-region
        Gauss-Newton of ``evaluation.fitting.fit``; 0 keeps the start). Near its solution a
        refinement meets its cost tolerance in a few; a Stribeck peak refined from its
        secant's start takes about a dozen; more than 30 means the model does not describe
        the data.
    n_threads : int
        Threads of the compiled evaluation (0: every core).

    The thresholds below (one line each on why) are fixed by the documented calibrations
    (docs/explanation/discovery.md); change them only with the calibration.
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
    gauss_newton: int = 30
    n_threads: int = 0

    # -- the data ------------------------------------------------------------------------
    default_trim: int = 100
    """Samples left out at each end by default (a twentieth of the record when fewer): there
    the motion's filters fit one polynomial to the first or last window instead of centring
    one on each sample (at the longest window, 1601, half of it would leave out a tenth of a
    record of 8000 samples)."""
    held_run: int = HELD_RUN
    """Consecutive equal values of a force channel that make a dropout
    (``gsfric.platform.usable.data_problems``; default ``HELD_RUN``, identify's too)."""
    noise_window: int = HIGH_FREQUENCY_WINDOW
    """Window (samples) of the local cubic fit whose residual measures the force noise
    (``gsfric.signal.noise.high_frequency_std``; default ``HIGH_FREQUENCY_WINDOW``)."""

    # -- the load cells' noise as the user gives it ----------------------------------------
    record_travel: float = 1e-3
    """Largest travel (m) of the platform frame's origin, from its first sample, in a noise
    record (``--noise-record``) with pose columns: a record at rest. A rig's encoders and a
    motion-capture system are noisy to micrometres, at most a tenth of a millimetre; a move
    beyond a millimetre changes the forces (inertia, friction, the weight's share per leg)
    and its spread is no longer the load cells' noise (``floor.check_at_rest``)."""
    record_turn: float = 1e-3
    """Largest rotation (rad) of the platform from its first sample in a noise record: the
    angular ``record_travel`` (1 mm at a 1 m lever)."""
    noise_spread: tuple[float, float] = PLAUSIBLE_SPREAD
    """A given force noise (``--force-noise``, a noise record's, a column map's) must lie
    within these multiples of each measured force channel's standard deviation
    (``ForceNoise.check_plausible``; why: ``gsfric.signal.noise.PLAUSIBLE_SPREAD``)."""

    # -- rests and the speed band ------------------------------------------------------------
    rest_band: float = 5.0
    """Half-width of the not-sliding band, in standard deviations of the speed estimate: a
    speed within it may be noise around a rest (``rest.sliding_mask``)."""
    move_to_noise: float = 20.0
    """A recorded channel moves when its range exceeds this many times its white noise
    (``rest.moves``): a channel held fixed mixes no rest with a move, whatever its window."""
    spline_noise_draws: int = 8
    """Unit white-noise records through which the smoothing spline's velocity noise gain is
    measured on a non-uniform time base (``rest.spline_differentiator``): enough for a gain
    averaged over 51 samples."""

    # -- the candidates and their fit ---------------------------------------------------------
    stribeck_quantile: float = 0.9
    """Quantile of the sliding leg speeds above which the Stribeck velocity is not fitted: a
    Stribeck decay above nearly every sliding speed is a speed-independent friction
    (``seal_friction`` by another name), and noise would choose the two-parameter name
    (``candidates.stribeck_velocity_bound``)."""
    secant_rounding: float = 1e-9
    """Relative size (to the force) below which a secant column's force difference is
    rounding of two evaluations of the compiled model (``residuals.secant``): such a column
    would be fitted with an arbitrary, huge coefficient."""
    delay_range: float = 0.5
    """Half-width (s) of the delays the profile of ``refine.delay_profile`` searches: the
    largest plausible delay between the pose and force channels of a rig."""
    delay_grid: int = 200
    """Steps of the delay profile's coarse grid over +-``delay_range`` (never finer than one
    sample): fine enough that the bounded search from its best point finds the valley."""
    stability_min_change: float = 0.3
    """Smallest change of an effect's contribution between the halves of the record, relative
    to the residual left, that makes it unstable with a Wald test p < alpha
    (``refine.half_stability``): the size of ``min_gap``."""

    # -- the statistics ----------------------------------------------------------------------
    max_order: int = 12
    """Largest AR order of the noise model (``statistics.Whitener``): enough for the coloured
    noise of the calibration records, few enough to leave the structure to the tests."""
    low_band: int = 3
    """The record's slowest components per leg (cosines: the mean and the periods of twice the
    record's length and of its length, ``statistics.low_band``) on which every F-test must
    also hold, the noise measured there alone: the wander of slow noise lives there."""
    ridge: float = 1e-10
    """Ridge added to the scaled normal equations (``statistics.solve``): keeps a column that
    the others nearly span from taking an arbitrary coefficient, far below any real signal."""

    # -- the lack-of-fit tests of the final residual -----------------------------------------
    state_bins: int = 24
    """Bins per state variable and leg in ``structure.state_structure`` (quantiles of the used
    samples): fine enough for a screw's ripple, with enough pairs per bin and fold."""
    dynamic_order: int = 6
    """Lagged residuals per leg in ``structure.dynamic_structure``: the noise's own past."""
    dynamic_lags: int = 4
    """Current and lagged samples of each input in ``structure.dynamic_structure`` (lags
    0..dynamic_lags): a delay or a filter of a few samples."""
    dynamic_min_gap: float = 0.5
    """Smallest input-driven part, relative to the RMS left, that counts (at least
    ``min_gap``): a motion differentiated from noisy poses leaves up to 0.31 times the noise
    that follows the accelerations (``benchmarks/discovery_rates.py``); a resonance or a
    delay of the size of the noise is above 0.6."""
    travel_edges: tuple[float, ...] = tuple(float(v) for v in np.geomspace(2e-5, 1e-2, 10))
    """Edges (m) of the bins of travel since a reversal in ``structure.reversal_structure``:
    geometric, from 20 um (the smallest play or pre-sliding length resolved at the pose noise
    of a rig) to 10 mm; longer travels form the reference bin, where the sliding law holds."""
    rest_min_run: int = 48
    """Shortest rest core (samples) that ``transients.rest_runs`` keeps: three windows of 16
    samples (the mean square of fewer lagged differences is too uncertain to compare)."""
    rest_min_rests: int = 6
    """Fewest rests that ``transients.rest_transients`` tests: a t-test on fewer group means
    rests on too few numbers to trust its tail."""
    rest_window: float = 1 / 3
    """Share of each rest core compared at its start and at its end
    (``transients.rest_transients``)."""
    rest_lags: tuple[int, ...] = (1, 4, 16)
    """Lags (samples) of the differences whose energy ``transients.rest_transients`` compares:
    fast and slow transients."""

    # -- the dictionary of out-of-catalog structure and the noise floor ----------------------
    dictionary_min_gap: float = 0.5
    """Smallest part of the final residual, relative to the RMS it leaves, that a group of the
    dictionary must explain (``dictionary.find``): as ``dynamic_min_gap``, above what a motion
    differentiated from noisy poses leaves that follows the motion (up to 0.31 times the
    noise), below an out-of-catalog structure at twice the noise."""
    dictionary_lines: int = 3
    """Spectral peaks of the residual tested as lines (``dictionary.line_frequencies``): mains,
    its harmonic and one more source; a peak not there is not fitted."""
    line_prominence: float = 30.0
    """A peak is a line candidate when its power (legs summed) is this many times the median
    power around it: the sum of six legs' white periodograms exceeds 30 times its median with
    a probability below 1e-20 per ordinate; a line of a tenth of the noise over a record of
    6000 samples stands 75 times above it."""
    memory_widths: tuple[float, ...] = (0.1, 0.2, 0.4, 0.8, 1.6, 3.2)
    """Widths of the dead bands (play) that the sensor-memory group tries per leg, in
    multiples of the leg's residual RMS (the one that correlates best with the residual is
    its column): a dead band's error is about its width, so from a tenth of the residual
    (the sign of the force's rate of change) to three times it (a play that the force
    seldom crosses)."""
    drift_pieces: int = 4
    """Equal stretches of the record whose levels the drift group fits beside its cubic in
    time: a step of the zero between them (a knock, a re-zeroing)."""
    floor_ratio: float = 2.0
    """The residual's RMS over the noise floor (force noise and propagated pose noise) above
    which ``no_discrepancy`` needs a stated reason, and which, with a floor the user gave
    (a specification, a recording at rest), is a discrepancy: a model right to within the
    noise leaves about one floor; twice it is a part of the size of the noise unexplained."""
    floor_segment: int = 32
    """Samples per segment of the force floor's spectral estimate
    (``gsfric.signal.noise.spectral_noise_std``): short enough that the friction steps at the
    reversals of a motion touch fewer than half of the segments, long enough for eight
    frequencies above a quarter of the sample rate."""
    floor_draws: int = 2
    """Draws of pose noise through the differentiating filters and the model
    (``floor.pose_noise_forces``): each gives a per-leg RMS over thousands of pairs."""

    # -- the regimes of the report ------------------------------------------------------------
    reversal_quantile: float = 0.05
    """Speeds below this quantile of all legs' speeds form the ``reversal`` band of the
    regimes (``regimes.bands``): the neighbourhood of each velocity reversal."""
    reversal_min_speed: float = 1e-3
    """Smallest upper edge of the ``reversal`` band, m/s (``regimes.bands``)."""
    time_stretches: int = 5
    """Equal stretches of the record in the ``time`` regime (``regimes.bands``)."""

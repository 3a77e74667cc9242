"""The discrepancy workflow: refit the model, test the candidate effects, add the winner, repeat.

Steps (docs/explanation/discovery.md explains each decision):

1. Simulate the measured motion with the current model; residuals ``r = F_measured - F_model``
   per leg. The first and last ``trim`` samples, where the differentiation of the recorded pose
   is least accurate, are left out of every fit and statistic.
2. Refit the model's own parameters (``REFIT``: prismatic friction coefficients, payload mass,
   plus the parameters of any effect the model already has) within their plausible ranges. A
   refit that would need an implausible value is reported as such; it is held at the range's
   edge and the rest of the gap is left to the candidates.
3. Round after round: linearise the model at the current parameters (compiled Jacobian),
   prewhiten with an AR model of the residual, and test every candidate effect against the
   refitted model with (a) a nested F-test on the prewhitened data at level ``alpha / K`` (K
   candidates: Bonferroni), (b) block cross-validation: the held-out prewhitened error must
   shrink, in total and in most folds, and (c) the gap it closes must reach ``min_gap`` times
   the noise level. The accepted candidate with the largest held-out gain wins; accepted
   candidates to which the winner adds nothing significant are reported as "cannot be told
   apart". The AR model is re-estimated from the winner's residual and the round repeated
   until the winner is stable (Cochrane-Orcutt).
4. Refine the winner and the refitted parameters by Gauss-Newton on the compiled model, add
   the winner, and start the next round; stop when no candidate is significant.
5. Block bootstrap of the final fit: how often each effect wins, and parameter intervals.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np
from tqdm import tqdm

from gsfric._checks import short
from gsfric._threads import one_blas_thread
from gsfric.discovery.conclusion import Given, conclude
from gsfric.discovery.outcome import Discovery
from gsfric.discovery.refit import refit_own_parameters
from gsfric.discovery.residuals import Problem, checked_forces
from gsfric.discovery.rounds import run_rounds
from gsfric.discovery.settings import Settings
from gsfric.errors import InputTypeError
from gsfric.evaluation.flags import check_flagged, flag_counts
from gsfric.models import check_measured_forces, platform_from
from gsfric.platform.description import Platform
from gsfric.platform.usable import check_poses
from gsfric.signal.noise import ForceNoise
from gsfric.trajectory import Motion


@one_blas_thread
def discover_motion(motion: Motion, forces: np.ndarray, platform: Platform | None = None, *,
                    settings: Settings | None = None, seed: int = 0, progress: bool = False,
                    poses: tuple[np.ndarray, np.ndarray] | None = None,
                    force_noise: ForceNoise | None = None, **options) -> Discovery:
    """Find which effects the model misses, fit them, and measure how much of the gap closes.

    Parameters
    ----------
    motion : Motion
        The measured motion (N steps), e.g. from ``gsfric.io.read_measured``.
    forces : ndarray, shape (N, 6)
        Measured actuator forces F1..F6, N (friction included).
    platform : Platform, optional
        The current model (default: ``gsfric.models.platform_from(None)``).
    settings : Settings, optional
    seed : int
        Seed of the block bootstrap.
    progress : bool
        Show progress on stderr.
    poses : (ndarray (N, 3), ndarray (N, 3, 3)), optional
        The recorded (unsmoothed) positions (m) and rotations, from which the pose noise and
        the uncertainty of the leg speeds are estimated (``rest.speed_uncertainty``; see
        ``rest.poses_from_columns``). Default: the samples the motion was made from
        (``Motion.recorded_poses``), else its smoothed poses, which underestimate it.
    force_noise : ForceNoise, optional
        The load cells' noise as the user gives it (a specification, a recording at rest):
        the force part of the noise floor the verdict compares the residual with
        (``floor``); default: estimated from the force channels.
    **options
        Fields of ``Settings`` overriding ``settings``.

    Returns
    -------
    Discovery

    Raises
    ------
    InputTypeError
        ``motion`` not a Motion, ``platform`` not a Platform, path or None, an unknown option.
    InputError
        ``forces`` of the wrong shape or type, mostly unusable data (NaN, dead or saturated
        channels), a bad setting; each in one line.
    """
    _check_call(motion, options)
    settings = dataclasses.replace(settings or Settings(), **options)
    given = Given(force_noise, seed,
                  str(platform) if isinstance(platform, (str, os.PathLike)) else "")
    platform = platform_from(platform)
    forces = _checked_data(motion, forces, platform, poses, force_noise, settings)
    bar = _Progress(progress, settings.max_effects + 3)
    bar.step("simulating the model along the measured motion")
    problem = _problem(motion, forces, platform, settings, poses)
    rng, theta0 = np.random.default_rng(seed), problem.model.theta0.copy()
    bar.step("refitting the model's own parameters")
    refit = refit_own_parameters(problem, theta0)
    found = run_rounds(problem, refit.fit, theta0, rng, bar.step)
    bar.step("bootstrap of the final fit")
    result = conclude(problem, motion, platform, refit, found, rng, given)
    bar.close()
    return result


def _problem(motion: Motion, forces: np.ndarray, platform: Platform, settings: Settings,
             poses: tuple[np.ndarray, np.ndarray] | None) -> Problem:
    """The data against the model (``Problem``); an ``InputError`` when the model flags too
    many of the samples used (``evaluation.flags.check_flagged``)."""
    problem = Problem(motion, forces, platform, settings, poses=poses)
    used_flags = problem.result.flag[problem.used]
    check_flagged(platform, flag_counts(used_flags), int(np.count_nonzero(used_flags)),
                  len(used_flags))
    return problem


def _check_call(motion: Motion, options: dict) -> None:
    """An ``InputTypeError`` for a ``motion`` that is not a Motion or an ``options`` key that
    is not a ``Settings`` field."""
    if not isinstance(motion, Motion):
        raise InputTypeError(f"discover: motion must be a gsfric.Motion, got {short(motion)} "
                             "(gsfric.io.read_measured)")
    unknown = sorted(set(options) - {f.name for f in dataclasses.fields(Settings)})
    if unknown:
        raise InputTypeError(f"discover: unknown option {unknown[0]!r} (a Settings field "
                             "name)")


def _checked_data(motion: Motion, forces: np.ndarray, platform: Platform,
                  poses: tuple[np.ndarray, np.ndarray] | None,
                  force_noise: ForceNoise | None, settings: Settings) -> np.ndarray:
    """The measured forces (N, 6), N, checked with the poses (the recorded ones, default the
    motion's) against the platform, and the user's force noise against the data; each
    problem an ``InputError`` in one line."""
    forces = checked_forces(motion, forces, settings)
    recorded = poses if poses is not None else motion.recorded_poses()
    check_poses(platform, *(recorded if recorded is not None else (motion.position,
                                                                   motion.rotation)), motion.t)
    check_measured_forces(platform, motion, forces)
    if force_noise is not None:
        force_noise.check_at_rest(settings.record_travel, settings.record_turn)
        force_noise.check_plausible(forces, settings.noise_spread)
    return forces


class _Progress:
    """A tqdm progress bar on stderr over the workflow's stages (or nothing)."""

    def __init__(self, enabled: bool, total: int) -> None:
        self.bar = None
        if enabled:
            self.bar = tqdm(total=total, unit="stage", desc="discover", leave=False)

    def step(self, text: str) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(text, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()

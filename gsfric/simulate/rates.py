"""The log's own rates against its poses differentiated: the difference in the forces, and how
much of it the differentiation's uncertainty accounts for (``gsfric simulate`` prints it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric.evaluation.evaluator import state_array
from gsfric.evaluation.uncertainty import force_sigma
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.trajectory import Motion


@dataclass(frozen=True)
class RateComparison:
    """Forces from a log's own rates against those from differentiating its poses
    (``compare_rates``).

    Attributes
    ----------
    rates : tuple of str
        The rates the log gave (``Differentiation.rates``).
    median_difference, largest_difference : ndarray, shape (6,)
        Median and largest |F_own - F_differentiated| per leg over the steps, N.
    median_ratio : float
        Median over steps and legs of |F_own - F_differentiated| / sigma_F (sigma_F of the
        differentiated motion): about 0.67 when the difference is the differentiation's noise.
    differentiation : str
        How the poses were differentiated (``Differentiation.describe``).
    """

    rates: tuple[str, ...]
    median_difference: np.ndarray
    largest_difference: np.ndarray
    median_ratio: float
    differentiation: str

    def describe(self) -> str:
        """One line for the console."""
        leg = int(np.argmax(self.largest_difference))
        return (f"the log's own {', '.join(self.rates)} against its poses differentiated "
                f"({self.differentiation}): F differs by a median "
                f"{float(np.median(self.median_difference)):.4g} N, up to "
                f"{self.largest_difference[leg]:.4g} N (leg {leg + 1}); median |dF| / sigma_F "
                f"= {self.median_ratio:.3g}")


def compare_rates(evaluator, motion: Motion, window: int | None, polyorder: int
                  ) -> RateComparison | None:
    """The actuator forces of ``motion`` (made by ``Motion.from_samples`` with some of the
    log's own rates) against those of its recorded poses differentiated with the same
    ``window`` and ``polyorder``; None for a motion without own rates or recorded poses, or
    an evaluator in paper mode."""
    how = motion.differentiation()
    poses = motion.recorded_poses()
    if how is None or not how.rates or poses is None or evaluator.mode != "kinematic":
        return None
    position, rotation = poses
    derived = Motion.from_samples(motion.t, position, window=window, polyorder=polyorder,
                                  quaternion=quaternion_from_rotation(rotation))
    own = evaluator.actuator_forces(state_array(motion))
    differentiated = evaluator.actuator_forces(state_array(derived))
    sigma = force_sigma(evaluator, derived)
    difference = np.abs(own - differentiated)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = float(np.nanmedian(difference / sigma)) if sigma is not None else np.nan
    return RateComparison(how.rates, np.median(difference, axis=0), np.max(difference, axis=0),
                          ratio, derived.differentiation().describe())


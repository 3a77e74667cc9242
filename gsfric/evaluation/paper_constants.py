"""The paper's constant accelerations and joint speed, the inputs of the paper-mode evaluation.

The paper's RESULTS section evaluates its friction with these constants instead of the motion's
own rates: platform acceleration (m/s^2) and angular acceleration (rad/s^2), the legs'
acceleration (m/s^2) and angular acceleration (rad/s^2), and one joint speed (rad/s).
"""

from __future__ import annotations

import numpy as np

PAPER_ACCELERATION = (0.07, 0.05, 0.04)
PAPER_ANGULAR_ACCELERATION = (0.005, 0.003, 0.0025)
PAPER_LEG_ACCELERATION = (0.055, 0.042, 0.027)
PAPER_LEG_ANGULAR_ACCELERATION = (0.0032, 0.0021, 0.0017)
PAPER_JOINT_SPEED = 0.02


def paper_constants() -> np.ndarray:
    """The paper's RESULTS constants in the order of the paper-mode input K, shape (13,)."""
    return np.concatenate([PAPER_ACCELERATION, PAPER_ANGULAR_ACCELERATION,
                           PAPER_LEG_ACCELERATION, PAPER_LEG_ANGULAR_ACCELERATION,
                           [PAPER_JOINT_SPEED]]).astype(float)

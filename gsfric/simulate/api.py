"""``gsfric.evaluate``: a platform over a motion, given as a ``Motion`` or as a table of samples.

The table is read as ``gsfric.io.read_trajectory`` reads a file (``motion_from_frame``), then
evaluated by ``gsfric.evaluation.evaluator.evaluate_motion``.
"""

from __future__ import annotations

import sys

from gsfric.errors import InputTypeError
from gsfric.evaluation.evaluator import evaluate_motion
from gsfric.evaluation.result import Result
from gsfric.io.readers import motion_from_frame
from gsfric.platform.description import Platform

READING = ("window", "polyorder", "log_format")
"""The keyword arguments of ``evaluate`` that read a DataFrame."""


def _is_frame(value: object) -> bool:
    """Whether ``value`` is a pandas DataFrame, without importing pandas: none can exist before
    pandas is imported."""
    pandas = sys.modules.get("pandas")
    return pandas is not None and isinstance(value, pandas.DataFrame)


def evaluate(platform: Platform, motion, mode: str = "kinematic", **kwargs) -> Result:
    """Reaction forces and friction in every joint of ``platform`` over a motion.

    Parameters
    ----------
    platform : Platform
        E.g. ``gsfric.reference_platform()`` or ``Platform.from_toml(path)``.
    motion : Motion or pandas.DataFrame
        N steps. A DataFrame holds samples with the columns of a trajectory file (``t, x, y,
        z`` in s and m with ``alpha, beta, gamma`` in rad, ``qw, qx, qy, qz`` or ``roll,
        pitch, yaw``); it is differentiated as ``gsfric.io.read_trajectory`` does.
    mode : {"kinematic", "paper"}
        "kinematic": accelerations from the motion; "paper": the paper's constants.
    **kwargs
        ``strict``, ``progress``, ``chunk`` of ``Evaluator.evaluate``; for a DataFrame also
        ``window``, ``polyorder`` and ``log_format`` (``gsfric.io.motion_from_frame``).

    Returns
    -------
    Result
        Arrays with the step as the leading axis, SI units, base frame: ``F`` (N, 6) N,
        ``R_E`` (N, 6, 3) N, ... (see ``Result``); ``result.to_frame()`` for a table with units.

    Raises
    ------
    InputError
        A DataFrame with missing or bad columns (one line naming the row and column);
        ``chunk`` not an integer >= 1.
    InputTypeError
        ``platform`` is not a Platform or ``motion`` not a Motion or DataFrame (swapped
        arguments, None, a NumPy array), in one line saying what to give; an unknown keyword
        argument; ``strict`` not a bool.
    StepFlagError
        ``strict=True`` and a flagged step.

    Examples
    --------
    >>> import numpy as np, gsfric
    >>> result = gsfric.evaluate(gsfric.reference_platform(),
    ...                          gsfric.models.sinusoidal(np.linspace(0, 1, 101)))
    >>> result.F.shape, result.R_E.shape
    ((101, 6), (101, 6, 3))
    """
    if _is_frame(motion):
        reading = {k: kwargs.pop(k) for k in READING if k in kwargs}
        motion = motion_from_frame(motion, **reading)
    elif set(READING) & set(kwargs):
        name = sorted(set(READING) & set(kwargs))[0]
        raise InputTypeError(f"evaluate: {name!r} reads a DataFrame; the motion is a "
                             f"{type(motion).__name__}")
    return evaluate_motion(platform, motion, mode, **kwargs)

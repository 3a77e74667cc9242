"""The step flags: their bits and limits, and their settings for the compiled code.

Step flags (bits of ``Result.flag``; 0 = sound step):

* 1 ``FLAG_NONFINITE``: a non-finite input or output value (outputs set to NaN);
* 2 ``FLAG_STROKE``: a leg length outside ``geometry.stroke``;
* 4 ``FLAG_SINGULAR``: the platform's 6x6 force Jacobian (columns ``(u_i, (E_i - p) x u_i)``)
  is near singular: its singularity measure ``h`` (output ``h``, derive/conditioning.py: the
  volume spanned by the legs' unit wrenches, moments in units of the platform's size, relative
  to orthogonal ones) is below ``SINGULAR_LIMIT = 2 / COND_LIMIT``. Unflagged steps are
  guaranteed a condition number below ``COND_LIMIT`` for that Jacobian with its moment rows
  divided by the platform's size and its columns scaled to unit length;
* 8 ``FLAG_UNIVERSAL``: a leg within ``UNIVERSAL_LIMIT`` of the direction of its universal
  joint's first axis (``1 - (u.a1)^2 < UNIVERSAL_LIMIT``), where the joint's torsion moment is
  undefined;
* 16 ``FLAG_COUPLING``: the coupled friction model's fixed point has not converged: the axial
  forces changed by more than ``COUPLING_TOLERANCE * (1 N + |F0|)`` over the last of its
  iterations (joint friction so large that it nearly locks the mechanism; docs/explanation/friction.md).

Every flag is computed in C in the same pass as the outputs (``compiled/batch.c``) with the
settings of ``flag_spec`` (tests/helpers.py has an independent NumPy version for the tests).
"""

from __future__ import annotations

import numpy as np

from gsfric.compiled.functions import FlagSpec
from gsfric.compiled.state import state_layout

FLAG_NONFINITE = 1
FLAG_STROKE = 2
FLAG_SINGULAR = 4
FLAG_UNIVERSAL = 8
FLAG_COUPLING = 16
FLAG_NAMES = {FLAG_NONFINITE: "non-finite value", FLAG_STROKE: "leg length outside the stroke",
              FLAG_SINGULAR: "near-singular platform Jacobian",
              FLAG_UNIVERSAL: "leg near its universal joint's first axis",
              FLAG_COUPLING: "coupled friction solve not converged"}
FLAG_BITS = {"NONFINITE": FLAG_NONFINITE, "STROKE": FLAG_STROKE, "SINGULAR": FLAG_SINGULAR,
             "UNIVERSAL": FLAG_UNIVERSAL, "COUPLING": FLAG_COUPLING}
"""Each flag's name (``FLAG_<name>`` here and in compiled/batch.c) and bit."""
FLAG_ROTATION = 32
EXPORT_FLAG_NAMES = {**FLAG_NAMES,
                     FLAG_ROTATION: "rotation block of the state not a rotation matrix"}
EXPORT_FLAG_BITS = {**FLAG_BITS, "ROTATION": FLAG_ROTATION}
"""The flags of the library ``gsfric export`` writes: the ones above and ``ROTATION``, a state
whose rotation block is not a rotation (``gsfric.trajectory.ROTATION_TOL``, the test of
``first_non_rotation``; its outputs are NaN). gsfric raises ``InputError`` for such a state
before evaluating it (``Motion``, ``Evaluator``); a controller's call cannot raise, so the
library flags it."""
COUPLING_TOLERANCE = 1e-6
COND_LIMIT = 1e6
SINGULAR_LIMIT = 2.0 / COND_LIMIT
UNIVERSAL_LIMIT = 1e-4


def flag_spec(outputs, stroke: tuple[float, float] | None) -> FlagSpec:
    """The settings of the step flags computed in C (``gsfric_flags`` in ``batch.c``).

    Parameters
    ----------
    outputs : sequence of (name, size, shape)
        The outputs of the function that computes the flags (``CompiledFunction.outputs``):
        the flags read ``D``, ``s2``, ``h`` and, when there, ``coupling_change`` and ``F0``.
    stroke : (float, float) or None
        The legs' length range, m (``geometry.stroke``); None: no stroke flag.
    """
    index = {name: k for k, (name, _, _) in enumerate(outputs)}
    lo, hi = stroke if stroke is not None else (0.0, 0.0)
    return FlagSpec(index["D"], index["s2"], index["h"], stroke is not None, lo, hi,
                    UNIVERSAL_LIMIT, SINGULAR_LIMIT, state_layout().size,
                    index.get("coupling_change", -1), index.get("F0", -1), COUPLING_TOLERANCE)


def _index_list(idx: np.ndarray, limit: int = 10) -> str:
    shown = ", ".join(str(i) for i in idx[:limit])
    return shown + (f", ... ({idx.size - limit} more)" if idx.size > limit else "")


def flag_message(flag: np.ndarray) -> str | None:
    """One line on the flagged steps of ``flag`` (how many, which kinds, which steps), or None
    when no step is flagged."""
    bad = np.flatnonzero(flag)
    if not bad.size:
        return None
    kinds = sorted({FLAG_NAMES[b] for b in FLAG_NAMES if np.any(flag & b)})
    return (f"{bad.size} of {flag.shape[0]} steps flagged ({'; '.join(kinds)}): steps "
            f"{_index_list(bad)}")

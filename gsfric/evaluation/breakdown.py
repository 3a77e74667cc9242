"""What each part contributes to the actuator forces: the breakdown of F per leg.

The parts come from the compiled map itself, by substitution (no separate model):

* ``gravity``: F0 of the platform without payload at the same poses, at rest (velocities and
  accelerations zero): the weight of platform and legs;
* ``inertia``: F0 of the platform without payload along the motion, minus ``gravity``: the
  inertial forces and moments of platform and legs;
* ``payload``: F0 with the payload minus F0 without it (its weight and inertia);
* ``joint_friction``: the joint friction moments carried by the actuators (``F_joint``; zero in
  the paper's model unless the effect ``joint_friction_coupling`` is on);
* ``prismatic_viscous``, ``prismatic_coulomb`` ((35) with |R_3|, paper model),
  ``prismatic_bushing`` (coupled model), ``prismatic_seal``: the prismatic friction's parts,
  as they enter F (``-Ffr_*``);
* ``effects``: the rest, the catalog's prismatic friction effects and the sensor bias.

The parts add up to F exactly (to rounding): ``F = gravity + inertia + payload +
joint_friction + prismatic_* + effects``. Units N, shape (N, 6) each, step leading.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from gsfric._optional import optional
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion

if TYPE_CHECKING:
    pass

PARTS = ("inertia", "gravity", "payload", "joint_friction", "prismatic_viscous",
         "prismatic_coulomb", "prismatic_bushing", "prismatic_seal", "effects")
"""Names of the parts, in the order of the columns of ``to_frame``."""

def _at_rest(motion: Motion) -> Motion:
    zero = np.zeros_like(motion.velocity)
    return Motion.from_arrays(motion.t, motion.position, motion.rotation, zero, zero, zero,
                              zero.copy())


def parts(full, run: Callable[[Platform, Motion], object], platform: Platform,
          motion: Motion) -> dict[str, np.ndarray]:
    """The actuator forces of ``platform`` along ``motion`` split into their parts.

    Parameters
    ----------
    full : Result
        The kinematic-mode evaluation of ``platform`` along ``motion``.
    run : callable
        ``run(platform, motion) -> Result``: evaluates the platform variants (without payload,
        at rest) that the parts are differences of.
    platform : Platform
    motion : Motion

    Returns
    -------
    dict
        ``PARTS`` name -> ndarray (N, 6), N; and ``F`` (N, 6), N, their sum.
    """
    bare = platform.with_body(payload_mass=0.0, payload_inertia=np.zeros((3, 3)))
    without_payload = run(bare, motion).F0
    gravity = run(bare, _at_rest(motion)).F0
    split = dict(
        inertia=without_payload - gravity,
        gravity=gravity,
        payload=full.F0 - without_payload,
        joint_friction=full.F_joint.copy(),
        prismatic_viscous=-full.Ffr_viscous,
        prismatic_coulomb=-full.Ffr_coulomb,
        prismatic_bushing=-full.Ffr_bushing,
        prismatic_seal=-full.Ffr_seal,
    )
    split["effects"] = full.F - sum(split.values())
    split["F"] = full.F.copy()
    return split


def to_frame(t: np.ndarray, parts: dict[str, np.ndarray]):
    """The parts as a DataFrame: ``t``, then ``{part}{i}`` for each part and leg i = 1..6, N."""
    pd = optional("pandas")

    cols = {"t": np.asarray(t, float)}
    for name in (*PARTS, "F"):
        for i in range(6):
            cols[f"{name}{i + 1}"] = parts[name][:, i]
    return pd.DataFrame(cols)


def plot(t: np.ndarray, parts: dict[str, np.ndarray], leg: int = 0, ax=None):
    """Stacked contributions to F of one leg (index from 0) over time; returns the axes."""
    plt = optional("matplotlib.pyplot")
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4))
    for name in PARTS:
        values = parts[name][:, leg]
        if np.any(values != 0.0):
            ax.plot(t, values, label=name.replace("_", " "))
    ax.plot(t, parts["F"][:, leg], "k", lw=2, label="F")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(f"force of leg {leg + 1} (N)")
    ax.legend(fontsize=7, ncol=2)
    return ax

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


UNITS = {"t": "s", **{name: "N" for name in (*PARTS, "F")}}
"""Unit of each column group of ``frame``."""


def frame(t: np.ndarray, parts: dict[str, np.ndarray]):
    """The parts as a DataFrame: step as the index, columns (part, leg) for each of ``PARTS``
    and ``F`` and legs 1..6, N, and ``t``, s.

    ``frame["gravity"]`` is then the (N, 6) table of one part (columns legs 1..6),
    ``frame["t"]`` the times; ``attrs["units"]`` maps ``t`` and each part to its unit.
    """
    pd = optional("pandas")
    names = (*PARTS, "F")
    columns = pd.MultiIndex.from_tuples(
        [("t", "")] + [(name, leg) for name in names for leg in range(1, 7)],
        names=["part", "leg"])
    values = np.column_stack([np.asarray(t, float)] + [parts[name] for name in names])
    out = pd.DataFrame(values, columns=columns, index=pd.RangeIndex(len(values), name="step"))
    out.attrs["units"] = dict(UNITS)
    return out


def flat(parts_frame):
    """A ``frame`` as the table ``gsfric simulate --breakdown`` writes: columns ``t``, then
    ``{part}{i}`` for each part and leg i = 1..6, N."""
    out = parts_frame.copy()
    out.columns = [part if part == "t" else f"{part}{leg}" for part, leg in out.columns]
    return out.reset_index(drop=True)


ROUNDING = 1e-9
"""A part smaller than this times the largest |F| (at least 1 N) is rounding: drawn as zero."""


def shown_parts(parts_frame, legs) -> list[str]:
    """The parts not zero (beyond rounding, ``ROUNDING``) on any of ``legs`` (indices from 0)."""
    columns = [leg + 1 for leg in legs]
    scale = ROUNDING * max(1.0, float(np.abs(parts_frame["F"][columns].to_numpy()).max()))
    return [name for name in PARTS
            if np.abs(parts_frame[name][columns].to_numpy()).max() > scale]


def plot(parts_frame, leg: int = 0, axes=None, shown=None):
    """What each part contributes to F of one leg (index from 0) over time, in panels: F on
    top, then each part of ``shown`` (default: those not zero, ``shown_parts``) on a scale of
    its own; the parts left out are named in the title. Returns the axes."""
    plt = optional("matplotlib.pyplot")
    t = parts_frame["t"].to_numpy()
    shown = shown_parts(parts_frame, [leg]) if shown is None else list(shown)
    if axes is None:
        _, axes = plt.subplots(len(shown) + 1, 1, figsize=(8, 1.3 * (len(shown) + 1)),
                               sharex=True, squeeze=False)
        axes = axes[:, 0]
    axes[0].plot(t, parts_frame["F"][leg + 1], "k", lw=1.5)
    axes[0].set_ylabel("F (N)", fontsize=9)
    zero = [name.replace("_", " ") for name in PARTS if name not in shown]
    axes[0].set_title(f"Actuator force of leg {leg + 1} and its parts (N)"
                      + (f"\nzero: {', '.join(zero)}" if zero else ""), fontsize=10)
    for ax, name in zip(axes[1:], shown):
        ax.plot(t, parts_frame[name][leg + 1], lw=1.2)
        ax.axhline(0.0, color="0.7", lw=0.6)
        ax.set_ylabel(f"{name.replace('_', ' ')}\n(N)", fontsize=8, rotation=0, ha="right",
                      va="center")
    axes[-1].set_xlabel("t (s)")
    return axes

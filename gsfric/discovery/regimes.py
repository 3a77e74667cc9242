"""Where the residuals concentrate: regimes of speed, load, stroke, pose and time.

Every (sample, leg) pair is put in one band of each regime:

* ``speed``: the leg's sliding speed |dD/dt|: ``reversal`` (below the
  ``Settings.reversal_quantile`` quantile of all legs' speeds, 5 %, at least
  ``Settings.reversal_min_speed``, 1 mm/s: the neighbourhood of each velocity reversal), then
  ``slow``, ``medium``, ``fast`` (terciles of the rest);
* ``load``: the model's actuator force |F|: ``low``, ``medium``, ``high`` (terciles);
* ``stroke``: the leg length D: ``short``, ``middle``, ``long`` (terciles);
* ``pose``: the platform's tilt (angle between its z axis and the base's): ``level``,
  ``tilted``, ``most tilted`` (terciles);
* ``time``: ``Settings.time_stretches`` (five) equal stretches of the record.

For each band: its share of the pairs, the RMS of the residual before and after, the
concentration (band RMS over overall RMS: above 1, the gap gathers there) and the
*friction-like* part ``mean(r sgn(v))`` (positive when the measurement shows more friction than
the model, as an actuator force opposing the motion reads).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsfric.discovery.settings import Settings


@dataclass
class Band:
    """One band of one regime.

    Attributes
    ----------
    regime, name : str
    share : float
        Share of the (sample, leg) pairs in the band.
    rms_before, rms_after : float
        RMS residual in the band, N.
    concentration_before, concentration_after : float
        Band RMS over the overall RMS.
    friction_before, friction_after : float
        ``mean(r sgn(v))`` in the band, N.
    limits : tuple[float, float]
        Range of the banding variable (its unit: m/s, N, m, rad, s).
    """

    regime: str
    name: str
    share: float
    rms_before: float
    rms_after: float
    concentration_before: float
    concentration_after: float
    friction_before: float
    friction_after: float
    limits: tuple[float, float]


def _terciles(values: np.ndarray, names: tuple[str, ...]) -> tuple[np.ndarray, list]:
    edges = np.quantile(values, np.linspace(0, 1, len(names) + 1))
    labels = np.clip(np.searchsorted(edges[1:-1], values, side="right"), 0, len(names) - 1)
    return labels, [(float(edges[k]), float(edges[k + 1])) for k in range(len(names))]


def _tilt(rotation: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(rotation[:, 2, 2], -1.0, 1.0))


def _speed_regime(v: np.ndarray, quantile: float, min_speed: float
                  ) -> tuple[np.ndarray, list[str], list]:
    """The ``speed`` regime of the leg speeds v (M, 6), m/s: labels (M, 6), band names and
    limits (m/s); the ``reversal`` band below the ``quantile`` of v, at least ``min_speed``."""
    threshold = max(float(np.quantile(v, quantile)), min_speed)
    labels = np.zeros(v.shape, int)
    moving = v >= threshold
    if moving.sum() >= 3:
        inner, limits = _terciles(v[moving], ("slow", "medium", "fast"))
        labels[moving] = inner + 1
    else:
        limits = [(threshold, float(v.max()))] * 3
    return labels, ["reversal", "slow", "medium", "fast"], [(0.0, threshold)] + limits


def _time_regime(t: np.ndarray, stretches: int) -> tuple[np.ndarray, list[str], list]:
    """The ``time`` regime of the sample times t (M,), s: labels (M, 6), band names and
    limits (s) of ``stretches`` equal stretches."""
    m = len(t)
    stretch = np.minimum((np.arange(m) * stretches) // m, stretches - 1)
    edges = [(float(t[stretch == k][0]), float(t[stretch == k][-1]))
             for k in range(stretches)]
    return (np.repeat(stretch[:, None], 6, axis=1), [f"{a:.4g}-{b:.4g} s" for a, b in edges],
            edges)


def bands(t: np.ndarray, speed: np.ndarray, length: np.ndarray, force: np.ndarray,
          rotation: np.ndarray, before: np.ndarray, after: np.ndarray, settings: Settings
          ) -> list[Band]:
    """Residual statistics per band of every regime.

    Parameters
    ----------
    t : ndarray, shape (M,)
        Time, s.
    speed : ndarray, shape (M, 6)
        Leg sliding speeds dD/dt, m/s.
    length : ndarray, shape (M, 6)
        Leg lengths D, m.
    force : ndarray, shape (M, 6)
        Model actuator forces, N.
    rotation : ndarray, shape (M, 3, 3)
        Platform orientation.
    before, after : ndarray, shape (M, 6)
        Residuals of the model as given and of the final model, N.
    settings : Settings
        ``reversal_quantile``, ``reversal_min_speed`` and ``time_stretches``.

    Returns
    -------
    list[Band]
    """
    m = len(t)
    s = np.sign(speed)
    v = np.abs(speed)
    regimes: dict[str, tuple[np.ndarray, list[str], list]] = {}
    regimes["speed"] = _speed_regime(v, settings.reversal_quantile, settings.reversal_min_speed)
    lab, lim = _terciles(np.abs(force).ravel(), ("low", "medium", "high"))
    regimes["load"] = (lab.reshape(m, 6), ["low", "medium", "high"], lim)
    lab, lim = _terciles(length.ravel(), ("short", "middle", "long"))
    regimes["stroke"] = (lab.reshape(m, 6), ["short", "middle", "long"], lim)
    lab, lim = _terciles(_tilt(rotation), ("level", "tilted", "most tilted"))
    regimes["pose"] = (np.repeat(lab[:, None], 6, axis=1), ["level", "tilted", "most tilted"],
                       lim)
    regimes["time"] = _time_regime(np.asarray(t), settings.time_stretches)

    overall_b = np.sqrt(np.mean(before ** 2))
    overall_a = np.sqrt(np.mean(after ** 2))
    out = []
    for regime, (labels, names, limits) in regimes.items():
        for k, name in enumerate(names):
            mask = labels == k
            if not mask.any():
                continue
            rb = float(np.sqrt(np.mean(before[mask] ** 2)))
            ra = float(np.sqrt(np.mean(after[mask] ** 2)))
            out.append(Band(
                regime, name, float(mask.mean()), rb, ra,
                rb / overall_b if overall_b > 0 else 1.0,
                ra / overall_a if overall_a > 0 else 1.0,
                float(np.mean(before[mask] * s[mask])), float(np.mean(after[mask] * s[mask])),
                tuple(limits[k])))
    return out


def hotspots(table: list[Band], top: int = 4) -> list[Band]:
    """The bands where the residual before concentrated most (concentration > 1)."""
    ranked = sorted((b for b in table if b.concentration_before > 1.0),
                    key=lambda b: -b.concentration_before)
    return ranked[:top]

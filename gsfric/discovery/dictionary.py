"""Structure the catalog cannot name, found and described by one mechanism: a regression of the
final residual on a generic dictionary of out-of-catalog features, each group accepted by the
rule the candidate effects face (``lackfit.test``: F-test at ``alpha`` over the groups, also on
the record's slowest components alone or on the rest alone, a lower held-out error of the block
cross-validation, a gap of at least ``Settings.dictionary_min_gap`` times the noise), with the
noise model fitted to the residual left by the group (what the group explains cannot inflate
the noise model that judges it).

The groups (``GROUPS``: the ``dictionary`` entries of ``outside.OUTSIDE``, which say what each
suggests) have one column per leg and feature (a cell's own trouble is one cell's): sines at
the residual's most prominent spectral peaks (``line``), the other legs' model forces
(``coupling``), a load cell's reading through a dead band whose width is chosen per leg from a
tenth of the residual to three times it, and a dead band around zero force (``sensor memory``),
time polynomials and piecewise levels (``drift``), the leg's stroke, its square, its speed, its
speed's magnitude and the platform's position (``state``).

The groups are taken by forward selection (``find``), and each accepted group is described
in a rig engineer's words (``Unexplained.description``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from gsfric._optional import optional
from gsfric.discovery import lackfit, outside
from gsfric.discovery.residuals import Problem
from gsfric.discovery.settings import Settings
from gsfric.trajectory import Motion

GROUPS = outside.names("dictionary")
"""The dictionary's groups (``outside.OUTSIDE``), in the order of the report."""


@dataclass
class Unexplained:
    """One structure of the final residual that no catalog effect explains.

    Attributes
    ----------
    kind : str
        Its group (``GROUPS``).
    legs : list of int
        The legs it is on (1-based): those with at least a quarter of the largest leg's RMS.
    size_rms : float
        RMS of the fitted structure over all legs, N.
    per_leg_rms : list of float
        RMS of the fitted structure per leg, N.
    gap : float
        ``size_rms`` over the RMS of the residual it leaves.
    p_value : float
        The group's F-test (prewhitened), beside ``level``.
    level : float
        The level of the test (``alpha`` over the groups).
    cv_gain : float
        Relative fall of the held-out squared error.
    description : str
        What it is, where and how large, in words.
    details : dict
        The numbers of the description (frequency, amplitude, phase; coupling share; width;
        drift).
    """

    kind: str
    legs: list[int]
    size_rms: float
    per_leg_rms: list[float]
    gap: float
    p_value: float
    level: float
    cv_gain: float
    description: str
    details: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Features:
    """What the dictionary reads of the record (M used samples).

    Attributes
    ----------
    t : ndarray, shape (M,)
        Sample times, s.
    F : ndarray, shape (M, 6)
        The final model's forces, N.
    D, speed : ndarray, shape (M, 6)
        Leg lengths (m) and speeds (m/s).
    position : ndarray, shape (M, 3)
        The platform's position, m.
    weight : ndarray, shape (M, 6)
        The pairs' weights (0: not sliding).
    noise : float
        The force noise, N (the widths of the dead bands are multiples of it).
    """

    t: np.ndarray
    F: np.ndarray
    D: np.ndarray
    speed: np.ndarray
    position: np.ndarray
    weight: np.ndarray
    noise: float

    @classmethod
    def of(cls, problem: Problem, motion: Motion, theta: np.ndarray, force_noise: np.ndarray
           ) -> Features:
        """What the dictionary reads of the record at the final parameters theta, with the
        floor's force noise per leg (6,), N."""
        used = problem.used
        return cls(np.asarray(motion.t[used], float), problem.model.forces(theta)[used],
                   problem.result.D[used], problem.result.D_dot[used],
                   np.asarray(motion.position[used], float), problem.weight,
                   float(np.sqrt(np.mean(np.square(force_noise)))))


def find(residual: np.ndarray, x: Features, settings: Settings) -> list[Unexplained]:
    """The dictionary's groups that the residual (M, 6), N, holds, each described.

    Forward selection: every group is tested on the residual; of those accepted, the one of
    the largest held-out gain is taken and its fit removed, and the others accepted are
    tested again on what it leaves, until none is: one structure is described once, by the
    group that explains it best (a cross-talk on a sinusoidal motion is not also a line at
    the motion's frequency)."""
    level = settings.alpha / len(GROUPS)
    built, results = {}, {}
    for kind in GROUPS:               # one group's columns at a time: only those that count
        columns = BUILDERS[kind](residual, x, settings)           # are kept for the rounds
        if columns is None:
            continue
        design, describe = columns          # the builder's own array: weighted and scaled
        design *= x.weight[:, :, None]        # in place (a group holds up to 200 MB)
        _scale(design)
        del columns
        result = _test(residual, design, x, settings, level, kind)
        if result.significant:
            built[kind], results[kind] = (design, describe), result
        del design
    left, out = residual, []
    while built:
        kind = max(built, key=lambda k: results[k].details["cv_gain"])
        result, describe = results[kind], built.pop(kind)[1]
        per_leg = np.asarray(result.per_leg_rms)
        legs = [i + 1 for i in np.flatnonzero(per_leg >= 0.25 * per_leg.max())]
        text, details = describe(result.fitted, legs)
        out.append(Unexplained(kind, legs, result.structure_rms, result.per_leg_rms,
                               result.gap, float(result.p_value), level,
                               float(result.details["cv_gain"]), text, details))
        left = left - result.fitted
        results = {k: _test(left, built[k][0], x, settings, level, k) for k in built}
        built = {k: v for k, v in built.items() if results[k].significant}
    return out


def _test(residual: np.ndarray, X: np.ndarray, x: Features, s: Settings, level: float,
          kind: str):
    """``lackfit.test`` of the group's columns X (M, 6, k) on the residual, prewhitened with
    the noise model of what they leave, at ``level``."""
    valid = x.weight > 0
    whitener = lackfit.whitener_beyond(residual, X, valid, s)
    return lackfit.test(residual, X, whitener, alpha=level, min_gap=s.dictionary_min_gap,
                        n_blocks=s.n_blocks, n_folds=s.n_folds, ridge=s.ridge,
                        names=[kind] * X.shape[2],
                        low=whitener.low_band(x.t, valid, q=s.low_band), by="pairs")


def _scale(X: np.ndarray) -> None:
    """Each column of X (M, 6, k) brought to unit RMS in place (a column without values left
    at zero)."""
    scale = np.sqrt(np.einsum("ijk,ijk->k", X, X) / (X.shape[0] * X.shape[1]))
    X /= np.where(scale > 0, scale, 1.0)


def _per_leg(columns: list[np.ndarray]) -> np.ndarray:
    """Columns (M, 6, 6 k): each feature (M, 6) of ``columns`` on its own leg alone."""
    M, legs = columns[0].shape
    X = np.zeros((M, legs, legs * len(columns)))
    for j, c in enumerate(columns):
        for i in range(legs):
            X[:, i, j * legs + i] = c[:, i]
    return X


def _legs_text(legs: list[int]) -> str:
    return ("leg " if len(legs) == 1 else "legs ") + ", ".join(str(i) for i in legs)


# -- lines ------------------------------------------------------------------------------------


def line_frequencies(t: np.ndarray, residual: np.ndarray, most: int, prominence: float
                     ) -> list[float]:
    """The frequencies (Hz) of the ``most`` largest peaks of the residual's power (legs
    summed, zero-padded eightfold for a frequency within a sixteenth of the record's
    resolution) that stand ``prominence`` times above the median power around them."""
    n = len(t)
    if n < 64:
        return []
    step = (t[-1] - t[0]) / (n - 1)
    signal = optional("scipy.signal")
    freqs, density = signal.periodogram(residual, 1.0 / step, np.hanning(n), 8 * n, axis=0)
    density[[0, -1]] *= 2      # the one-sided density doubles all other frequencies
    power = np.sum(density, axis=1)
    median_filter = optional("scipy.ndimage").median_filter
    baseline = np.repeat(median_filter(power[::8], size=81, mode="reflect"), 8)[:len(power)]
    # the first 24 frequencies are the drift's (the record's slowest components), and none of
    # the last two is a line; peaks above ``prominence`` times the baseline (a height of the
    # next float up: strictly above), more than 4 / T apart (32 of the padded frequencies)
    # with the larger one kept, the ``most`` largest
    peaks, found = signal.find_peaks(power[23:-1], np.nextafter(prominence * baseline[23:-1],
                                                                 np.inf), distance=33)
    peaks = peaks[np.argsort(found["peak_heights"], kind="stable")[::-1][:most]] + 23
    return [float(freqs[k]) for k in peaks]


def _lines(residual: np.ndarray, x: Features, s: Settings):
    freqs = line_frequencies(x.t, residual * (x.weight > 0), s.dictionary_lines,
                             s.line_prominence)
    # a peak at a frequency of the motion's own (a sinusoidal motion's, its harmonics) is a
    # structure that follows the motion, for the other groups: not a line
    own = line_frequencies(x.t, x.F, 4 * s.dictionary_lines, s.line_prominence)
    resolution = 4.0 / max(float(x.t[-1] - x.t[0]), 1e-300)
    freqs = [f for f in freqs if all(abs(f - g) > resolution for g in own)]
    if not freqs:
        return None
    tau = x.t - x.t[0]
    cols = []
    for f in freqs:
        w = 2 * np.pi * f * tau
        cols += [np.repeat(np.sin(w)[:, None], 6, axis=1), np.repeat(np.cos(w)[:, None], 6, 1)]

    def describe(fitted: np.ndarray, legs: list[int]):
        parts, details = [], []
        for f in freqs:
            w = 2 * np.pi * f * tau
            basis = np.stack([np.cos(w), np.sin(w)], axis=1)
            coef, *_ = np.linalg.lstsq(basis, fitted, rcond=None)       # (2, 6)
            amplitude = np.hypot(coef[0], coef[1])
            if amplitude.max() < 0.1 * np.sqrt(2) * np.sqrt(np.mean(fitted ** 2)):
                continue
            on = [i + 1 for i in np.flatnonzero(amplitude >= 0.25 * amplitude.max())]
            phase = np.degrees(np.arctan2(-coef[1], coef[0]))
            rel = [(phase[i - 1] - phase[on[0] - 1] + 180) % 360 - 180 for i in on]
            if len(on) == 1:
                relation = ""
            elif all(abs(r) < 30 for r in rel):
                relation = " in phase"
            elif all(abs(r) < 30 or abs(r) > 150 for r in rel):
                opposite = [leg for leg, r in zip(on, rel) if abs(r) > 150]
                relation = f", {_legs_text(opposite)} in antiphase to leg {on[0]}"
            else:
                relation = " with phases " + ", ".join(f"{r:.0f}" for r in rel) + " deg"
            parts.append(f"a {f:.4g} Hz line of {float(np.mean(amplitude[np.array(on) - 1])):.2g}"
                         f" N on {_legs_text(on)}{relation}")
            details.append({"frequency": f, "amplitude": [float(a) for a in amplitude],
                            "phase_deg": [float(p) for p in phase], "legs": on})
        if not parts:
            parts = ["lines at " + ", ".join(f"{f:.4g}" for f in freqs) + f" Hz on "
                     f"{_legs_text(legs)}"]
        text = "; ".join(parts) + (": electrical interference on the load cells or their "
                                   "amplifiers (mains, a drive's switching), or a vibration "
                                   "at that frequency")
        return text, {"lines": details}

    return _per_leg(cols), describe


# -- coupling ---------------------------------------------------------------------------------


def _coupling(residual: np.ndarray, x: Features, s: Settings):
    F = x.F - x.F.mean(axis=0)
    legs = F.shape[1]
    X = np.zeros(F.shape + (legs * (legs - 1),))
    pairs = []
    for i in range(legs):
        for j in range(legs):
            if j != i:
                X[:, i, len(pairs)] = F[:, j]
                pairs.append((i, j))

    def describe(fitted: np.ndarray, on: list[int]):
        shares = []
        for i in range(legs):
            others = [j for j in range(legs) if j != i]
            A = F[:, others] * x.weight[:, i:i + 1]
            coef, *_ = np.linalg.lstsq(A, fitted[:, i], rcond=None)
            k = int(np.argmax(np.abs(coef)))
            shares.append((i, others[k], float(coef[k])))
        shares = [sh for sh in shares if sh[0] + 1 in on]
        text = "; ".join(f"leg {i + 1} reads {100 * c:.2g} % of leg {j + 1}'s force"
                         for i, j, c in shares)
        return (text + ": cross-talk between the load-cell channels (wiring, a shared "
                "ground, an amplifier's crosstalk)"), {
            "coupling": [{"leg": i + 1, "source_leg": j + 1, "share": c} for i, j, c in shares]}

    return X, describe


# -- sensor memory ----------------------------------------------------------------------------


def play(F: np.ndarray, width: float | np.ndarray) -> np.ndarray:
    """What a reading with a dead band (play) of +-``width`` makes of F (M, k): it follows F
    only when F leaves the band around its last value (backlash operator). ``width``: one,
    one per column (k,), or several per column (W, k), which give (W, M, k)."""
    F = np.asarray(F, float)
    widths = np.asarray(width, float)
    many = widths.ndim == 2
    w = np.broadcast_to(widths if many else widths[None], (len(widths) if many else 1,)
                        + F.shape[1:])
    out = np.empty((w.shape[0],) + F.shape)
    y = np.broadcast_to(F[0], w.shape).copy()
    for k in range(len(F)):       # one step of every width and column at once
        np.clip(y, F[k] - w, F[k] + w, out=y)
        out[:, k] = y
    return out if many else out[0]


def _best_width(residual: np.ndarray, valid: np.ndarray, scale: np.ndarray, error,
                s: Settings) -> np.ndarray:
    """Per leg, the column of ``error(widths (W, 6)) -> (W, M, 6)`` whose width (one of
    ``Settings.memory_widths`` times the leg's residual RMS ``scale`` (6,)) correlates best
    with the leg's residual: one column per leg, not several nearly equal ones whose
    difference a fit would take for signal."""
    widths = np.maximum(np.outer(s.memory_widths, scale), 1e-12)
    c = error(widths) * valid[None]
    norm = np.sqrt(np.sum(c ** 2, axis=1))
    r = np.abs(np.sum(c * residual[None], axis=1)) / np.where(norm > 0, norm, np.inf)
    best = np.argmax(r, axis=0)                                   # (6,)
    return c[best, :, np.arange(residual.shape[1])].T


def _memory(residual: np.ndarray, x: Features, s: Settings):
    F = x.F
    rate = np.gradient(F, x.t, axis=0)
    valid = x.weight > 0
    scale = np.sqrt(np.sum(residual ** 2, axis=0) / np.maximum(valid.sum(axis=0), 1))
    cols = [_best_width(residual, valid, scale, lambda w: play(F, w) - F[None], s)]
    if np.any(np.abs(F) < s.memory_widths[-1] * scale.max()):
        cols.append(_best_width(residual, valid, scale,
                                lambda w: np.clip(F[None], -w[:, None], w[:, None]), s))

    def describe(fitted: np.ndarray, on: list[int]):
        parts, details = [], []
        for i in (leg - 1 for leg in on):
            up, down = rate[:, i] > 0, rate[:, i] < 0
            valid = x.weight[:, i] > 0
            if not (np.any(up & valid) and np.any(down & valid)):
                continue
            h = 0.5 * float(np.mean(fitted[up & valid, i]) - np.mean(fitted[down & valid, i]))
            details.append({"leg": i + 1, "half_width": abs(h), "reads_low_when_rising": h < 0})
            parts.append(f"+-{abs(h):.2g} N on leg {i + 1}")
        text = ("a dead band (hysteresis) of " + ", ".join(parts) + ": the reading lags the "
                "force by a fixed amount that depends on the direction of the force change (a "
                "load cell's hysteresis, play in its mounting, a dead band in its "
                "electronics)") if parts else ("a reading that depends on the direction of the "
                                               f"force change on {_legs_text(on)}")
        return text, {"memory": details}

    return _per_leg(cols), describe


# -- drift ------------------------------------------------------------------------------------


def _drift(residual: np.ndarray, x: Features, s: Settings):
    t = x.t
    tau = 2 * (t - t[0]) / max(t[-1] - t[0], 1e-300) - 1
    cols = [np.repeat(np.polynomial.legendre.legval(tau, [0] * p + [1])[:, None], 6, axis=1)
            for p in (1, 2, 3)]
    for edge in np.linspace(-1, 1, s.drift_pieces + 1)[1:-1]:
        cols.append(np.repeat((tau > edge).astype(float)[:, None], 6, axis=1))

    def describe(fitted: np.ndarray, on: list[int]):
        parts, details = [], []
        for i in (leg - 1 for leg in on):
            valid = x.weight[:, i] > 0
            if not valid.any():
                continue
            f = fitted[valid, i]
            n = max(len(f) // 10, 1)
            change = float(np.mean(f[-n:]) - np.mean(f[:n]))
            span = float(np.ptp(f))
            details.append({"leg": i + 1, "change": change, "range": span})
            parts.append(f"{span:.2g} N on leg {i + 1} (end less start {change:+.2g} N)")
        text = ("a drift over the record of " + ", ".join(parts) + ": a zero drift of the "
                "load cells (temperature), or a change of the rig during the record")
        return text, {"drift": details}

    return _per_leg(cols), describe


# -- state ------------------------------------------------------------------------------------


def _state(residual: np.ndarray, x: Features, s: Settings):
    stroke = x.D - x.D.mean(axis=0)
    position = x.position - x.position.mean(axis=0)
    cols = [stroke, stroke ** 2, x.speed, np.abs(x.speed)]
    cols += [np.repeat(position[:, k:k + 1], 6, axis=1) for k in range(3)]
    names = ("stroke", "stroke squared", "speed", "speed magnitude", "x", "y", "z")

    def describe(fitted: np.ndarray, on: list[int]):
        X = _per_leg(cols) * x.weight[:, :, None]
        flat = X.reshape(-1, X.shape[2])
        coef, *_ = np.linalg.lstsq(flat, fitted.reshape(-1), rcond=None)
        share = {}
        for j, name in enumerate(names):
            part = X[:, :, j * 6:(j + 1) * 6] @ coef[j * 6:(j + 1) * 6]
            share[name] = max(float(np.sum(part * fitted)) / max(float(np.sum(fitted ** 2)),
                                                                 1e-300), 0.0)
        main = max(share, key=share.get)
        size = float(np.sqrt(np.mean(fitted ** 2)))
        text = (f"a force of {size:.2g} N RMS on {_legs_text(on)} that follows the "
                f"{'platform position ' + main if main in 'xyz' else 'leg ' + main}: a "
                "friction or load that varies with the motion's state in a way no catalog "
                "effect has (a seal's friction along the stroke, a cable or hose pulling)")
        return text, {"state": share}

    return _per_leg(cols), describe


BUILDERS: dict[str, Callable] = {"line": _lines, "coupling": _coupling,
                                 "sensor memory": _memory, "drift": _drift, "state": _state}
"""Each group's builder: ``(residual, features, settings) -> (columns (M, 6, k), describe)``
or None (nothing to test), ``describe(fitted, legs) -> (text, details)``."""

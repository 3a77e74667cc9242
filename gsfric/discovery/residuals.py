"""The measured data against the model: residuals, the samples used, what may change.

``Problem`` holds the measured forces of the samples used (the first and last few, where the
differentiation of the recorded pose is least accurate, are left out), the compiled model
(``ParametricModel``), the candidates to test and the bounds of every parameter. Its
``linearise`` gives a ``Design``: the residual ``r = F_measured - F_model`` per leg at the
current parameters and the columns of dF/dtheta for the refitted parameters and the
candidates, on which every statistic of a round works.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import product

import numpy as np

from gsfric._checks import suggest
from gsfric.discovery import rest
from gsfric.discovery import statistics as st
from gsfric.discovery.candidates import (
    CANDIDATE_NAMES,
    CANDIDATES,
    REFIT,
    Candidate,
    stribeck_velocity_bound,
)
from gsfric.discovery.model import BASE_PARAMETERS, ParametricModel
from gsfric.discovery.settings import Settings
from gsfric.errors import InputError
from gsfric.evaluation.parameters import PRISMATIC_EPS
from gsfric.platform.description import Platform
from gsfric.platform.usable import check_force_channels
from gsfric.signal.noise import divided_noise_std_every_window, high_frequency_std
from gsfric.trajectory import Motion, taken_as_even

DELAY = "time_offset.delay"


class Columns:
    """The design's derivative columns, (M, 6, k), over the used samples.

    Columns that need the compiled model are held in an array (``stored``, the first
    ``stored.shape[2]`` columns); the secant columns of ``time_offset`` are not: a delay only
    shifts the model's forces in time (``gsfric.catalog``), so each such column,
    ``(F(t - delay) - F(t)) / size`` times the sliding weight, is computed from the forces F
    of the whole record (N, 6) over the rows asked for, at each request (``base``, (M, 6):
    F(t) over the used samples, default F's). The largest array of a round then holds only
    the columns that cost a model evaluation.

    Indexing as an array: ``columns[a:b]`` gives rows a..b of every column, (b - a, 6, k);
    ``columns[:, :, j]`` one column (M, 6), ``columns[:, :, [j, ...]]`` several.
    """

    ndim = 3

    def __init__(self, stored: np.ndarray, t: np.ndarray, F: np.ndarray, used: slice,
                 weight: np.ndarray, delays: Sequence[tuple[float, float]] = (),
                 base: np.ndarray | None = None) -> None:
        self.stored = stored
        self.t = t
        self.F = F
        # each leg's forces contiguous: np.interp reads them whole at every call
        self._legs = np.ascontiguousarray(np.asarray(F, float).T)
        self.base = F[used] if base is None else base
        self.used = used
        self.weight = weight
        self.delays = [(float(d), float(size)) for d, size in delays]

    @property
    def shape(self) -> tuple[int, int, int]:
        m, legs, k = self.stored.shape
        return (m, legs, k + len(self.delays))

    def _shifted(self, j: int, rows: slice) -> np.ndarray:
        """Delay column j at ``rows`` (a step of 1), (m, 6), computed at each request: the
        interpolation costs less than a model evaluation, and kept for every delay over
        the record it would be the round's second largest array."""
        delay, size = self.delays[j]
        start, stop, _ = rows.indices(self.stored.shape[0])
        g0 = self.used.start
        x = self.t[g0 + start:g0 + stop] - delay
        out = np.empty((stop - start, self.F.shape[1]))
        for i, leg in enumerate(self._legs):
            out[:, i] = np.interp(x, self.t, leg)
        out -= self.base[start:stop]
        out /= size
        out *= self.weight[start:stop]
        return out

    def rows(self, rows: slice, cols: Sequence[int] | None = None) -> np.ndarray:
        """Columns ``cols`` (default all) at ``rows``, (m, 6, len(cols))."""
        k0 = self.stored.shape[2]
        k = self.shape[2]
        cols = list(range(k)) if cols is None else [int(c) % k for c in cols]
        if all(c < k0 for c in cols):
            if cols == list(range(k0)):
                return self.stored[rows]
            return self.stored[rows][:, :, cols]
        m = len(range(*rows.indices(self.stored.shape[0])))
        out = np.empty((m, self.stored.shape[1], len(cols)))
        every = cols[:k0] == list(range(k0))
        if every:
            out[:, :, :k0] = self.stored[rows]          # every stored column, in order
        for k, c in enumerate(cols):
            if c >= k0:
                out[:, :, k] = self._shifted(c - k0, rows)
            elif not every or k >= k0:
                out[:, :, k] = self.stored[rows][:, :, c]
        return out

    def __getitem__(self, key):
        if isinstance(key, slice):
            return self.rows(key)
        rows, legs, cols = key
        if not isinstance(rows, slice) or legs != slice(None):
            raise IndexError("Columns: index as [a:b] or [:, :, columns]")
        if np.ndim(cols) == 0:
            return self.rows(rows, [cols])[:, :, 0]
        return self.rows(rows, cols)

    def chunks(self, size: int = 2000):
        """Row slices of at most ``size`` samples covering the columns."""
        m = self.shape[0]
        for a in range(0, m, size):
            yield slice(a, min(m, a + size))


def secant(stepped: np.ndarray, F: np.ndarray, size: float, rounding: float) -> np.ndarray:
    """The secant column ``(stepped - F) / size`` (forces (M, 6), N; size in the amplitude's
    unit), zero where the difference is rounding: at most ``rounding``
    (``Settings.secant_rounding``) times the force (the
    stepped and the unstepped forces come from two evaluations of the compiled model, and
    where a step changes nothing, a clamped Coulomb sum, they still differ by a few units of
    the last place). A column made of rounding noise on a stretch of the record would
    otherwise be fitted there (a fold's training blocks) with an arbitrary, huge coefficient."""
    d = stepped - F
    d[np.abs(d) <= rounding * np.abs(F)] = 0.0
    return d / size


@dataclass
class Design:
    """The model linearised at theta: residual and derivative columns over the used samples.

    Columns are Jacobian parameters (``names``; a candidate with variants has one column per
    variant); ``lower``/``upper`` bound each column's coefficient (a step of the parameter
    from theta, times ``signs``); ``refit`` lists the refitted parameters' columns and
    ``variants`` each candidate's column sets.
    """

    theta: np.ndarray
    r: np.ndarray                 # (M, 6) residual at theta
    X: np.ndarray | Columns       # (M, 6, k) derivative columns
    names: list[str]              # Jacobian parameter of each column
    lower: np.ndarray             # bounds of the step from theta, per column
    upper: np.ndarray
    refit: list[int]              # columns of the refitted parameters
    variants: dict[str, list[list[int]]]   # candidate -> column sets (one per variant)
    grid: dict[str, list[dict]]   # candidate -> parameter values set for each variant
    signs: np.ndarray = None      # parameter step per unit coefficient of each column (+-1)
    XtX: np.ndarray = None        # unwhitened cross-products, for the gap closed
    Xtr: np.ndarray = None
    rtr: float = 0.0

    def __post_init__(self) -> None:
        if self.signs is None:
            self.signs = np.ones(len(self.names))
        if isinstance(self.X, np.ndarray):
            X = self.X.reshape(-1, self.X.shape[2])
            r = self.r.reshape(-1)
            self.XtX = np.einsum("ik,il->kl", X, X)
            self.Xtr = np.einsum("ik,i->k", X, r)
        else:
            k = self.X.shape[2]
            self.XtX, self.Xtr = np.zeros((k, k)), np.zeros(k)
            for rows in self.X.chunks():
                X = self.X[rows].reshape(-1, k)
                r = self.r[rows].reshape(-1)
                self.XtX += np.einsum("ik,il->kl", X, X)
                self.Xtr += np.einsum("ik,i->k", X, r)
        r = self.r.reshape(-1)
        self.rtr = float(r @ r)

    def largest_model(self, ridge: float) -> list[int]:
        """Columns of the largest model: the refitted parameters' and each candidate's once,
        with the variant (grid value, sign, secant step) that fits the residual best together
        with the refit (plain least squares, unbounded, solved with ``ridge``).

        A candidate is one effect with one value of its grid parameters: its variants side by
        side are no model of the catalog (the stroke references' hinges, both signs, add up to
        any friction law along the stroke; the delay's secants to a filter of the force), and
        what only such a sum fits is structure the candidates do not explain. With all
        variants, the largest model behind the rounds' noise model would change with the
        number of grid points tried and take that structure out of what the noise model
        sees. Returns the design's column indices, the refit's first."""
        cols = list(self.refit)
        for sets in self.variants.values():
            best, chosen = np.inf, sets[0]
            for v in sets:
                c = self.refit + v
                A, b = self.XtX[np.ix_(c, c)], self.Xtr[c]
                sse = st.sse(A, b, self.rtr, st.solve(A, b, ridge=ridge))
                if sse < best:
                    best, chosen = sse, v
            cols += [c for c in chosen if c not in cols]
        return cols


@dataclass(frozen=True)
class _Secants:
    """The secant columns of a design (``Problem._secant_variants``), in column order.

    ``names``, ``signs``: each column's amplitude parameter and the sign of its step;
    ``variants``, ``grid``: each candidate's columns (one per variant) and the grid values
    of each variant; ``steps`` (n_theta,) and ``sizes``: the parameters and step size of each
    column evaluated by the compiled model; ``delays``: (signed step, size) of each
    ``time_offset`` column computed when asked for (``Columns``), the last columns."""

    names: list[str]
    signs: list[float]
    variants: dict[str, list[list[int]]]
    grid: dict[str, list[dict]]
    steps: list[np.ndarray]
    sizes: list[float]
    delays: list[tuple[float, float]]


def checked_forces(motion: Motion, forces: np.ndarray, settings: Settings) -> np.ndarray:
    """The measured forces (N, 6), N, as floats; an ``InputError`` for a wrong shape, a
    problem of the data that no model effect explains (``check_force_channels``, runs of
    ``settings.held_run`` equal values) or a row that is not finite."""
    n = len(motion)
    forces = np.asarray(forces, float)
    if forces.shape != (n, 6):
        raise InputError(f"forces: expected shape ({n}, 6), got {forces.shape}")
    check_force_channels(np.asarray(motion.t, float), forces, held_run=settings.held_run)
    if not np.isfinite(forces).all():
        row = int(np.flatnonzero(~np.isfinite(forces).all(axis=1))[0])
        raise InputError(f"forces: row {row + 1} is not finite")
    return forces


def _trim(n: int, settings: Settings) -> tuple[int, int]:
    """The samples left out at each end of a record of n, and the fewest (sample, leg) pairs
    the workflow needs (20 per block); an ``InputError`` when the record is too short or a
    candidate is not in the catalog."""
    trim = settings.trim
    if trim is None:
        trim = min(settings.default_trim, n // 20)
    trim = int(trim)
    used = n - 2 * trim
    needed = 20 * settings.n_blocks
    if used < needed:
        raise InputError(f"measured data: {n} samples ({used} after leaving out {trim} at "
                         f"each end); the workflow needs at least {needed + 2 * trim}")
    for name in settings.candidates:
        if name not in CANDIDATE_NAMES:
            raise InputError(f"candidates: unknown effect {name!r}"
                             f"{suggest(name, CANDIDATE_NAMES)}")
    return trim, needed


@dataclass(frozen=True)
class SpeedBand:
    """The uncertainty of each leg's differentiated speed due to pose noise (``speed_band``).

    Attributes
    ----------
    sigma_v : ndarray, shape (N, 6)
        Standard deviation of each leg's speed, m/s.
    reach : ndarray of int, shape (N,)
        The differentiator's half window at each sample, samples.
    poses : (ndarray (N, 3), ndarray (N, 3, 3)) or None
        The recorded poses (positions, m; rotations), None when the motion has none: its
        smoothed poses underestimate the pose noise.
    """

    sigma_v: np.ndarray
    reach: np.ndarray
    poses: tuple[np.ndarray, np.ndarray] | None


def speed_band(motion: Motion, platform: Platform,
               poses: tuple[np.ndarray, np.ndarray] | None, settings: Settings) -> SpeedBand:
    """The speed band of each leg from the recorded ``poses`` (default: the motion's), as the
    motion was differentiated: Savitzky-Golay filters on a uniform time base (a log's time
    stamps rounded to 0.1 us included), else smoothing splines."""
    n = len(motion)
    t = np.asarray(motion.t, float)
    if poses is None:
        poses = motion.recorded_poses()
    recorded = poses
    if recorded is None:
        poses = (np.asarray(motion.position, float), np.asarray(motion.rotation, float))
    sigma_v, reach = np.zeros((n, 6)), np.zeros(n, int)
    if taken_as_even(motion):
        # the filters the motion was differentiated with, when it was made from these
        # samples (not chosen a second time)
        filters = motion.sample_filters() if recorded is not None else None
        if filters is not None and len(filters[0][0][0]) != n:
            filters = None
        gain, reach = rest.differentiator(*poses, filters=filters,
                                          move_to_noise=settings.move_to_noise)
        sigma_v = rest.speed_uncertainty(platform, t, *poses, gain=gain)
    else:
        # jittered times: the smoothing splines' own noise gain, on divided differences
        spline = rest.spline_differentiator(t, *poses, settings.spline_noise_draws)
        if spline is not None:
            gain, reach = spline
            D = platform.leg_lengths(*poses)
            sigma_v = gain[:, None] * divided_noise_std_every_window(t, D)[None, :]
    return SpeedBand(sigma_v, reach, recorded)


@dataclass(frozen=True)
class Sliding:
    """The (sample, leg) pairs known to slide (``sliding_pairs``), over the used samples.

    Attributes
    ----------
    sliding : ndarray of bool, shape (M, 6)
        Pairs whose speed is beyond the speed band (and not within a rest).
    weight : ndarray, shape (M, 6)
        ``sliding`` as 1.0 / 0.0.
    sigma_v : ndarray, shape (6,)
        Each leg's median speed band over the used samples, m/s.
    move_reach : int
        The reach of the moves' windows, where a rest begins and ends, samples.
    """

    sliding: np.ndarray
    weight: np.ndarray
    sigma_v: np.ndarray
    move_reach: int


def sliding_pairs(D_dot: np.ndarray, band: SpeedBand, used: slice, needed: int,
                  settings: Settings) -> Sliding:
    """The sliding pairs of the ``used`` samples, from each leg's speed ``D_dot`` (N, 6), m/s,
    beyond the speed ``band``; an ``InputError`` when fewer than ``needed`` pairs slide."""
    sliding = rest.sliding_mask(D_dot, band.sigma_v, 3 * PRISMATIC_EPS, reach=band.reach,
                                rest_band=settings.rest_band)[used]
    move_reach = rest.move_reach(band.reach[used], sliding.any(axis=1))
    pairs = int(np.count_nonzero(sliding))
    if pairs < needed:
        window = 2 * move_reach + 1
        raise InputError(
            f"measured data: {pairs} (sample, leg) pairs slide beyond the speed "
            f"uncertainty of the differentiated poses; the workflow needs at least "
            f"{needed}: moves shorter than the differentiator's window ({window} samples) "
            "or too slow for the pose noise cannot be told from rests")
    # per leg, the median over the used samples (the band itself is per sample)
    return Sliding(sliding, sliding.astype(float), np.median(band.sigma_v[used], axis=0),
                   move_reach)


class Problem:
    """The data, the model, what may change and within which bounds.

    ``y`` holds the measured forces of the used samples (``used``), ``model`` the compiled
    model over the whole motion, ``candidates`` the catalog effects to test (those the model
    does not have yet and that apply to it), ``own_effects`` those it has (refitted with its
    own parameters), ``plausible`` the plausible ranges of the refitted parameters.
    """

    def __init__(self, motion: Motion, forces: np.ndarray, platform: Platform,
                 settings: Settings, poses: tuple[np.ndarray, np.ndarray] | None = None
                 ) -> None:
        n = len(motion)
        forces = checked_forces(motion, forces, settings)
        trim, needed = _trim(n, settings)
        self.settings = settings
        self.lazy = True
        """Whether ``linearise`` computes the time_offset secant columns when asked for
        (``Columns``) rather than holding them (the reference path, for the tests)."""
        self.used = slice(trim, n - trim)
        threads = settings.n_threads or os.cpu_count() or 1
        self.model = ParametricModel(platform, motion, n_threads=threads)
        self.y = forces[self.used]
        self.platform = platform
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.result = self.model.evaluate(self.model.theta0)
        D = self.result.D[self.used]
        self.context = {"mean_length": float(D.mean()), "min_length": float(D.min()),
                        "max_length": float(D.max())}
        # rests and reversals: pairs (sample, leg) not known to slide are left out
        band = speed_band(motion, platform, poses, settings)
        self.poses, self.reach = band.poses, band.reach
        """The recorded poses (``SpeedBand.poses``) and the differentiator's half window at
        each sample (N,), samples."""
        pairs = sliding_pairs(self.result.D_dot, band, self.used, needed, settings)
        self.sliding, self.weight = pairs.sliding, pairs.weight
        self.sigma_v, self.move_reach = pairs.sigma_v, pairs.move_reach
        # the speeds the sliding samples cover: a Stribeck decay above nearly all of them is
        # a speed-independent friction on this data (see ``Settings.stribeck_quantile``)
        speeds = np.abs(self.result.D_dot[self.used])[self.sliding]
        quantile = self.settings.stribeck_quantile
        self.context["sliding_speed"] = (float(np.quantile(speeds, quantile))
                                         if speeds.size else np.inf)
        self.force_noise = high_frequency_std(forces[self.used], settings.noise_window)
        self.candidates = [c for c in CANDIDATES if c.name in settings.candidates
                           and c.name not in platform.effects]
        self.skipped = {c.name: c.applies(platform) for c in self.candidates
                        if c.applies(platform)}
        self.candidates = [c for c in self.candidates if c.name not in self.skipped]
        self.own_effects = [c for c in CANDIDATES if c.name in platform.effects]
        self.plausible = self._plausible(settings)

    def _plausible(self, settings: Settings) -> dict[str, tuple[float, float]]:
        out = {}
        specs = {r.name: r for r in REFIT}
        given = dict(settings.plausible or {})
        for name in settings.refit:
            if name not in BASE_PARAMETERS:
                raise InputError(f"refit: {name!r} is not one of {', '.join(BASE_PARAMETERS)}")
            value = self.model.theta0[self.model.index[name]]
            if name in given:
                lo, hi = (float(v) for v in given[name])
            elif name in specs:
                lo, hi = specs[name].bounds(value)
            else:
                lo, hi = 0.0, np.inf
            if not lo <= value <= hi:
                lo, hi = min(lo, value), max(hi, value)
            if hi > lo:
                out[name] = (lo, hi)
        return out

    # -- parameters ---------------------------------------------------------------------
    def bounds(self, name: str) -> tuple[float, float]:
        """Absolute bounds of a Jacobian parameter: plausible (refit) or physical (effects)."""
        if name in self.plausible:
            return self.plausible[name]
        effect, _, param = name.partition(".")
        for c in CANDIDATES:
            if c.name == effect and param in c.refined:
                grid = c.grids(self.context)[param]
                lo, hi = float(min(grid)), float(max(grid))
                value = float(self.model.theta0[self.model.index[name]])
                own = c.name in self.platform.effects
                return (min(lo, value), max(hi, value)) if own else (lo, hi)
            if c.name == effect and param in c.fitted:
                k = c.fitted.index(param)
                if name == "stribeck.velocity":
                    return (c.lower[k], stribeck_velocity_bound(c.upper[k], self.context))
                return (c.lower[k], c.upper[k])
        return (-np.inf, np.inf)

    def refit_names(self, active: Sequence[str]) -> list[str]:
        names = list(self.plausible)
        for c in self.own_effects + [c for c in CANDIDATES if c.name in active]:
            names += [col for col in c.refined_columns if col not in names]
        return names

    def with_fixed(self, theta: np.ndarray, candidates: Sequence[Candidate]) -> np.ndarray:
        theta = theta.copy()
        for c in candidates:
            for p, v in c.fixed(self.platform, self.context).items():
                theta[self.model.index[f"{c.name}.{p}"]] = v
        return theta

    def residual(self, theta: np.ndarray) -> np.ndarray:
        return self.mask(self.y - self.model.forces(theta)[self.used])

    def mask(self, a: np.ndarray) -> np.ndarray:
        """``a`` (M, 6, ...) with the not-sliding (sample, leg) pairs set to zero."""
        w = self.weight.reshape(self.weight.shape + (1,) * (a.ndim - 2))
        return a * w

    # -- linearisation ------------------------------------------------------------------
    def linearise(self, theta: np.ndarray, active: Sequence[str],
                  candidates: Sequence[Candidate]) -> Design:
        """Residual and columns at theta for the refit and the candidates' parameters.

        Refitted parameters and smooth candidates: columns of the compiled Jacobian.
        Candidates whose amplitude enters the non-negative Coulomb sum, or that have a grid
        (see ``candidates``): one variant per sign of the amplitude and grid value, each the
        one-sided step ``(F(amplitude + sign size) - F) / size`` for each of the candidate's
        ``secants`` sizes (1 but for ``time_offset``), evaluated by the compiled model; a
        variant's coefficient is the amplitude's distance from zero (non-negative).
        """
        theta = self.with_fixed(theta, candidates)
        refit = self.refit_names(active)
        plain = [c for c in candidates if not c.stepped]
        columns = refit + [col for c in plain for col in c.columns]
        variants: dict[str, list[list[int]]] = {}
        grid: dict[str, list[dict]] = {}
        k = len(refit)
        for c in plain:
            variants[c.name] = [list(range(k, k + len(c.columns)))]
            grid[c.name] = [{}]
            k += len(c.columns)
        sec = self._secant_variants(theta, [c for c in candidates if c.stepped], k)
        variants.update(sec.variants)
        grid.update(sec.grid)
        names = columns + sec.names
        signs = np.array([1.0] * len(columns) + sec.signs)
        X = np.empty((len(self.y), 6, len(names) - len(sec.delays)))
        F, _ = self.model.jacobian(theta, columns, rows=self.used,
                                   out=X[:, :, :len(columns)])
        for j, (step, size) in enumerate(zip(sec.steps, sec.sizes)):
            X[:, :, len(columns) + j] = secant(self.model.forces(step)[self.used],
                                               F[self.used], size,
                                               self.settings.secant_rounding)
        X *= self.weight[:, :, None]
        if sec.delays:
            # the forces at theta as the compiled model's force map gives them (what a
            # secant's model evaluation would shift), against F of the Jacobian's pass
            X = Columns(X, np.asarray(self.model.t, float), self.model.forces(theta),
                        self.used, self.weight, sec.delays, base=F[self.used])
        lower, upper = self._column_bounds(theta, names, signs, len(columns))
        return Design(theta, self.mask(self.y - F[self.used]), X, names, lower, upper,
                      list(range(len(refit))), variants, grid, signs)

    def _secant_variants(self, theta: np.ndarray, stepped: Sequence[Candidate], k: int
                         ) -> _Secants:
        """The secant columns of the ``stepped`` candidates at theta, the first of them
        column ``k`` of the design: one per sign of the amplitude, secant size and grid value
        (``linearise``)."""
        index = self.model.index
        out = _Secants([], [], {}, {}, [], [], [])
        owners = []
        for c in stepped:
            amp = f"{c.name}.{c.amplitude}"
            settings = [{}]
            for gname, values in c.grids(self.context).items():
                settings = [{**s_, gname: v} for s_ in settings for v in values]
            out.variants[c.name], out.grid[c.name] = [], []
            for sign, size, values in product(c.signs, c.secants, settings):
                step = theta.copy()
                for gname, v in values.items():
                    step[index[f"{c.name}.{gname}"]] = v
                step[index[amp]] += sign * size
                if self.lazy and amp == DELAY and theta[index[amp]] == 0.0:
                    # a shift of F in time: computed when asked for (``Columns``)
                    out.delays.append((sign * size, size))
                else:
                    out.steps.append(step)
                    out.sizes.append(size)
                out.variants[c.name].append([k])
                out.grid[c.name].append(values)
                out.names.append(amp)
                out.signs.append(sign)
                owners.append(c.name)
                k += 1
        delays = len(out.delays)
        if delays and owners[-delays:] != [DELAY.split(".")[0]] * delays:
            raise AssertionError("the time_offset secant columns must come last")
        return out

    def _column_bounds(self, theta: np.ndarray, names: list[str], signs: np.ndarray,
                       first_secant: int) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of each column's coefficient: the step of its parameter from theta within
        ``bounds``; from column ``first_secant`` on, the signed distance of the amplitude
        from its value (times ``signs``), non-negative."""
        index = self.model.index
        lower = np.empty(len(names))
        upper = np.empty(len(names))
        for j, name in enumerate(names):
            lo, hi = self.bounds(name)
            lo, hi = lo - theta[index[name]], hi - theta[index[name]]
            if j >= first_secant:
                # coefficient = signed distance of the amplitude from its value, >= 0
                lo, hi = (lo, hi) if signs[j] > 0 else (-hi, -lo)
                lo = max(lo, 0.0)
            lower[j], upper[j] = lo, hi
        return lower, upper

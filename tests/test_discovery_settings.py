"""Every field of the discovery ``Settings`` reaches the places that use it.

No code of gsfric reads a class default of ``Settings`` (``Settings.max_order``): the settings
the user passes are the ones used. And every field, changed from its default, changes what it
governs (a result, a chosen order, a fitted value, a decision) on small synthetic records:
were it ignored anywhere on its way, its test would fail.
"""

from __future__ import annotations

import ast
import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest

import gsfric
from gsfric.discovery import (
    conclusion,
    dictionary,
    discover,
    final_tests,
    floor,
    refine,
    regimes,
    rounds,
)
from gsfric.discovery.floor import ForceNoise
from gsfric.discovery.residuals import DELAY, Problem
from gsfric.discovery.selection import low_band_of, screen_candidates
from gsfric.discovery.settings import Settings
from gsfric.errors import InputError
from gsfric.models import minimum_jerk_moves, reference_platform
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.synth import synthesize
from gsfric.trajectory import Motion

FORCES = [f"F{i}" for i in range(1, 7)]
FIELDS = {f.name for f in dataclasses.fields(Settings)}
ROUND = {"candidates": ("seal_friction", "sensor_bias")}
"""The candidates of the tests of a round: the effect hidden and one that is not there."""


# -- no class defaults --------------------------------------------------------------------------

PACKAGE = Path(gsfric.__file__).parent
ENTRY = (Path("discovery", "workflow.py"), "discover_motion")
"""The one function that makes the default settings (``Settings()``) for a user who gave none."""


class _DefaultReads(ast.NodeVisitor):
    """Reads of ``Settings``' defaults in a module: ``Settings.<field>``,
    ``getattr(Settings, ...)`` and, outside ``ENTRY``, ``Settings()``; (line, text) each."""

    def __init__(self, module: Path) -> None:
        self.module, self.function, self.found = module, None, []

    def visit_FunctionDef(self, node) -> None:
        outer, self.function = self.function, self.function or node.name
        self.generic_visit(node)
        self.function = outer

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_Attribute(self, node: ast.Attribute) -> None:
        if node.attr in FIELDS and _is_settings(node.value):
            self.found.append((node.lineno, f"Settings.{node.attr}"))
        self.generic_visit(node)

    def visit_Call(self, node: ast.Call) -> None:
        if isinstance(node.func, ast.Name) and node.func.id == "getattr" and node.args \
                and _is_settings(node.args[0]):
            self.found.append((node.lineno, "getattr(Settings, ...)"))
        if _is_settings(node.func) and (self.module, self.function) != ENTRY:
            self.found.append((node.lineno, "Settings()"))
        self.generic_visit(node)


def _is_settings(node: ast.AST) -> bool:
    return (isinstance(node, ast.Name) and node.id == "Settings"
            or isinstance(node, ast.Attribute) and node.attr == "Settings")


def _default_reads(source: str, module: Path) -> list[tuple[int, str]]:
    visitor = _DefaultReads(module)
    visitor.visit(ast.parse(source))
    return visitor.found


def test_no_code_reads_a_class_default_of_settings():
    """Outside settings.py, no module of gsfric reads a field on the class (its default) nor
    makes default settings of its own: each place reads the settings it was given."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = path.relative_to(PACKAGE)
        if module == Path("discovery", "settings.py"):
            continue
        found += [f"{module}:{line}: {text}"
                  for line, text in _default_reads(path.read_text(), module)]
    assert found == []


def test_the_scan_finds_each_kind_of_default_read():
    source = ("from gsfric.discovery import settings\n"
              "def fit(order=Settings.max_order):\n"
              "    return settings.Settings.ridge + getattr(Settings, 'alpha') + Settings().trim\n"
              "def discover_motion(settings=None):\n"
              "    return settings or Settings()\n")
    found = _default_reads(source, Path("discovery", "other.py"))
    assert [text for _, text in found] == ["Settings.max_order", "Settings.ridge",
                                           "getattr(Settings, ...)", "Settings()",
                                           "Settings()"]
    assert _default_reads(source, ENTRY[0]) == found[:-1]


# -- the records --------------------------------------------------------------------------------


def _recorded(data) -> tuple[Motion, np.ndarray, gsfric.Platform]:
    """The motion differentiated from the record's poses, its forces (N, 6) and its model."""
    f = data.frame
    motion = Motion.from_samples(f["t"].to_numpy(), f[["x", "y", "z"]].to_numpy(),
                                 quaternion=f[["qw", "qx", "qy", "qz"]].to_numpy())
    return motion, f[FORCES].to_numpy(), data.model


@pytest.fixture(scope="module")
def record():
    """6 s at 200 Hz of the excitation motion with a hidden seal friction of 2 N, coloured
    force noise of 0.1 N and pose noise of 10 um."""
    return _recorded(synthesize(effects=["seal_friction:force=2"], samples=1200, noise=0.1,
                                noise_correlation=0.5, pose_noise=1e-5, seed=1))


@pytest.fixture(scope="module")
def rests():
    """20 s of moves of 0.5 s between rests of 0.7 s (15 rests), a seal friction of 1 N."""
    rng = np.random.default_rng(0)
    t = np.arange(4000) / 200.0
    targets = np.c_[rng.uniform(-0.03, 0.03, (20, 2)), 0.95 + rng.uniform(-0.02, 0.02, 20)]
    return _recorded(synthesize(reference_platform(friction_model="paper"),
                                ["seal_friction:force=1"],
                                motion=minimum_jerk_moves(t, targets, 1.2, 0.5), noise=0.1,
                                pose_noise=1e-5, seed=2))


def problem(data, **changes) -> Problem:
    """The record's problem with the default settings but ``changes`` (one thread unless
    changed)."""
    motion, forces, platform = data
    return Problem(motion, forces, platform, Settings(**{"n_threads": 1, **changes}))


@pytest.fixture(scope="module")
def linearised(record):
    """A round on ``record``: the default problem with ``ROUND``'s candidates, its design at
    the model's parameters and its noise model."""
    p = problem(record, **ROUND)
    design = p.linearise(p.model.theta0, [], p.candidates)
    return p, design, rounds._noise_whitener(design, p)


def screen(record, linearised, **changes):
    """The round's candidates screened under the settings ``changes``."""
    _, design, whitener = linearised
    p = problem(record, **ROUND, **changes)
    return screen_candidates(p, design, whitener, p.candidates)


def refit_jacobian(p: Problem, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """The residual (M, 6), N, and its derivatives (M, 6, k) for ``names`` at the model's
    parameters, on the sliding pairs."""
    F, J = p.model.jacobian(p.model.theta0, names, rows=p.used)
    J *= p.weight[:, :, None]
    return p.mask(p.y - F[p.used]), J


def final(p: Problem) -> final_tests.FinalResidual:
    """The final tests' data at the model's parameters (nothing named)."""
    theta = p.model.theta0
    return final_tests.FinalResidual.of(p, theta, p.residual(theta), [])


# -- the data and the problem -------------------------------------------------------------------


def test_trim(record):
    assert problem(record).used == slice(60, 1140)        # min(default_trim, N // 20)
    assert problem(record, trim=30).used == slice(30, 1170)


def test_default_trim(record):
    assert problem(record, default_trim=20).used == slice(20, 1180)


def test_n_blocks(record, linearised):
    """The blocks of a round's tests, and the record's length the workflow needs."""
    assert len(screen(record, linearised).blocks.ztz) == 40
    assert len(screen(record, linearised, n_blocks=12).blocks.ztz) == 12
    with pytest.raises(InputError, match="needs at least 1320"):
        problem(record, n_blocks=60)


def test_candidates(record):
    assert len(problem(record).candidates) > 2
    assert [c.name for c in problem(record, **ROUND).candidates] == list(ROUND["candidates"])


def test_refit(record):
    assert len(problem(record).plausible) > 1
    assert list(problem(record, refit=("payload_mass",)).plausible) == ["payload_mass"]


def test_plausible(record):
    mass = record[2].platform.payload_mass
    given = problem(record, plausible={"payload_mass": (mass - 1.0, mass + 2.0)})
    assert given.plausible["payload_mass"] == (mass - 1.0, mass + 2.0)
    assert problem(record).plausible["payload_mass"] != (mass - 1.0, mass + 2.0)


def test_n_threads(record, monkeypatch):
    """The compiled model's threads and the pose noise floor's (0: every core)."""
    motion, forces, platform = record
    assert Problem(motion, forces, platform, Settings()).model.n_threads == (os.cpu_count()
                                                                          or 1)
    p = problem(record, n_threads=3)
    assert p.model.n_threads == 3
    threads = []

    class Evaluator(floor.Evaluator):
        def __init__(self, platform, *, n_threads):
            threads.append(n_threads)
            super().__init__(platform, n_threads=n_threads)

    monkeypatch.setattr(floor, "Evaluator", Evaluator)
    conclusion._floor(p, motion, platform, p.residual(p.model.theta0), 1.0)
    assert threads == [3]


def test_held_run(record):
    """Four equal force values in a row: noise at the default (5), a dropout at 4."""
    motion, forces, platform = record
    held = forces.copy()
    held[500:504, 1] = held[500, 1]
    problem((motion, held, platform))
    with pytest.raises(InputError, match="F2: the same value .* in 4 rows"):
        gsfric.discover(motion, held, platform, held_run=4)


def test_noise_window(record):
    default = problem(record).force_noise
    assert not np.allclose(problem(record, noise_window=41).force_noise, default, rtol=0.01)


def test_rest_band(record):
    default = np.count_nonzero(problem(record).sliding)
    assert np.count_nonzero(problem(record, rest_band=200.0).sliding) < 0.95 * default


def test_move_to_noise(record):
    """A signal that moves less than ``move_to_noise`` times its noise reaches nowhere."""
    assert problem(record).reach.max() > 0
    assert problem(record, move_to_noise=1e12).reach.max() == 0


def test_spline_noise_draws(record):
    """On a jittered time base (poses sampled at jittered stamps) the speed band is the
    smoothing splines' noise gain, measured on ``spline_noise_draws`` draws."""
    motion, forces, platform = record
    t = np.asarray(motion.t)
    jitter = np.r_[0.0, np.random.default_rng(0).uniform(-0.2, 0.2, len(t) - 1)] * (t[1] - t[0])
    position, rotation = motion.recorded_poses()
    q = quaternion_from_rotation(rotation)
    at = t + jitter
    position = np.stack([np.interp(at, t, position[:, k]) for k in range(3)], axis=1)
    q = np.stack([np.interp(at, t, q[:, k]) for k in range(4)], axis=1)
    jittered = Motion.from_samples(at, position,
                                   quaternion=q / np.linalg.norm(q, axis=1, keepdims=True))
    default = problem((jittered, forces, platform)).sigma_v
    one = problem((jittered, forces, platform), spline_noise_draws=1).sigma_v
    assert not np.allclose(one, default, rtol=1e-3)


def test_stribeck_quantile(record):
    default = problem(record).context["sliding_speed"]
    assert problem(record, stribeck_quantile=0.5).context["sliding_speed"] < 0.8 * default


def test_secant_rounding(record):
    """A secant column is zero where its force difference is below ``secant_rounding`` times
    the force: the seal friction's step of 1 N is a few thousandths of the legs' forces."""
    def zero_share(p):
        design = p.linearise(p.model.theta0, [], p.candidates)
        return np.mean(design.X[:, :, design.names.index("seal_friction.force")][p.sliding]
                       == 0)

    assert zero_share(problem(record, **ROUND)) == 0
    assert zero_share(problem(record, **ROUND, secant_rounding=0.1)) > 0.5


# -- a round: the noise model, the candidates' tests and the refinement -------------------------


def test_max_order(record, linearised):
    p, design, whitener = linearised
    assert whitener.order >= 1
    assert rounds._noise_whitener(design, problem(record, **ROUND, max_order=0)).order == 0


def test_ridge(record, linearised):
    """The ridge of every solve: a large one shrinks the candidates' fitted steps."""
    default, ridged = screen(record, linearised), screen(record, linearised, ridge=1.0)
    assert ridged.blocks.ridge == 1.0
    step, shrunk = (s.fits["seal_friction"].coef[-1] for s in (default, ridged))
    assert abs(shrunk) < 0.9 * abs(step)


def test_low_band(record, linearised, discovered):
    """The slowest components on which the band tests measure the noise, per leg, and what
    the report says of them."""
    _, _, whitener = linearised
    assert low_band_of(problem(record), whitener).shape[2] == 3
    assert low_band_of(problem(record, low_band=5), whitener).shape[2] == 5
    assert screen(record, linearised).blocks.low_rows == 6 * 3
    assert screen(record, linearised, low_band=5).blocks.low_rows == 6 * 5
    result = discovered()
    assert "the record's three slowest components" in result.report()
    changed = dataclasses.replace(result, settings=Settings(low_band=5))
    assert "the record's five slowest components" in changed.report()


def test_n_folds(record, linearised):
    assert screen(record, linearised).cv_null.shape == (8,)
    assert screen(record, linearised, n_folds=4).cv_null.shape == (4,)


def test_min_fold_share(record, linearised):
    assert screen(record, linearised).tests["seal_friction"].significant
    test = screen(record, linearised, min_fold_share=1.01).tests["seal_friction"]
    assert not test.significant and "(needs 101%)" in test.reason


def test_min_gap(record, linearised):
    test = screen(record, linearised, min_gap=1e3).tests["seal_friction"]
    assert not test.significant and "(needs 1000)" in test.reason


def test_n_bootstrap(record, linearised):
    """One bootstrap draw gives intervals of zero width."""
    _, _, whitener = linearised
    def widths(p):
        names = p.refit_names([])
        r, J = refit_jacobian(p, names)
        intervals = conclusion._intervals(p, J, names, whitener, r, np.random.default_rng(0),
                                        p.model.theta0)
        return np.array([hi - lo for lo, hi in intervals.values()])

    assert np.all(widths(problem(record, n_bootstrap=20)) > 0)
    assert np.all(widths(problem(record, n_bootstrap=1)) == 0)


def test_gauss_newton(record, linearised):
    """Without Gauss-Newton iterations the refinement stays where it starts."""
    _, _, whitener = linearised
    def refined(p):
        names = p.refit_names([])
        theta, _, _ = refine.refine(p, p.model.theta0, names, whitener,
                                    start=refit_jacobian(p, names))
        return theta

    theta0 = problem(record).model.theta0
    assert not np.allclose(refined(problem(record)), theta0)
    assert np.array_equal(refined(problem(record, gauss_newton=0)), theta0)


@pytest.mark.parametrize("changes, span, points", [({}, 0.5, 201),
                                                   ({"delay_range": 0.1}, 0.1, 41),
                                                   ({"delay_grid": 20}, 0.5, 21)])
def test_delay_range_and_delay_grid(record, linearised, changes, span, points):
    """The delay profile's coarse grid: +-``delay_range`` in ``delay_grid`` steps."""
    _, _, whitener = linearised
    p = problem(record, **changes)
    names = p.refit_names([]) + [DELAY]
    delays = refine.delay_profile(p, p.model.theta0, names, whitener).delays
    assert delays[0] == pytest.approx(-span) and delays[-1] == pytest.approx(span)
    assert len(delays) == points


def test_stability_min_change(record, linearised):
    """A bias that changes little between the record's halves is stable unless any change
    counts (every difference significant at alpha = 1)."""
    _, _, whitener = linearised
    def stable(p):
        names = p.refit_names(["sensor_bias"])
        r, J = refit_jacobian(p, names)
        return refine.half_stability(p, J, r, names, "sensor_bias", whitener).stable

    assert stable(problem(record, alpha=1.0))
    assert not stable(problem(record, alpha=1.0, stability_min_change=0.0))


# -- the lack-of-fit tests of the final residual ------------------------------------------------


def test_state_bins(record):
    """The bins of the state test: the held-out gains of the bin means change with them."""
    default = final_tests._state(final(problem(record))).details["gains"]
    coarse = final_tests._state(final(problem(record, state_bins=4))).details["gains"]
    assert not np.allclose(list(coarse.values()), list(default.values()), atol=1e-3)


@pytest.mark.parametrize("changes", [{"dynamic_order": 1}, {"dynamic_lags": 0}])
def test_dynamic_order_and_dynamic_lags(record, changes):
    """The residual's own lags and the inputs' lags of the dynamic test's ARX model."""
    default = final_tests._dynamic(final(problem(record)))
    changed = final_tests._dynamic(final(problem(record, **changes)))
    assert changed.details["inputs"] != pytest.approx(default.details["inputs"], abs=1e-3)


def test_dynamic_min_gap(record):
    """The smallest driven part the dynamic test counts: a residual that follows the legs'
    acceleration two samples late, of a fifth of the noise, is driven by the motion at
    ``dynamic_min_gap`` 0.1, not at the default 0.5."""
    def dynamic(p):
        d = final(p)
        rng = np.random.default_rng(3)
        late = np.roll(d.acceleration / d.acceleration.std(), 2, axis=0)
        residual = p.mask(0.02 * late + rng.normal(0, 0.1, late.shape))
        return final_tests._dynamic(dataclasses.replace(d, residual=residual))

    assert 0.1 < dynamic(problem(record)).gap < 0.5
    assert not dynamic(problem(record, min_gap=0.0)).significant
    assert dynamic(problem(record, min_gap=0.0, dynamic_min_gap=0.1)).significant


def test_travel_edges(rests):
    """The bins of travel since a reversal: the profile's upper edges are the ones given
    (and the longest travel)."""
    edges = (1e-3, 4e-3)
    profile = final_tests._reversal(final(problem(rests, travel_edges=edges))).details[
        "profile"]
    assert [e for e, _ in profile[:-1]] == list(edges)
    default = final_tests._reversal(final(problem(rests))).details["profile"]
    assert len(default) > 3


def test_rest_min_run(rests):
    assert final_tests._rest(final(problem(rests))).details["cores"] > 0
    assert final_tests._rest(final(problem(rests, rest_min_run=10 ** 6))).details["cores"] == 0


def test_rest_window(rests):
    default = final_tests._rest(final(problem(rests))).details["u"]
    assert final_tests._rest(final(problem(rests, rest_window=0.1))).details["u"] != \
        pytest.approx(default, abs=1e-4)


def test_rest_lags(rests):
    assert final_tests._rest(final(problem(rests))).details["lag"] in (1, 4, 16)
    assert final_tests._rest(final(problem(rests, rest_lags=(2,)))).details["lag"] == 2


def test_rest_min_rests(rests):
    """The fewest rests the test is made on: none with more than the record has."""
    default = final_tests._rest(final(problem(rests)))
    assert default.details["rests"] >= 6 and default.p_value < 1
    fewer = final_tests._rest(final(problem(rests, rest_min_rests=100)))
    assert fewer.p_value == 1.0 and fewer.details["lag"] == 0


# -- the dictionary of structure outside the catalog --------------------------------------------


def features(n: int = 1200, rate: float = 200.0) -> dictionary.Features:
    """Six legs moving slowly (0.2-1 Hz) for n samples at ``rate``, Hz; force noise 0.2 N."""
    rng = np.random.default_rng(0)
    t = np.arange(n) / rate
    f, phase = rng.uniform(0.2, 1.0, 6), rng.uniform(0, 2 * np.pi, 6)
    F = 200 + 50 * np.sin(2 * np.pi * f * t[:, None] + phase)
    D = 1.0 + 0.05 * np.sin(2 * np.pi * f * t[:, None] + phase + 1.0)
    position = np.stack([0.02 * np.sin(2 * np.pi * 0.3 * t)] * 3, axis=1)
    return dictionary.Features(t, F, D, np.gradient(D, t, axis=0), position, np.ones((n, 6)),
                               0.2)


def noise(x: dictionary.Features) -> np.ndarray:
    return np.random.default_rng(1).normal(0, 0.2, x.F.shape)


def lines(x: dictionary.Features, frequencies=(50.0,)) -> np.ndarray:
    """Noise with lines of 0.5 N at ``frequencies`` (Hz) on legs 1 and 3."""
    r = noise(x)
    for f in frequencies:
        r[:, [0, 2]] += 0.5 * np.sin(2 * np.pi * f * x.t)[:, None]
    return r


def found(residual: np.ndarray, x: dictionary.Features, **changes) -> dict:
    """The dictionary's structures in the residual, by group."""
    return {s.kind: s for s in dictionary.find(residual, x, Settings(**changes))}


def test_dictionary_min_gap():
    x = features()
    assert list(found(lines(x), x)) == ["line"]
    assert found(lines(x), x, dictionary_min_gap=10.0) == {}


def test_line_prominence():
    x = features()
    assert found(lines(x), x, line_prominence=1e9) == {}


def test_dictionary_lines():
    """The spectral peaks tested as lines: both of two, or the larger alone."""
    x = features()
    residual = lines(x, (50.0, 70.0))
    assert len(found(residual, x)["line"].details["lines"]) == 2
    assert len(found(residual, x, dictionary_lines=1)["line"].details["lines"]) == 1


def test_memory_widths():
    """The dead bands tried: a band of 0.8 N is fitted by the widths of the residual's size,
    not by a tenth of it alone."""
    x = features()
    band = noise(x)
    band[:, 4] += dictionary.play(x.F, 0.8)[:, 4] - x.F[:, 4]
    default = found(band, x)["sensor memory"]
    narrow = found(band, x, memory_widths=(0.1,))["sensor memory"]
    assert narrow.gap < 0.9 * default.gap


def test_drift_pieces():
    """A step of the zero of 1.5 times the noise in the middle of the record: the levels of
    four stretches fit it, the cubic in time alone not enough of it."""
    x = features()
    step = noise(x) + np.where(x.t > x.t[len(x.t) // 2], 0.3, 0.0)[:, None]
    assert "drift" in found(step, x)
    assert "drift" not in found(step, x, drift_pieces=1)


# -- the noise floor, the verdict and the regimes -----------------------------------------------


def noise_floor(p: Problem) -> floor.NoiseFloor:
    """The verdict's floor of the record at the model's parameters."""
    full = p.y - p.model.forces(p.model.theta0)[p.used]
    return conclusion._floor(p, p.model.motion, p.platform, full, 1.0)


def test_floor_segment(record):
    """The segments of the force floor's spectral estimate."""
    default = noise_floor(problem(record)).force
    assert not np.allclose(noise_floor(problem(record, floor_segment=128)).force, default,
                           rtol=0.01)


def test_floor_draws(record):
    default = noise_floor(problem(record))
    one = noise_floor(problem(record, floor_draws=1))
    assert "(2 draws)" in default.pose_source and "(1 draws)" in one.pose_source
    assert not np.allclose(one.pose, default.pose, rtol=1e-3)


def bands(p: Problem) -> dict:
    """The regimes' bands of the record's residual at the model's parameters, by regime."""
    u, r = p.used, p.residual(p.model.theta0)
    out = {}
    for band in regimes.bands(np.asarray(p.model.t[u]), p.result.D_dot[u], p.result.D[u],
                              p.result.F[u], p.model.motion.rotation[u], r, r, p.settings):
        out.setdefault(band.regime, {})[band.name] = band
    return out


def test_reversal_quantile(record):
    assert bands(problem(record))["speed"]["reversal"].share == pytest.approx(0.05, abs=0.01)
    assert bands(problem(record, reversal_quantile=0.3))["speed"]["reversal"].share == \
        pytest.approx(0.3, abs=0.01)


def test_reversal_min_speed(record):
    assert bands(problem(record))["speed"]["reversal"].limits[1] < 0.02
    assert bands(problem(record, reversal_min_speed=0.02))["speed"]["reversal"].limits == \
        (0.0, 0.02)


def test_time_stretches(record):
    assert len(bands(problem(record))["time"]) == 5
    assert len(bands(problem(record, time_stretches=3))["time"]) == 3


# -- the whole workflow -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def discovered(record):
    """``discover(**changes)``: the workflow on ``record`` with ``ROUND``'s candidates, 20
    bootstrap draws and the load cells' noise given (0.1 N), the settings changed."""
    motion, forces, platform = record
    runs = {}

    def run(**changes):
        key = tuple(sorted(changes.items()))
        if key not in runs:
            runs[key] = discover(motion, forces, platform, n_threads=1, n_bootstrap=20,
                                 force_noise=ForceNoise.specified(0.1), **ROUND, **changes)
        return runs[key]

    return run


def test_the_result_holds_the_settings_passed(discovered):
    assert discovered(alpha=0.02).settings == Settings(n_threads=1, n_bootstrap=20, alpha=0.02,
                                                       **ROUND)


def test_alpha(discovered):
    """The family-wise level of a round's tests, over its two candidates."""
    assert discovered().rounds[0].level == pytest.approx(0.01 / 2)
    assert discovered(alpha=0.02).rounds[0].level == pytest.approx(0.02 / 2)


def test_max_effects(discovered):
    assert discovered().names == ["seal_friction"]
    nothing = discovered(max_effects=0)
    assert nothing.names == [] and nothing.rounds == []


def test_floor_ratio(discovered):
    """The residual over the floor the user gave above which the data are not explained."""
    assert discovered().verdict == "explained"
    strict = discovered(floor_ratio=0.5)
    assert strict.verdict == "unexplained_discrepancy"
    assert strict.verdict_decided_by == "floor"


def test_every_field_has_a_test():
    """Each field of ``Settings`` is changed by a test of this module (by its name)."""
    tested = {name[len("test_"):] for name in globals() if name.startswith("test_")}
    missing = [f for f in sorted(FIELDS)
               if f not in tested and not any(f in name.split("_and_") for name in tested)]
    assert missing == []


def _record(travel: float, turn: float) -> ForceNoise:
    return ForceNoise((0.1,) * 6, "noise record", "noise record r.csv", motion=(travel, turn))


def test_record_travel():
    record = _record(2e-3, 0.0)
    with pytest.raises(InputError, match="moves 0.002 m"):
        record.check_at_rest(Settings().record_travel, Settings().record_turn)
    wide = Settings(record_travel=5e-3)
    record.check_at_rest(wide.record_travel, wide.record_turn)


def test_record_turn():
    record = _record(0.0, 2e-3)
    with pytest.raises(InputError, match="turns 0.002 rad"):
        record.check_at_rest(Settings().record_travel, Settings().record_turn)
    wide = Settings(record_turn=5e-3)
    record.check_at_rest(wide.record_travel, wide.record_turn)


def test_noise_spread():
    forces = np.random.default_rng(4).normal(40.0, 1.0, (500, 6))
    noise = _record(0.0, 0.0)                         # 0.1 N against a spread of 1 N
    noise.check_plausible(forces, Settings().noise_spread)
    with pytest.raises(InputError, match="implausible"):
        noise.check_plausible(forces, Settings(noise_spread=(0.5, 10.0)).noise_spread)

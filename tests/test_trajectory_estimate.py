"""The motion estimated from noisy poses: closed-form motions whose derivatives are known,
differentiated from their noisy samples; the force error of the true model evaluated on the
estimate must stay well below the force noise (docs/explanation/discovery.md, "The motion estimate")."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal
from scipy.spatial.transform import Rotation

import gsfric.signal.windows as windows
from gsfric.errors import InputError
from gsfric.models import minimum_jerk_moves, reference_platform
from gsfric.signal.noise import white_noise_std
from gsfric.signal.rotations import quaternion_from_rotation
from gsfric.signal.savgol import savgol_filter
from gsfric.signal.windows import adaptive_filters, gcv_window, motion_filters, savgol_adaptive
from gsfric.synth import read_forces
from gsfric.trajectory import Motion

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

AXIS = np.array([2.0, -1.0, 2.0]) / 3
R0 = Rotation.from_euler("zxz", [0.3, 0.2, -0.4]).as_matrix()
FORCE_NOISE = 0.2
"""Force noise, N, against which the motion estimate's force error is judged."""


def chirp(t: np.ndarray, f0, f1, amplitude, phase):
    """Linear chirps from f0 to f1 Hz over t (columns): value, first, second derivative."""
    t = t[:, None]
    span = t[-1, 0] - t[0, 0]
    angle = 2 * np.pi * (f0 * t + (f1 - f0) * t ** 2 / (2 * span)) + phase
    rate = 2 * np.pi * (f0 + (f1 - f0) * t / span)
    slope = 2 * np.pi * (f1 - f0) / span
    s, c = np.sin(angle), np.cos(angle)
    return amplitude * s, amplitude * c * rate, amplitude * (c * slope - s * rate ** 2)


def chirp_motion(rng, samples: int, rate: float, high: float, height: float = 0.95) -> Motion:
    """Position chirps on x, y, z and a rotation chirp about a fixed axis, from 0.05-0.2 Hz up
    to ``high`` Hz, with their exact derivatives (omega = angle' AXIS in the base frame)."""
    t = np.arange(samples) / rate
    f0, f1 = rng.uniform(0.05, 0.2, 4), high * rng.uniform(0.8, 1.0, 4)
    value, first, second = chirp(t, f0, f1, np.array([0.03, 0.03, 0.02, 0.05]),
                                 rng.uniform(0, 2 * np.pi, 4))
    rotation = Rotation.from_rotvec(value[:, 3:] * AXIS).as_matrix() @ R0
    return Motion.from_arrays(t, value[:, :3] + [0.0, 0.0, height], rotation, first[:, :3],
                              first[:, 3:] * AXIS, second[:, :3], second[:, 3:] * AXIS)


def noisy_poses(rng, motion: Motion, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions with N(0, sigma^2) noise, m, and quaternions turned by random rotation
    vectors of N(0, sigma^2) components, rad."""
    n = len(motion)
    position = motion.position + rng.normal(0.0, sigma, (n, 3))
    rotation = Rotation.from_rotvec(rng.normal(0.0, sigma, (n, 3))).as_matrix() \
        @ motion.rotation
    return position, quaternion_from_rotation(rotation)


def force_error(platform, exact: Motion, estimate: Motion) -> float:
    """RMS over the interior (a twentieth left out at each end) of the forces of the true
    model on the estimated motion minus those on the exact motion, N."""
    n = len(exact)
    inner = slice(n // 20, n - n // 20)
    e = (read_forces(platform, estimate) - read_forces(platform, exact))[inner]
    return float(np.sqrt(np.mean(e ** 2)))


def heavy():
    ref = reference_platform(friction_model="paper")
    return ref.with_body(payload_mass=1.5 * ref.platform.payload_mass).with_friction(
        prismatic_viscous=2 * ref.friction.prismatic_viscous)


@pytest.mark.parametrize("platform, rate, high, seed", [
    (reference_platform(friction_model="paper"), 200.0, 2.0, 0),
    (reference_platform(friction_model="paper"), 200.0, 2.0, 1),
    (heavy(), 200.0, 3.0, 2),
    (reference_platform(friction_model="paper"), 500.0, 4.0, 3),
])
def test_chirp_true_model_within_the_noise(platform, rate, high, seed):
    """On a chirp up to the band the pose sampling supports (1e-5 pose noise), the true model
    on the estimated motion leaves a residual within 1.15 times a 0.2 N force noise:
    sqrt(noise^2 + error^2) <= 1.15 noise, an error below 0.57 times the noise."""
    rng = np.random.default_rng(seed)
    exact = chirp_motion(rng, 3000, rate, high)
    position, quaternion = noisy_poses(rng, exact, 1e-5)
    estimate = Motion.from_samples(exact.t, position, quaternion=quaternion)
    error = force_error(platform, exact, estimate)
    assert np.hypot(FORCE_NOISE, error) <= 1.15 * FORCE_NOISE, error


def test_local_choice_beats_every_single_window():
    """A chirp's content changes along the record: no single window suits all of it. The
    per-sample choice gives a smaller force error than the best fixed window of order 4
    (and than the generalized cross-validation window of the smoothed pose)."""
    rng = np.random.default_rng(5)
    platform = reference_platform(friction_model="paper")
    exact = chirp_motion(rng, 3000, 200.0, 3.0)
    position, quaternion = noisy_poses(rng, exact, 1e-5)
    adaptive = force_error(platform, exact,
                           Motion.from_samples(exact.t, position, quaternion=quaternion))
    fixed = {w: force_error(platform, exact, Motion.from_samples(
        exact.t, position, quaternion=quaternion, window=w)) for w in range(21, 122, 10)}
    assert adaptive < 0.8 * min(fixed.values()), (adaptive, fixed)
    gcv = gcv_window(position, 4)
    assert adaptive < 0.8 * force_error(platform, exact, Motion.from_samples(
        exact.t, position, quaternion=quaternion, window=gcv))


def test_windows_follow_the_frequency_and_the_noise():
    """Long windows where the chirp is slow, short ones where it is fast; shorter for the
    velocity than for the acceleration; the shortest for noise-free samples; longer for more
    noise."""
    rng = np.random.default_rng(3)
    exact = chirp_motion(rng, 3000, 200.0, 3.0)
    position, _ = noisy_poses(rng, exact, 1e-5)
    (_, w1), (_, w2) = motion_filters(position)
    fifth = len(position) // 5
    assert np.median(w2[:fifth]) >= 1.5 * np.median(w2[-fifth:])
    assert np.median(w1) <= np.median(w2)
    _, clean = adaptive_filters(exact.position, deriv=2)
    assert np.median(clean) < np.median(w2)
    louder, _ = noisy_poses(np.random.default_rng(3), exact, 1e-4)
    _, loud = adaptive_filters(louder, deriv=2)
    assert np.median(loud) > np.median(w2)


@pytest.mark.parametrize("sigma", [1e-6, 1e-5, 1e-4])
def test_white_noise_std_recovers_the_pose_noise(sigma):
    """The noise estimate behind the filter choice and the speed band: within 10 % on a
    resolved motion, and (almost) nothing on noise-free samples."""
    rng = np.random.default_rng(7)
    exact = chirp_motion(rng, 4000, 200.0, 2.0)
    position, _ = noisy_poses(rng, exact, sigma)
    np.testing.assert_allclose(white_noise_std(position), sigma, rtol=0.1)
    assert np.all(white_noise_std(exact.position) < 1e-8)


def test_white_noise_of_a_log_whose_rests_read_one_value():
    """Moves and rests logged at 0.1 um (mm with four decimals), rests three quarters of the
    record: every rest reads one value, and the noise is that of the rounding in the moves,
    resolution / sqrt(12), not zero (the median of the differences, most of them zero)."""
    rng = np.random.default_rng(3)
    t = np.arange(6000) / 500.0
    targets = rng.uniform(-0.02, 0.02, (7, 3)) + [0.0, 0.0, 0.9]
    moves = minimum_jerk_moves(t, targets, period=2.0, move=0.5)
    resolution = 1e-7
    logged = np.round(moves.position / resolution) * resolution
    at_rest = np.all(np.diff(logged, axis=0) == 0.0, axis=1).mean()
    assert at_rest > 0.6
    np.testing.assert_allclose(white_noise_std(logged), resolution / np.sqrt(12), rtol=0.15)


@pytest.mark.parametrize("cap", [801, 1601])
def test_windows_spanning_a_triangle_waves_corners_are_not_chosen(monkeypatch, cap):
    """Two windows that both span the corners of a triangle wave are wrong alike and differ
    little; the choice must not take them for unbiased. Longer candidate windows leave the
    acceleration error of the windows up to 201 samples (without the detected-bias rule, 801
    samples gave nine times that error)."""
    rng = np.random.default_rng(5)
    rate = 476.0
    t = np.arange(int(8 * rate)) / rate
    f = rng.uniform(0.15, 0.6, 3)
    phase = rng.uniform(0, 2 * np.pi, 3)
    # arcsin of a slightly shrunk sine: a triangle wave with rounded corners
    position = 0.02 * 2 / np.pi * np.arcsin(0.995 * np.sin(2 * np.pi * f * t[:, None] + phase))
    acceleration = np.gradient(np.gradient(position, t, axis=0), t, axis=0)
    recorded = position + rng.normal(0.0, 1e-5, position.shape)

    def error(longest):
        monkeypatch.setattr(windows, "MAX_AUTO_WINDOW", longest)
        filters = motion_filters(recorded)
        estimate = savgol_adaptive(recorded, filters, 1 / rate)[2]
        inner = slice(len(t) // 20, -len(t) // 20)
        return float(np.sqrt(np.mean((estimate - acceleration)[inner] ** 2)))

    assert error(cap) < 1.1 * error(201)


def test_jittered_log_times_are_differentiated_on_their_own_time_base():
    """A log whose sample times jitter (+-20 % of the step) is differentiated on its actual
    times (smoothing spline): its velocity error is well below that of pretending the times
    were uniform (a pose error of the speed times the jitter)."""
    rng = np.random.default_rng(11)
    step = 1 / 200.0
    t = np.arange(2000) * step + rng.uniform(-0.2, 0.2, 2000) * step
    t[0] = 0.0
    angle = 0.05 * np.sin(2 * np.pi * 0.7 * t)
    position = np.stack([0.03 * np.sin(2 * np.pi * 0.5 * t), 0.02 * np.cos(2 * np.pi * t),
                         0.95 + 0 * t], axis=1)
    velocity = np.stack([0.03 * np.pi * np.cos(2 * np.pi * 0.5 * t),
                         -0.04 * np.pi * np.sin(2 * np.pi * t), 0 * t], axis=1)
    rotation = Rotation.from_rotvec(angle[:, None] * AXIS).as_matrix() @ R0
    noisy = position + rng.normal(0, 1e-5, position.shape)
    motion = Motion.from_samples(t, noisy, quaternion=quaternion_from_rotation(rotation))
    inner = slice(100, -100)
    error = np.sqrt(np.mean((motion.velocity - velocity)[inner] ** 2))
    assert error < 5e-4
    as_if_uniform = Motion.from_samples(np.arange(2000) * step, noisy,
                                        quaternion=quaternion_from_rotation(rotation))
    assert error < 0.75 * np.sqrt(np.mean((as_if_uniform.velocity - velocity)[inner] ** 2))


@pytest.mark.parametrize("rate", [1000.0, pytest.param(2000.0, marks=pytest.mark.slow)])
def test_jittered_kilohertz_log_keeps_its_accelerations(rate):
    """On a 1-2 kHz log with jittered times (+-10 % of the step) the spline's penalty is chosen
    for the acceleration: a motion of 0.3, 1 and 3 Hz on its three axes keeps its accelerations
    within 1 % of the largest amplitude, as on a uniform time base (a penalty that minimises the
    position's cross-validation error, searched over a linear range, flattened the 1 and 3 Hz
    axes: errors of their full amplitude)."""
    rng = np.random.default_rng(5)
    n = int(10 * rate)
    t = np.arange(n) / rate + rng.uniform(-0.1, 0.1, n) / rate
    f = np.array([0.3, 1.0, 3.0])
    position = 0.03 * np.sin(2 * np.pi * f * t[:, None]) + [0.0, 0.0, 0.9]
    acceleration = -0.03 * (2 * np.pi * f) ** 2 * np.sin(2 * np.pi * f * t[:, None])
    quaternion = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    inner = slice(n // 20, -n // 20)
    for sigma in (1e-6, 1e-5):
        noisy = position + rng.normal(0, sigma, position.shape)
        motion = Motion.from_samples(t, noisy, quaternion=quaternion)
        error = np.sqrt(np.mean((motion.acceleration - acceleration)[inner] ** 2, axis=0))
        amplitude = 0.03 * (2 * np.pi * f) ** 2
        assert np.all(error < 0.01 * amplitude.max()), (sigma, error)


def test_log_of_microsecond_stamps_and_rounded_positions_with_rests():
    """A 1946 Hz log whose times are whole microseconds (so not uniform to 1e-4 of the step) and
    whose positions are rounded to 0.1 um, moves between rests: the rests read exactly the same
    value, and the noise behind the spline's penalty is that of the samples that change (a
    noise of zero from the rests chose no smoothing: accelerations of tens of m/s^2)."""
    rate, move, rest = 1946.0, 0.6, 1.5
    t = np.round(np.arange(int(8 * rate)) / rate * 1e6) / 1e6
    period = move + rest
    k = (t // period).astype(int)
    s = np.clip((t - k * period) / move, 0.0, 1.0)
    moving = (t - k * period) < move
    step = np.where(k % 2 == 0, 0.03, -0.03)
    x = np.where(k % 2 == 0, 0.0, 0.03) + step * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)
    a = step * (60 * s - 180 * s ** 2 + 120 * s ** 3) / move ** 2 * moving
    position = np.round(np.c_[x, 0 * x, 0.9 + 0 * x] / 1e-7) * 1e-7
    motion = Motion.from_samples(t, position, quaternion=np.tile([1.0, 0, 0, 0], (len(t), 1)))
    inner = slice(len(t) // 20, -len(t) // 20)
    error = np.sqrt(np.mean((motion.acceleration[:, 0] - a)[inner] ** 2))
    assert error < 0.01 * np.abs(a).max()


def test_repeated_time_stamp_names_the_row():
    t = np.arange(50) / 100.0
    t[17] = t[16]
    position = np.zeros((50, 3)) + [0.0, 0.0, 0.95]
    quaternion = np.tile([1.0, 0.0, 0.0, 0.0], (50, 1))
    with pytest.raises(InputError, match=r"^log.csv: row 18: t does not increase$"):
        Motion.from_samples(t, position, quaternion=quaternion, source="log.csv")


@pytest.mark.parametrize("window", [7, 31, 101])
@pytest.mark.parametrize("deriv", [0, 1, 2])
def test_savgol_filter_is_scipys_where_scipys_is_exact(window, deriv):
    """Order 4, short windows: scipy.signal.savgol_filter (mode "interp") to rounding."""
    y = np.cumsum(np.random.default_rng(window + deriv).normal(size=(300, 3)), axis=0)
    expected = signal.savgol_filter(y, window, 4, deriv=deriv, axis=0, mode="interp")
    np.testing.assert_allclose(savgol_filter(y, window, 4, deriv), expected,
                               rtol=0, atol=1e-9 * np.abs(expected).max())


@pytest.mark.parametrize("window", [201, 401, 1601])
@pytest.mark.parametrize("deriv", [0, 1, 2])
def test_long_savgol_windows_reproduce_the_polynomials_of_their_order(window, deriv):
    """A polynomial of order 6 and its derivatives come back exactly from the order-6 filter,
    at the ends as in the middle, however long the window (scipy's weights of the value are
    zero at 401 samples)."""
    n = 3 * window
    x = (np.arange(n) - n / 2) / n
    coefficients = np.array([0.3, -1.0, 2.0, 0.5, -4.0, 1.0, 7.0])
    y = np.polynomial.polynomial.polyval(x, coefficients)
    exact = np.polynomial.polynomial.polyval(
        x, np.polynomial.polynomial.polyder(coefficients, deriv)) / n**deriv
    got = savgol_filter(y[:, None], window, 6, deriv)[:, 0]
    np.testing.assert_allclose(got, exact, rtol=0, atol=1e-9 * np.abs(exact).max())


def _gcv_by_filtering(y, polyorder):
    """The generalized cross-validation window by filtering with every candidate."""
    candidates = windows.candidate_windows(len(y), polyorder)
    return candidates[int(np.argmin([windows._gcv_score(y, w, polyorder)
                                     for w in candidates]))]


@pytest.mark.parametrize("noise", [0.0, 1e-15, 1e-9, 1e-7, 1e-6, 1e-4])
@pytest.mark.parametrize("shape", [(3000,), (4000, 3),
                                   pytest.param((20_000, 4), marks=pytest.mark.slow)])
def test_gcv_window_is_the_window_filtering_gives(noise, shape):
    """The scores from the spectrum and from transforms, with their rounding bounds, leave
    the window that filtering with every candidate gives: on noise-free samples
    (rounding-level residuals), at the rounding's level, and with noise."""
    rng = np.random.default_rng(int(noise * 1e15) % 1000 + shape[0])
    t = np.arange(shape[0]) / 500.0
    columns = shape[1] if len(shape) > 1 else 1
    y = np.stack([0.7 + 0.05 * np.sin(2 * np.pi * rng.uniform(0.1, 3) * t + rng.uniform(0, 6))
                  + rng.uniform(-0.2, 0.2) * t for _ in range(columns)], axis=1).reshape(shape)
    y = y + noise * rng.standard_normal(shape)
    for polyorder in (2, 4):
        assert gcv_window(y, polyorder) == _gcv_by_filtering(y, polyorder)


def test_gcv_window_needs_a_window():
    with pytest.raises(ValueError, match="fewer than the shortest window"):
        gcv_window(np.ones(4), 4)


@pytest.mark.parametrize("outlier", [1.2e154, 1e300])
def test_gcv_window_of_squares_beyond_the_float_range_is_the_filtering_one(outlier):
    """A sample so large that its squares overflow: the window filtering with every candidate
    gives, not an error."""
    y = 0.7 + 0.01 * np.sin(np.arange(300) / 20.0)
    y[0] = outlier
    with np.errstate(over="ignore", invalid="ignore"):
        assert gcv_window(y, 2) == _gcv_by_filtering(y, 2)

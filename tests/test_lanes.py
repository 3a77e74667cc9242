"""The builds of the compiled model change no result beyond rounding.

The SIMD-over-steps code (derive/simd.py) is printed once and compiled when the package is
built, on x86-64 for three instruction sets (meson.build): the baseline (1 step per lane),
x86-64-v3 (AVX2: 4) and x86-64-v4 (AVX-512: 8). Each build is loaded in this process; the
tests cover every build that this CPU runs.
"""

from __future__ import annotations

import ctypes

import numpy as np
import pytest
from helpers import numpy_flags, perturbed_platform, random_states, with_every_effect
from scipy.spatial.transform import Rotation

from derive.build import SIMD_FUNCTIONS, SIMD_SEPARATE

from gsfric import models
from gsfric.compiled import native
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.trajectory import Motion

FUNCTIONS = (*SIMD_FUNCTIONS, *SIMD_SEPARATE)
"""The SIMD-over-steps functions (derive/build.py): the generic map, the fixed models' and the
parameter Jacobian."""
BUILDS = native.cpu_builds()
"""The builds installed that this CPU runs (on an AVX-512 machine: 8 and 4 lanes and the x86-64
baseline's per-step functions)."""
SIMD_BUILDS = [isa for isa in BUILDS if native.lanes(native.library(isa))]
"""Those with SIMD-over-steps code."""
LANES = {"baseline": 0, "x86-64-v3": 4, "x86-64-v4": 8}


def _evaluate(isa: str, x, P, Q) -> dict:
    return {f"{name}:{k}": v for name in FUNCTIONS
            for k, v in native.get(name, isa)([x, P, Q]).items()}


OTHER_BUILDS = [isa for isa in BUILDS if isa != "baseline"] or [
    pytest.param(None, marks=pytest.mark.skip(reason="this CPU runs only the baseline build"))]


@pytest.mark.parametrize("isa", BUILDS)
def test_each_build_has_its_lane_width(isa):
    if native.build_path("x86-64-v3") is None:
        pytest.skip("not x86-64: one build, its lane width its own")
    assert native.lanes(native.library(isa)) == LANES[isa]


@pytest.mark.parametrize("isa", OTHER_BUILDS)
def test_every_build_agrees_with_the_baseline(isa):
    rng = np.random.default_rng(8)
    platform = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 203)  # not a multiple of any lane width: the last group is partial
    ev = Evaluator(platform)
    baseline = _evaluate("baseline", x, ev.P, ev.Q)
    other = _evaluate(isa, x, ev.P, ev.Q)
    for name, value in baseline.items():
        function = name.split(":")[0]
        # the last change of a converged iteration is rounding: measured against F0
        reference = baseline.get(f"{function}:F0", value) \
            if name.endswith(":coupling_change") else value
        scale = max(np.abs(reference).max(), 1e-300)
        np.testing.assert_allclose(other[name], value, rtol=0, atol=1e-12 * scale,
                                   err_msg=name)


def test_the_widest_build_is_loaded_by_default():
    assert native.chosen_build() == BUILDS[0]
    assert native.library()._name == native.library(BUILDS[0])._name == \
        str(native.build_path(BUILDS[0]))


@pytest.mark.parametrize("isa", SIMD_BUILDS)
def test_vector_exp_is_within_two_ulp_of_the_c_library(isa):
    lib = native.library(isa)
    x = np.concatenate([np.linspace(-745, 710, 200_001), np.random.default_rng(3).normal(
        0, 5, 100_000), [0.0, -0.0, 1e-300, -1e-300, 709.78, -708.39]])
    y = np.empty_like(x)
    lib.gsfric_simd_exp(x.ctypes.data_as(ctypes.c_void_p), y.ctypes.data_as(ctypes.c_void_p),
                        ctypes.c_longlong(x.size))
    with np.errstate(over="ignore", under="ignore"):
        ref = np.exp(x)
    normal = (ref >= np.finfo(float).tiny) & np.isfinite(ref)
    ulp = np.abs(y[normal] - ref[normal]) / np.spacing(ref[normal])
    assert ulp.max() <= 2, ulp.max()
    assert (y[x > 709.79] == np.inf).all() and (y[x < -708.4] == 0).all()
    special = np.array([np.inf, -np.inf, np.nan])
    out = np.empty(3)
    lib.gsfric_simd_exp(special.ctypes.data_as(ctypes.c_void_p),
                        out.ctypes.data_as(ctypes.c_void_p), ctypes.c_longlong(3))
    assert out[0] == np.inf and out[1] == 0 and np.isnan(out[2])


def test_flags_in_c_equal_the_numpy_flags():
    """The step flags computed in C (compiled/batch.c) and in NumPy from the outputs
    (``numpy_flags``) on steps with every cause: stroke, singular pose, non-finite."""


    n = 40
    angles = np.linspace(1.2, 1.9, n)
    angles[20] = np.pi / 2                               # the singular pose
    rotation = Rotation.from_rotvec(angles[:, None] * [0.0, 0.0, 1.0]).as_matrix()
    position = np.tile([0.0, 0.0, models.HOME_HEIGHT], (n, 1))
    position[5] = [0.0, 0.0, 1.4]                        # beyond the stroke
    position[9] = [1e200, 0.0, 1e200]                    # overflowing outputs
    zeros = np.zeros((n, 3))
    motion = Motion(np.arange(n) * 0.01, position, rotation, zeros, zeros, zeros, zeros)
    ev = Evaluator(models.reference_platform())
    result = ev.evaluate_quiet(motion)
    assert all((result.flag & bit).any() for bit in (1, 2, 4)) and (result.flag == 0).any()
    raw = native.get("eval")([state_array(motion), ev.P, ev.Q])
    stroke = ev.platform.geometry.stroke
    np.testing.assert_array_equal(numpy_flags(state_array(motion), raw, stroke), result.flag)
    for name, value in raw.items():                      # NaN where flagged non-finite
        np.testing.assert_array_equal(value.reshape(result.arrays[name].shape),
                                      result.arrays[name])


def _divider(lib, op, a, b):
    a, b = np.ascontiguousarray(a, float), np.ascontiguousarray(b, float)
    y = np.empty_like(a)
    lib.gsfric_simd_divider(ctypes.c_int(op), a.ctypes.data_as(ctypes.c_void_p),
                            b.ctypes.data_as(ctypes.c_void_p), y.ctypes.data_as(ctypes.c_void_p),
                            ctypes.c_longlong(a.size))
    return y


@pytest.mark.parametrize("isa", SIMD_BUILDS)
def test_vector_division_and_square_roots_against_the_ieee_operations(isa):
    """a / b, 1 / b, sqrt(a) and 1 / sqrt(a) as the SIMD code computes them (off the divider on
    AVX-512: estimate, Newton steps, a final correction) on random operands of every magnitude,
    subnormal to huge, significands near 2 included, and on 0, inf, NaN, negative operands.
    a / b and sqrt(a) equal the IEEE operations bit for bit, sign of zero included. 1 / b and
    1 / sqrt(a) are within 1 ulp of the correctly rounded ones (the final Newton step of a
    reciprocal can miss by 1 ulp where the significand of its operand is within about 1000 ulp
    of 2: measured 0.1 % of such operands); results that are 0, inf or NaN are exact."""
    lib = native.library(isa)
    rng = np.random.default_rng(13)
    n = 400_000

    def magnitudes():
        significand = np.where(rng.random(n) < 0.1, 2.0 - rng.integers(1, 1000, n) * 2.0 ** -52,
                               rng.uniform(1, 2, n))
        return rng.choice([-1.0, 1.0], n) * np.ldexp(significand, rng.integers(-1075, 1024, n))

    special = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, -5e-324, 2.2e-308,
                        np.finfo(float).max, -1.0, 1.0, 3.0, 1e-310, 1e300, 1e-300, 2.0 ** -960])
    sa, sb = (g.ravel() for g in np.meshgrid(special, special))
    a = np.concatenate([magnitudes(), sa, rng.normal(size=1000)])
    b = np.concatenate([magnitudes(), sb, rng.normal(size=1000)])
    with np.errstate(all="ignore"):
        expected = {0: (a / b, 0), 1: (1.0 / b, 1), 2: (np.sqrt(a), 0), 3: (1.0 / np.sqrt(a), 1)}
        for op, (ref, ulp) in expected.items():
            y = _divider(lib, op, a, b)
            same = ((y == ref) & (np.signbit(y) == np.signbit(ref))) | (np.isnan(y) & np.isnan(ref))
            close = np.isfinite(ref) & (np.abs(y - ref) <= ulp * np.spacing(np.abs(ref)))
            ok = same | close
            assert ok.all(), (op, a[~ok][:3], b[~ok][:3], y[~ok][:3], ref[~ok][:3])
            special_result = ~np.isfinite(ref) | (ref == 0)       # inf, NaN, signed zero: exact
            assert same[special_result].all(), (op, a[special_result & ~same][:3])

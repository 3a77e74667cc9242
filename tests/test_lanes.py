"""The lane width and the target CPU chosen at build time change no result beyond rounding.

The SIMD-over-steps code (derive/simd.py) is printed once and compiled with a lane width
chosen for the CPU (8 with AVX-512, 4 with AVX, 1 otherwise) or forced with ``GSFRIC_LANES``;
a portable build targets ``GSFRIC_MARCH=x86-64-v3``. Each build is made in a subprocess (the
flags are read at import) into the usual cache, so that it is compiled once per machine.
"""

from __future__ import annotations

import ctypes
import os
import subprocess
import sys

import numpy as np
import pytest
from helpers import perturbed_platform, random_states, with_every_effect
from scipy.spatial.transform import Rotation

from gsfric import models
from gsfric.compiled import native
from gsfric.evaluation.evaluator import Evaluator, state_array
from gsfric.evaluation.flags import numpy_flags
from gsfric.trajectory import Motion

SCRIPT = """
import sys, numpy as np
from gsfric.compiled import native
from gsfric.evaluation.evaluator import Evaluator
from gsfric.evaluation.parameters import parameter_vector
x, P, Q = (np.load(sys.argv[1])[k] for k in ("x", "P", "Q"))
lib = native._library()
assert native.is_compiled()
res = {f"{name}:{k}": v for name in FUNCTIONS
       for k, v in native.get(name)([x, P, Q]).items()}
np.savez(sys.argv[2], lanes=lib.gsfric_simd_lanes(), **res)
"""
FUNCTIONS = ("eval", "eval_coupled", "eval_posthoc", "actuator_coupled", "actuator_posthoc")
"""The SIMD-over-steps functions (derive/build.py): the generic map and the fixed models'."""


def _variant(tmp_path, env_extra, x, P, Q):
    np.savez(tmp_path / "in.npz", x=x, P=P, Q=Q)
    env = dict(os.environ, **env_extra)
    subprocess.run([sys.executable, "-c", f"FUNCTIONS = {FUNCTIONS!r}\n{SCRIPT}",
                    str(tmp_path / "in.npz"),
                    str(tmp_path / "out.npz")], env=env, check=True, timeout=600)
    return dict(np.load(tmp_path / "out.npz"))


@pytest.mark.skipif(not native.is_compiled(), reason="no C compiler")
@pytest.mark.parametrize("env, lanes", [({"GSFRIC_LANES": "1"}, 1), ({"GSFRIC_LANES": "4"}, 4),
                                        ({"GSFRIC_MARCH": "x86-64-v3"}, 4)])
def test_lane_widths_and_portable_build_agree_with_the_native_build(tmp_path, env, lanes):
    rng = np.random.default_rng(8)
    platform = with_every_effect(rng, perturbed_platform(rng))
    x = random_states(rng, 203)  # not a multiple of any lane width: the last group is partial
    ev = Evaluator(platform)
    native_res = {f"{name}:{k}": v for name in FUNCTIONS
                  for k, v in native.get(name)([x, ev.P, ev.Q]).items()}
    other = _variant(tmp_path, env, x, ev.P, ev.Q)
    assert int(other.pop("lanes")) == lanes
    for name, value in native_res.items():
        function = name.split(":")[0]
        # the last change of a converged iteration is rounding: measured against F0
        reference = native_res.get(f"{function}:F0", value) \
            if name.endswith(":coupling_change") else value
        scale = max(np.abs(reference).max(), 1e-300)
        np.testing.assert_allclose(other[name], value, rtol=0, atol=1e-12 * scale,
                                   err_msg=name)


@pytest.mark.skipif(not native.is_compiled(), reason="no C compiler")
def test_vector_exp_is_within_two_ulp_of_the_c_library():
    lib = native._library()
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


@pytest.mark.skipif(not native.is_compiled(), reason="no C compiler")
def test_flags_in_c_equal_the_fallbacks_numpy_flags():
    """The step flags computed in C (compiled/batch.c) and those of the no-compiler fallback
    (``numpy_flags``, NumPy) on steps with every cause: stroke, singular pose, non-finite."""


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


@pytest.mark.skipif(not native.is_compiled(), reason="no C compiler")
def test_vector_division_and_square_roots_against_the_ieee_operations():
    """a / b, 1 / b, sqrt(a) and 1 / sqrt(a) as the SIMD code computes them (off the divider on
    AVX-512: estimate, Newton steps, a final correction) on random operands of every magnitude,
    subnormal to huge, significands near 2 included, and on 0, inf, NaN, negative operands.
    a / b and sqrt(a) equal the IEEE operations bit for bit, sign of zero included. 1 / b and
    1 / sqrt(a) are within 1 ulp of the correctly rounded ones (the final Newton step of a
    reciprocal can miss by 1 ulp where the significand of its operand is within about 1000 ulp
    of 2: measured 0.1 % of such operands); results that are 0, inf or NaN are exact."""
    lib = native._library()
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

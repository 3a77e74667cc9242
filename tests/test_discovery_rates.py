"""The records of benchmarks/discovery_rates.py: rig faults outside the catalog (lines, dead
bands, hysteresis, cross-talk, drift) under white, AR and pink noise, and null records. A
small subset in the default suite; the faults over two motions each and a set of nulls behind
``slow``."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def rates():
    spec = importlib.util.spec_from_file_location(
        "discovery_rates", ROOT / "benchmarks" / "discovery_rates.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module       # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_the_noise_kinds_have_the_noise_level_and_their_colour(rates):
    rng = np.random.default_rng(0)
    white, ar, pink = (rates.force_noise(kind, rng, 8000, 0.2) for kind in rates.NOISES)
    for x in (white, ar, pink):
        assert x.std(axis=0) == pytest.approx(np.full(6, 0.2), rel=1e-6)

    def lag1(x):
        return float(np.mean(np.sum(x[1:] * x[:-1], 0) / np.sum(x * x, 0)))

    assert abs(lag1(white)) < 0.05 and lag1(ar) == pytest.approx(0.9, abs=0.03)
    assert lag1(pink) > 0.5


def test_a_dead_band_in_one_load_cell_is_unexplained(rates):
    result, noise, _ = rates.one_case("fault", ["dead_band"], "rests", "reference", "ar", 3.0,
                                      7, 3000)
    assert not result.names or result.verdict == "unexplained_discrepancy"
    assert result.verdict == "unexplained_discrepancy"
    assert "sensor memory" in [s.kind for s in result.structures]


@pytest.mark.slow
def test_faults_are_unexplained_and_nulls_name_nothing(rates):
    unexplained, total = 0, 0
    for k, name in enumerate(rates.FAULTS):
        for j, family in enumerate(("rests", "sines")):
            result, _, _ = rates.one_case("fault", [name], family, ("reference", "heavy")[j],
                                          rates.NOISES[(k + j) % 3], 3.0, 100 + 2 * k + j,
                                          6000)
            unexplained += result.verdict == "unexplained_discrepancy"
            total += 1
            assert not (result.names and result.verdict == "explained")
    assert unexplained >= 0.9 * total
    for seed, noise in enumerate(rates.NOISES * 2):
        result, _, _ = rates.one_case("null", [], ("rests", "sines")[seed % 2], "reference",
                                      noise, 0.0, 200 + seed, 6000)
        assert result.names == []

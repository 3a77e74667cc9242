"""One name for one quantity: a column ``X1..X6`` of ``Result.to_frame()`` and of
``simulate``'s files holds ``Result.X``; the friction that loads the actuators is in the
default output, and the paper's post-hoc scalars carry the suffix ``_s``."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import gsfric
from gsfric import models
from gsfric.cli import main
from gsfric.evaluation.columns import COLUMNS, DEFAULT_GROUPS, GROUPS, plan
from gsfric.io.readers import read_trajectory
from gsfric.io.tables import read_table, write_table

CONTRACT_NAMES = {"RE": "R_E", "RC": "R_C", "MC": "M_C"}
"""Column families whose names the file contract fixes, and the Result array each holds."""


@pytest.fixture(scope="module")
def result():
    # a sliding motion on the reference platform: seal friction loads the actuators while the
    # paper's post-hoc scalar of (35) stays small, so the two prismatic frictions differ; its
    # poses differentiated, so that the Result has sigma_F and rest too
    frame = models.sinusoidal(np.linspace(0.0, 2.0, 201)).to_frame()
    return gsfric.evaluate(models.reference_platform(), frame)


def _families(columns) -> dict[str, list[str]]:
    """{base name: [its six columns]} of the per-leg scalar families ``X1..X6``, ``X_1..X_6``."""
    found: dict[str, list[str]] = {}
    for name in columns:
        match = re.fullmatch(r"(.+?)_?([1-6])", name)
        if match and not re.fullmatch(r".+[xyz]", match.group(1)):
            found.setdefault(match.group(1), []).append(name)
    return {k: v for k, v in found.items() if len(v) == 6}


def test_every_per_leg_array_written_as_x1_x6_holds_the_same_values(result):
    frame = result.to_frame()
    families = _families(frame.columns)
    assert {"F", "Ffr", "Ffr_s", "MfrE_s", "MfrC_s", "F0", "D", "F_joint", "sigma_F"} <= set(families)
    for base, names in families.items():
        array = CONTRACT_NAMES.get(base, base)
        assert array in result.arrays, f"column {names[0]} has no Result.{base}"
        values = getattr(result, array)
        assert values.shape == (len(result), 6), base
        np.testing.assert_array_equal(frame[names].to_numpy(), values, err_msg=base)
        if base in CONTRACT_NAMES:
            assert base not in result.arrays        # no Result array of another meaning
    # and the other way: every (N, 6) array of the Result that is a column is under its name
    written = {c.array for c in COLUMNS if c.array is not None}
    for name in written:
        values = result.arrays[name]
        if values.shape == (len(result), 6) and name not in CONTRACT_NAMES.values():
            assert name in families, name


def test_vector_columns_hold_the_result_arrays_components(result):
    frame = result.to_frame()
    for base, array in (("MfrE", "MfrE"), ("MfrC", "MfrC"), ("RE", "R_E"), ("RC", "R_C")):
        for i in range(1, 7):
            for j, axis in enumerate("xyz"):
                np.testing.assert_array_equal(frame[f"{base}{axis}{i}"],
                                              getattr(result, array)[:, i - 1, j])


def test_the_friction_that_loads_the_actuators_is_in_the_default_output(result):
    default = {name for name, _, _, _ in plan(DEFAULT_GROUPS)}
    assert {f"Ffr{i}" for i in range(1, 7)} <= default
    assert {f"Ffr_s{i}" for i in range(1, 7)} <= default
    # the two differ on this motion: the post-hoc scalar is not what loads the actuator
    assert np.max(np.abs(result.Ffr)) > 2 * np.max(np.abs(result.Ffr_s))
    # F = F0 + F_joint - Ffr along each leg (the prismatic friction is the one in F)
    np.testing.assert_allclose(result.F, result.F0 + result.F_joint - result.Ffr,
                               atol=1e-9 * np.abs(result.F).max())
    assert "Ffr1..Ffr6" in GROUPS["friction"] and "FfrS" not in " ".join(GROUPS.values())


def test_simulate_files_use_the_result_names(tmp_path):
    motion = models.sinusoidal(np.linspace(0.0, 2.0, 201))
    write_table(motion.to_frame(), tmp_path / "m.csv")
    platform = models.reference_platform()
    expected = gsfric.evaluate(platform, read_trajectory(tmp_path / "m.csv"))
    for suffix in ("csv", "parquet"):
        out = tmp_path / f"o.{suffix}"
        run = CliRunner().invoke(main, ["simulate", "--trajectory", str(tmp_path / "m.csv"),
                                        "--out", str(out), "--columns", "all"])
        assert run.exit_code == 0, run.output
        written = read_table(out)
        for base, names in _families(written.columns).items():
            values = getattr(expected, CONTRACT_NAMES.get(base, base))
            np.testing.assert_allclose(written[names].to_numpy(), values, rtol=1e-9,
                                       atol=1e-9, err_msg=base)
        assert isinstance(written, pd.DataFrame)

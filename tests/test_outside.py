"""The table of structures outside the catalog (``discovery.outside``) and the mechanisms that
look for them agree: each mechanism looks for exactly the structures the table gives it, and
each finding is put in the table's words."""

from __future__ import annotations

import numpy as np

from gsfric.discovery import dictionary, final_tests, lackfit, outside
from gsfric.discovery.evidence import Structure


def test_the_basis_columns_are_the_tables_basis_signals():
    named = set(lackfit.column_names(pose=3))
    assert named == set(outside.names("basis"))
    rng = np.random.default_rng(0)
    t = np.arange(200) / 100.0
    F, speed = rng.normal(size=(200, 6)), rng.normal(size=(200, 6))
    X = lackfit.basis(t, F, speed, np.ones((200, 6)), pose=rng.normal(size=(200, 6, 3)))
    assert X.shape[2] == len(lackfit.column_names(pose=3))


def test_the_dictionary_builds_each_group_of_the_table_and_no_other():
    assert list(dictionary.BUILDERS) == list(outside.names("dictionary"))


def test_the_final_residual_is_tested_for_each_form_of_the_table():
    tests = [t.name for t in final_tests.STRUCTURE_TESTS if t.name != "basis"]
    assert sorted(tests) == sorted(outside.names("test"))
    assert sorted(final_tests.SUMMARY_ORDER) == sorted(outside.names("test"))


def test_a_finding_is_said_in_the_tables_words():
    by_name = {t.name: t for t in final_tests.STRUCTURE_TESTS}
    found = Structure(significant=True, gap=1.0, p_value=0.0, structure_rms=1.0,
                      per_leg_rms=[1.0] * 6, details={"signals": {"F": 0.2, "F^3": 0.7},
                                                      "variable": "force of leg i+2"})
    assert by_name["basis"].words(found) == ("F^3", outside.entry("basis", "F^3").looks_like)
    shows, looks = by_name["state"].words(found)
    assert shows == "repeats with force of leg i+2" and "crosstalk" in looks
    rest = outside.entry("test", "rest")
    assert by_name["rest"].words(found) == (rest.shows, rest.looks_like)
    assert outside.looks_like("basis", None) == "" == outside.looks_like("basis", "nothing")


def test_the_documentation_table_has_a_row_per_structure():
    rows = outside.markdown_table().splitlines()[2:]
    assert len(rows) == len(outside.OUTSIDE)
    assert all(row.count(" | ") == 3 for row in rows)   # the pipes of F|F| are escaped

"""The fault-injection table: every case of ``cases_*.py`` through the one runner.

Each case asserts its outcome class (a correct result, a correct result with a named warning,
or a one-line error with its exit code), that no traceback was printed, that no input changed
and that nothing was left behind (docs: the reference of exit codes and errors).
"""

from __future__ import annotations

import pytest
from cases_api import api_cases
from cases_env import (
    compiler_cases,
    interrupt_cases,
    stale_cases,
    thread_cases,
    usage_cases,
)
from cases_inputs import good_platform_cases, platform_cases, rig_cases, table_cases
from cases_logs import log_cases
from cases_outputs import output_cases
from runner import check_api_case, check_case

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

CASES = [*table_cases(), *platform_cases(), *rig_cases(), *good_platform_cases(), *log_cases(),
         *output_cases(), *compiler_cases(), *thread_cases(), *usage_cases(),
         *interrupt_cases(), *stale_cases()]


API_CASES = api_cases()


def test_case_ids_are_unique():
    ids = [c.id for c in [*CASES, *API_CASES]]
    assert len(ids) == len(set(ids))


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_fault(case, tmp_path, monkeypatch):
    check_case(case, tmp_path, monkeypatch)


@pytest.mark.parametrize("case", API_CASES, ids=lambda c: c.id)
def test_api_fault(case, tmp_path, recwarn):
    check_api_case(case, tmp_path)

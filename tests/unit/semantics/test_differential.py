"""The runtime reaches exactly the reference verdicts (see differential.py).

``COSLEEC_DIFF`` sets the number of cases (default 2000 in CI; 100000 for a long run).
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, given, settings

from tests.unit.semantics.differential import Case, cases, reference, runtime

CASES = int(os.environ.get("COSLEEC_DIFF", "2000"))


@settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=False)
@given(cases())
def test_the_runtime_reaches_the_reference_verdicts(case: Case) -> None:
    want = reference(case)
    got = runtime(case)
    assert got["choices"] == want["choices"], case.text
    assert got["verdicts"] == want["verdicts"], (case.text, case.trace)
    assert got["conflicts"] == want["conflicts"], case.text

"""The express lane on generated rule sets: the property half of ``test_express.py``.

The differential test's generated rule sets and traces (with rules that some action also
triggers, so that an event may trigger and fulfil at once) run with the lane and without
it (``test_express.same``): everything a user can see must be equal, and the general path
alone must meet the reference semantics. In a file of its own so that the mutation runs,
which take ``test_express.py``'s hand-made cases among their first files, reach it only
after those (``scripts/mutants``).
"""

from __future__ import annotations

import os
from unittest import mock

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.unit.runtime.test_express import same, trace_of
from tests.unit.semantics.differential import Case, cases, reference, runtime


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases(), st.booleans())
def test_the_lane_changes_nothing_on_generated_rules(case: Case, action_triggers: bool) -> None:
    with mock.patch.dict(os.environ, {"COSLEEC_EXPRESS": "0"}):  # the differential test, general path
        assert runtime(case) == reference(case), case
    text = case.text.replace("when T1", "when A") if action_triggers else case.text
    same(
        text,
        trace_of(case),
        semantics=case.semantics,
        priorities=list(case.priorities),
        priority_semantics=case.priority_semantics,
        priority_lead=case.lead,
    )

"""Generated sentences are made once per case: what is kept must be what would be made."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.runtime import Manager, VirtualClock, people

RULES = """def_start
  event Ask
  event Share
  event Refuse
  event ExplainWhy
  measure isPatient: boolean
  measure age: numeric
def_end
rule_start
  R1 when Ask then Share within 1 minutes
    unless not isPatient then {Refuse and ExplainWhy}
    unless age < 16 then Refuse
rule_end
"""


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.sampled_from([True, False, None]), st.sampled_from([None, 3, 15.5, 16, 40])),
        min_size=1,
        max_size=12,
    )
)
def test_a_kept_sentence_is_the_one_that_would_be_made(runs: list[tuple[bool | None, float | None]]) -> None:
    m = Manager.from_text(RULES, clock=VirtualClock(), dispatch=False)
    m.start(check=False)
    seen: dict[str, str] = {}
    for patient, age in runs:
        values = {k: v for k, v in (("isPatient", patient), ("age", age)) if v is not None}
        if values:
            m.update(**values)
        (d,) = m.event("Ask")
        said = d.for_people
        assert said == people._said(people._shape(d), d.values)  # the kept one is the made one
        key = repr(sorted(d.values.items())) + repr(d.clause)
        assert seen.setdefault(key, said) == said
    m.close()


def test_two_values_give_two_sentences() -> None:
    m = Manager.from_text(RULES, clock=VirtualClock(), dispatch=False)
    m.start(check=False)
    m.update(isPatient=True, age=3)
    (young,) = m.event("Ask")
    m.update(age=40)
    (old,) = m.event("Ask")
    assert young.clause == 2 and old.clause == 0
    assert young.for_people != old.for_people
    m.update(age=3)
    (again,) = m.event("Ask")
    assert again.for_people == young.for_people
    m.close()

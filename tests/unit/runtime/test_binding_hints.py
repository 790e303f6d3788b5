"""A task bound wrongly is told what the rules are, not how to complete an implementation."""

from __future__ import annotations

import pytest

from cosleec.runtime import BindingError, Manager, Task, hedge

RULES = """def_start event E event A event B measure m: boolean def_end
rule_start
  R1 when E then A unless m then B
  R2 when E then B
rule_end
"""


def test_a_task_naming_no_rule_hears_the_nearest_and_the_rules() -> None:
    class Typo(Task):
        rule = "R11"

    class Far(Task):
        rule = "Charging"

    with pytest.raises(BindingError) as e:
        Manager.from_text(RULES).bind(Typo())
    assert "no rule named 'R11'" in e.value.message
    assert e.value.hint == "did you mean 'R1'? the rules are R1, R2"
    assert "hint: did you mean 'R1'?" in str(e.value)
    with pytest.raises(BindingError) as e:
        Manager.from_text(RULES).bind(Far())
    assert e.value.hint == "the rules are R1, R2"


def test_a_clause_the_rule_has_not_is_numbered_against_the_rule_s_clauses() -> None:
    class TooMany(Task):
        rule = "R1"

        def default(self, decision: object) -> None: ...

        @hedge(2)
        def second(self, decision: object) -> None: ...

    class NoClause(Task):
        rule = "R2"

        @hedge(1)
        def first(self, decision: object) -> None: ...

    with pytest.raises(BindingError) as e:
        Manager.from_text(RULES).bind(TooMany())
    assert (
        e.value.hint
        == "rule R1 has one unless clause, 1: number each @hedge(i) as its unless clauses, from 1"
    )
    with pytest.raises(BindingError) as e:
        Manager.from_text(RULES).bind(NoClause())
    assert e.value.hint.startswith("rule R2 has no unless clause:")

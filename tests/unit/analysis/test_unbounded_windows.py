"""Two windows without an end (an untimed obligation, a prohibition `eventually`) overlap:
the runtime-conflict question is asked, not crashed on (it once built an empty z3 `And`
outside the encoding's context: an internal error on a file `check` accepts)."""

from __future__ import annotations

from cosleec.analysis import Settings, analyse_spec
from cosleec.lang import analyse

TEXT = """def_start
    event E
    event X
def_end
rule_start
    R1 when E then X
    R2 when E then not X eventually
rule_end
"""


def test_an_endless_obligation_and_an_endless_prohibition_are_a_runtime_conflict() -> None:
    r = analyse(TEXT, "t.sleec")
    assert r.spec is not None and r.symbols is not None
    found, unknown = analyse_spec(r.spec, dict(r.symbols.constant_values), Settings())
    assert ("runtime-conflict", "R1/R2") in {(f.code, f.subject) for f in found}
    assert not unknown

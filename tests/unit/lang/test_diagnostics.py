"""Diagnostics are keyword-only records whose JSON form reads back to the same value."""

from __future__ import annotations

import json

import pytest

from cosleec.lang import Diagnostic, Severity, analyse

BAD = [
    "def_start event A def_end rule_start R1 when A then B rule_end",  # undeclared response
    "def_start event A event A def_end rule_start R1 when A then A rule_end",  # declared twice
    "rule_start R1 when A then B rule_end",  # no def block
    "def_start event A def_end rule_start R1 when A then A within 3 minute rule_end",  # unit
    "def_start event A measure m : boolean def_end rule_start R1 when A then A unless m unless m rule_end",
]


@pytest.mark.parametrize("text", BAD)
def test_every_diagnostic_round_trips_through_json(text: str) -> None:
    result = analyse(text, "rules.sleec")
    assert result.diagnostics
    for d in result.diagnostics:
        back = Diagnostic.from_json(json.loads(json.dumps(d.to_json())))
        assert back == d
        assert back.path == "rules.sleec"


def test_diagnostics_are_built_by_keyword() -> None:
    with pytest.raises(TypeError):
        Diagnostic(Severity.ERROR, "code", "message")  # type: ignore[misc]

"""parse(print(ast)) == ast, for generated ASTs, in both dialects."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, given, settings

from cosleec.lang import analyse, format_spec
from cosleec.lang import ast as A

from .strategies import specifications


@pytest.mark.parametrize("dialect", [A.Dialect.TK, A.Dialect.LEGOS])
@settings(
    max_examples=int(os.environ.get("COSLEEC_EXAMPLES", "200")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(spec=specifications())
def test_print_then_parse_is_identity(dialect: A.Dialect, spec: A.Specification) -> None:
    text = format_spec(spec, dialect)
    result = analyse(text)
    syntax = [d for d in result.errors if d.code in {"syntax", "bad-char"}]
    assert not syntax, (text, syntax)
    assert result.spec == spec, text
    # printing is canonical: a second round gives the same text
    assert result.spec is not None and format_spec(result.spec, dialect) == text

"""The front end's fast paths do exactly what the general code does.

- AST nodes are built by a generated ``__init__`` (ast._fast_init): same signature, same
  fields, still frozen;
- the printer prints a block without comments in one loop (printer._Lines.plain_items):
  the same lines as the per-item path;
- the fast driver's inline callbacks (transformer.INLINE_BODIES) are held equal to plain
  Lark by test_parser_crosscheck.py; here, only that a subclass overriding a method is
  not bypassed.
"""

from __future__ import annotations

import dataclasses
import inspect
import os

import pytest
from hypothesis import HealthCheck, given, settings

from cosleec.lang import analyse, format_spec
from cosleec.lang import ast as A
from cosleec.lang import printer as P
from cosleec.lang.paper import PaperToAst
from cosleec.lang.transformer import INLINE_BODIES, ToAst

from .strategies import specifications

NODES = [
    c
    for c in vars(A).values()
    if isinstance(c, type) and c.__module__ == A.__name__ and dataclasses.is_dataclass(c)
]


def _generated_signature(cls: type) -> inspect.Signature:
    """The signature dataclasses would have given ``__init__``."""
    params = [inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)]
    fields = dataclasses.fields(cls)
    for kw_only in (False, True):
        for f in fields:
            if f.kw_only is not kw_only:
                continue
            kind = inspect.Parameter.KEYWORD_ONLY if kw_only else inspect.Parameter.POSITIONAL_OR_KEYWORD
            default = inspect.Parameter.empty if f.default is dataclasses.MISSING else f.default
            params.append(inspect.Parameter(f.name, kind, default=default))
    return inspect.Signature(params)


@pytest.mark.parametrize("cls", NODES, ids=lambda c: c.__name__)
def test_node_constructors_keep_the_dataclass_signature(cls: type) -> None:
    got = inspect.signature(cls.__init__)
    want = _generated_signature(cls)
    assert [(p.name, p.kind, p.default) for p in got.parameters.values()] == [
        (p.name, p.kind, p.default) for p in want.parameters.values()
    ]


def test_nodes_stay_frozen_and_complete() -> None:
    occ = A.Occurrence("E", span=A.Span(1, 2, 1, 3))
    assert (occ.event, occ.negated, occ.limit, occ.eventually, occ.span) == (
        "E",
        False,
        None,
        False,
        (1, 2, 1, 3),
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        occ.event = "F"  # type: ignore[misc]
    assert dataclasses.replace(occ, negated=True) == A.Occurrence("E", True)
    assert A.Name("x", braced=True) == A.Name("x") and hash(A.Name("x", braced=True)) == hash(A.Name("x"))


def test_inline_bodies_give_way_to_an_override() -> None:
    assert ToAst().inline_body("duration") is not None
    assert PaperToAst().inline_body("duration") is None  # the paper grammar's own method
    assert all(hasattr(ToAst, name) for name in INLINE_BODIES)


LONG = (
    "def_start event E event A event B measure m : boolean measure n : numeric def_end rule_start "
    "R1 when E then A within 5 seconds unless m then B within 10 minutes unless n > 3 then "
    "{A unless m} unless not m then B otherwise {A within 2 hours} "
    "R2 when E then A "
    "R3 when E and m then not B within 1 seconds unless (n + 1) * 2 > 3 rule_end"
)


def _per_item(monkeypatch: pytest.MonkeyPatch, spec: A.Specification, dialect: A.Dialect) -> str:
    with monkeypatch.context() as m:
        m.setattr(P._Lines, "plain", lambda self: False)
        return format_spec(spec, dialect)


@pytest.mark.parametrize("width", [P.WIDTH, 20])
@pytest.mark.parametrize("dialect", [A.Dialect.TK, A.Dialect.LEGOS])
def test_plain_blocks_print_as_items_do(
    monkeypatch: pytest.MonkeyPatch, dialect: A.Dialect, width: int
) -> None:
    spec = analyse(LONG).spec
    assert spec is not None
    monkeypatch.setattr(P, "WIDTH", width)
    monkeypatch.setattr(P.Printer.__init__, "__defaults__", (None, width))
    fast = format_spec(spec, dialect)
    assert fast == _per_item(monkeypatch, spec, dialect)
    if width == 20:
        assert "\n        unless" in fast  # long rules wrapped, one clause a line


@settings(
    max_examples=int(os.environ.get("COSLEEC_EXAMPLES", "100")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(spec=specifications())
def test_plain_blocks_print_as_items_do_generated(
    monkeypatch: pytest.MonkeyPatch, spec: A.Specification
) -> None:
    for dialect in (A.Dialect.TK, A.Dialect.LEGOS):
        assert format_spec(spec, dialect) == _per_item(monkeypatch, spec, dialect)

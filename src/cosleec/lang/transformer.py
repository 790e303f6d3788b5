"""Parse tree -> AST, run inline by the LALR parser (no intermediate tree is built).

Callbacks take the children list directly (no ``v_args`` wrapper): it is the fastest
calling convention Lark offers, and parsing speed is a project target. Optional grammar
parts are ``[x]`` so the children have fixed positions (``None`` when absent).

Tokens are read only through ``type``, ``value``, ``line`` and ``column``, which Lark's
``Token`` and the fast scanner's ``lexer.Token`` both have: the same transformer serves
plain Lark and the fast driver (lalr.py), and the cross-check test compares the two.
"""

from __future__ import annotations

import ast
import dataclasses
from dataclasses import replace
from itertools import pairwise
from typing import Any

from lark import Token, Transformer

from cosleec.lang import ast as A

_new = tuple.__new__


def tok_span(tok: Any) -> A.Span:
    """Where a token is (no token spans lines)."""
    line, col = tok.line, tok.column
    span: A.Span = _new(A.Span, (line, col, line, col + len(tok.value)))
    return span


def join(a: A.Span, b: A.Span) -> A.Span:
    """From the start of ``a`` to the end of ``b``."""
    span: A.Span = _new(A.Span, (a[0], a[1], b[2], b[3]))
    return span


def ident(tok: Any) -> str:
    """An identifier's text; SLEEC-TK's ``^`` keyword escape is dropped."""
    v: str = tok.value
    return v[1:] if v[0] == "^" else v


_BOOLEAN = A.BooleanType()
_NUMERIC = A.NumericType()


class Block:
    """A parsed block before the Specification is assembled (parser.assemble)."""

    __slots__ = ("items", "kind", "span")

    def __init__(self, kind: A.BlockKind, span: A.Span, items: list[Any]) -> None:
        self.kind = kind
        self.span = span
        self.items = items


# The hottest methods of ToAst again, as function bodies the fast driver compiles into its
# reduction callbacks (lalr.direct_callback): there ``c0``, ``c1``, ... are the children
# the method reads as ``c[0]``, ``c[1]``, ... (tokens or values, ``None`` for an absent
# ``[part]``), with ``tok_span``/``ident`` written out, so that one reduction is one call
# instead of four or five. Each must build exactly what its method builds:
# tests/unit/lang/test_parser_crosscheck.py holds the driver equal to plain Lark, which
# calls the methods.
_TOKEN_SPAN = "_new(Span, ({t}.line, {t}.column, {t}.line, {t}.column + len({t}.value)))"
_NAME_AND_SPAN = (
    "v = c0.value\n"
    "line = c0.line\n"
    "col = c0.column\n"
    "n = v[1:] if v[0] == '^' else v\n"
    "span = _new(Span, (line, col, line, col + len(v)))\n"
)
_BINOP = "a = c0.span\nb = c1.span\nreturn BinOp({op!r}, c0, c1, span=_new(Span, (a[0], a[1], b[2], b[3])))"
INLINE_BODIES: dict[str, str] = {
    "event_decl": _NAME_AND_SPAN + "return EventDecl(n, span=span)",
    "measure_decl": _NAME_AND_SPAN + "return MeasureDecl(n, c1, span=span)",
    "boolean_type": "return _BOOLEAN",
    "numeric_type": "return _NUMERIC",
    "rule": _NAME_AND_SPAN + "return Rule(n, c1, c2, span=span)",
    "trigger": _NAME_AND_SPAN + "return Trigger(n, c1, span=span)",
    "response_body": "return Response(tuple(c0), tuple(c1) if c1 else (), span=c0[0].span)",
    "inner_body": "return Response(tuple(c0), (), span=c0[0].span)",
    "item": "return ResponseItem(c0, c1, c2, span=c0.span)",
    "occurrence": (
        "v = c1.value\n"
        "line = c1.line\n"
        "col = c1.column\n"
        "if c0 is None:\n"
        "    span = _new(Span, (line, col, line, col + len(v)))\n"
        "else:\n"
        "    span = _new(Span, (c0.line, c0.column, line, col + len(v)))\n"
        "return Occurrence(v[1:] if v[0] == '^' else v, c0 is not None, c2, c3 is not None, span=span)"
    ),
    "name": _NAME_AND_SPAN + "return Name(n, span=span)",
    "braced_name": _NAME_AND_SPAN + "return Name(n, braced=True, span=span)",
    "int_lit": "return IntLit(int(c0.value), span=" + _TOKEN_SPAN.format(t="c0") + ")",
    "and_": _BINOP.format(op="and"),
    "or_": _BINOP.format(op="or"),
    "add": _BINOP.format(op="+"),
    "sub": _BINOP.format(op="-"),
    "mul": _BINOP.format(op="*"),
    "not_": ("b = c1.span\nreturn Not(c1, span=_new(Span, (c0.line, c0.column, b[2], b[3])))"),
    "compare": "return Compare(c1.value, c0, c2, span=" + _TOKEN_SPAN.format(t="c1") + ")",
    "rel_op": "return c0",
    "time_unit": "return c0",
    "sign": "return c0",
    "duration": (
        "a = c0.span\n"
        "return Duration(c0, c1.value, span=_new(Span, (a[0], a[1], c1.line, c1.column + len(c1.value))))"
    ),
    "within": "return TimeLimit(c0, None, span=c0.span)",
    "defeater": "return Defeater(c1, c2, span=" + _TOKEN_SPAN.format(t="c0") + ")",
    "otherwise": "return c0",
    "alternative": "return c0",
}
"""Method name -> the body the fast driver compiles for it (see the comment above)."""

INLINE_ENV: dict[str, Any] = {
    "_new": _new,
    "_BOOLEAN": _BOOLEAN,
    "_NUMERIC": _NUMERIC,
    **{name: getattr(A, name) for name in dir(A) if isinstance(getattr(A, name), type)},
}
"""The names :data:`INLINE_BODIES` use (and, once built in place, :data:`_IN_PLACE` bodies)."""


def _plain_node(cls: Any) -> bool:
    """Is ``cls`` a node class whose ``__init__`` only sets its fields, in order (a frozen,
    slotted dataclass with the generated ``__init__`` of ``cosleec.bulk.quick_init``: no
    ``__post_init__``, no ``__new__`` of its own, every field an ``__init__`` argument)?"""
    return (
        isinstance(cls, type)
        and dataclasses.is_dataclass(cls)
        and "__slots__" in cls.__dict__
        and cls.__dataclass_params__.frozen  # type: ignore[attr-defined]
        and not hasattr(cls, "__post_init__")
        and cls.__new__ is object.__new__
        and all(f.init and f.default_factory is dataclasses.MISSING for f in dataclasses.fields(cls))
    )


def _construction(call: ast.expr, env: dict[str, Any]) -> list[str] | None:
    """``Cls(args)`` as statements that build the node in place: the arguments, in the
    call's order, then the object and its fields set through their slots, in field order,
    as the generated ``__init__`` sets them; None when ``call`` is not such a call."""
    if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name)):
        return None
    cls: Any = env.get(call.func.id)
    if not _plain_node(cls) or any(isinstance(a, ast.Starred) for a in call.args):
        return None
    fields = dataclasses.fields(cls)
    positional = [f.name for f in fields if not f.kw_only]
    names = [*positional[: len(call.args)], *(k.arg for k in call.keywords)]
    if len(call.args) > len(positional) or None in names or len(set(names)) != len(names):
        return None
    if not set(names) <= {f.name for f in fields}:
        return None
    values = [*call.args, *(k.value for k in call.keywords)]
    lines = [f"_a{i} = {ast.unparse(v)}" for i, v in enumerate(values)]
    lines.append(f"_o = _object_new({cls.__name__})")
    for f in fields:
        if f.name in names:
            value = f"_a{names.index(f.name)}"
        elif f.default is not dataclasses.MISSING:
            value = f"_default_{cls.__name__}_{f.name}"
        else:
            return None  # a required argument missing: the call would raise, leave it so
        lines.append(f"_set_{cls.__name__}_{f.name}(_o, {value})")
    return [*lines, "return _o"]


def _in_place(body: str, env: dict[str, Any]) -> str:
    """``body`` with each ``return Cls(...)`` of a plain node class (:func:`_plain_node`)
    built in place (:func:`_construction`).

    Why: calling the class costs a type call and an ``__init__`` frame per node, a third of
    what making a node costs, and the fast driver makes one per reduction. The nodes are the
    same (fields, defaults, frozen: the class's ``__setattr__`` still refuses);
    tests/unit/lang/test_parser_crosscheck.py holds the driver equal to plain Lark, which
    calls the methods."""
    out: list[str] = []
    for stmt in ast.parse(body).body:
        built = _construction(stmt.value, env) if isinstance(stmt, ast.Return) and stmt.value else None
        out += built if built is not None else ast.unparse(stmt).splitlines()
    return "\n".join(out)


for _name, _cls in list(INLINE_ENV.items()):
    if _plain_node(_cls):
        INLINE_ENV["_object_new"] = object.__new__
        for _f in dataclasses.fields(_cls):
            _slot = next(k.__dict__[_f.name] for k in _cls.__mro__ if _f.name in k.__dict__)
            INLINE_ENV[f"_set_{_name}_{_f.name}"] = _slot.__set__
            if _f.default is not dataclasses.MISSING:
                INLINE_ENV[f"_default_{_name}_{_f.name}"] = _f.default
del _name, _cls, _f, _slot
_IN_PLACE = {name: _in_place(body, INLINE_ENV) for name, body in INLINE_BODIES.items()}
""":data:`INLINE_BODIES` with their nodes built in place: what the fast driver compiles."""


class ToAst(Transformer[Token, Any]):
    """Builds :mod:`cosleec.lang.ast` nodes; ``start`` returns the list of blocks.

    Give an instance to ``Lark(..., transformer=...)`` (it keeps no state, so one instance
    serves every parse, in any thread).
    """

    def inline_body(self, name: str) -> tuple[str, dict[str, Any]] | None:
        """The body the fast driver may compile instead of calling method ``name`` (see
        :data:`INLINE_BODIES`) and the names it uses; None where a subclass overrides the
        method, or there is none."""
        body = _IN_PLACE.get(name)
        if body is None or getattr(type(self), name) is not getattr(ToAst, name):
            return None
        return body, INLINE_ENV

    # -- lists (left-recursive list rules of the grammar)
    def list_first(self, c: list[Any]) -> list[Any]:
        return [c[0]]

    def list_more(self, c: list[Any]) -> list[Any]:
        lst: list[Any] = c[0]
        lst.append(c[-1])
        return lst

    # -- blocks
    def start(self, c: list[Any]) -> Any:
        return c[0] or []

    def def_block(self, c: list[Any]) -> Block:
        return Block("def", tok_span(c[0]), c[1] or [])

    def rule_block(self, c: list[Any]) -> Block:
        return Block("rule", tok_span(c[0]), c[1] or [])

    def concern_block(self, c: list[Any]) -> Block:
        return Block("concern", tok_span(c[0]), c[1:])

    def purpose_block(self, c: list[Any]) -> Block:
        return Block("purpose", tok_span(c[0]), c[1:])

    def relation_block(self, c: list[Any]) -> Block:
        return Block("relation", tok_span(c[0]), c[1:])

    def priority_block(self, c: list[Any]) -> Block:
        """The block's chains (lists of name tokens) expanded into consecutive pairs."""
        pairs = []
        for chain in c[1] or ():
            for hi, lo in pairwise(chain):
                hs, ls = tok_span(hi), tok_span(lo)
                pairs.append(
                    A.Priority(ident(hi), ident(lo), span=join(hs, ls), higher_span=hs, lower_span=ls)
                )
        return Block("priority", tok_span(c[0]), pairs)

    def semantics_block(self, c: list[Any]) -> Block:
        return Block("semantics", tok_span(c[0]), c[1] or [])

    def semantics_entry(self, c: list[Any]) -> A.SemanticsDecl:
        """``unless last-wins``: the value's names joined by `-`, as written."""
        words = c[1]
        value_span = join(tok_span(words[0]), tok_span(words[-1]))
        return A.SemanticsDecl(
            c[0].value,
            "-".join(w.value for w in words),
            span=join(tok_span(c[0]), value_span),
            value_span=value_span,
        )

    def chain_first(self, c: list[Any]) -> list[Any]:
        """``A > B``: the first two name tokens of a chain (``list_more`` adds the others)."""
        return [c[0], c[1]]

    # -- definitions
    def event_decl(self, c: list[Any]) -> A.EventDecl:
        return A.EventDecl(ident(c[0]), span=tok_span(c[0]))

    def measure_decl(self, c: list[Any]) -> A.MeasureDecl:
        return A.MeasureDecl(ident(c[0]), c[1], span=tok_span(c[0]))

    def boolean_type(self, c: list[Any]) -> A.BooleanType:
        return _BOOLEAN

    def numeric_type(self, c: list[Any]) -> A.NumericType:
        return _NUMERIC

    def scale_type(self, c: list[Any]) -> A.ScaleType:
        return A.ScaleType(tuple(ident(t) for t in c), literal_spans=tuple(tok_span(t) for t in c))

    def constant_decl(self, c: list[Any]) -> A.ConstantDecl:
        value, arrow, sign = c[1]
        return A.ConstantDecl(ident(c[0]), value, arrow=arrow, sign=sign, span=tok_span(c[0]))

    def const_int(self, c: list[Any]) -> tuple[int, bool, str]:
        return int(c[0].value), False, ""

    def const_signed(self, c: list[Any]) -> tuple[int, bool, str]:
        sign, digits = c
        value = int(digits.value)
        return (-value if sign.value == "-" else value), False, _sign(sign, digits)

    def const_name(self, c: list[Any]) -> tuple[str, bool, str]:
        return ident(c[0]), False, ""

    def const_arrow(self, c: list[Any]) -> tuple[str, bool, str]:
        return ident(c[0]), True, ""

    def fluent_decl(self, c: list[Any]) -> A.FluentDecl:
        return A.FluentDecl(ident(c[0]), c[1], c[2], span=tok_span(c[0]))

    def name_list(self, c: list[Any]) -> tuple[str, ...]:
        return tuple(ident(t) for t in c)

    # -- rules
    def rule(self, c: list[Any]) -> A.Rule:
        return A.Rule(ident(c[0]), c[1], c[2], span=tok_span(c[0]))

    def trigger(self, c: list[Any]) -> A.Trigger:
        return A.Trigger(ident(c[0]), c[1], span=tok_span(c[0]))

    def response_body(self, c: list[Any]) -> A.Response:
        items = c[0]
        return A.Response(tuple(items), tuple(c[1]) if c[1] else (), span=items[0].span)

    def inner_body(self, c: list[Any]) -> A.Response:
        items = c[0]
        return A.Response(tuple(items), (), span=items[0].span)

    def item(self, c: list[Any]) -> A.ResponseItem:
        occ: A.Occurrence = c[0]
        return A.ResponseItem(occ, c[1], c[2], span=occ.span)

    def occurrence(self, c: list[Any]) -> A.Occurrence:
        not_tok, name, limit, ev = c
        span = tok_span(name) if not_tok is None else join(tok_span(not_tok), tok_span(name))
        return A.Occurrence(ident(name), not_tok is not None, limit, ev is not None, span=span)

    def braced(self, c: list[Any]) -> A.Response:
        r: A.Response = c[0]
        return A.Response(r.items, r.defeaters, braced=True, span=r.span)

    def otherwise(self, c: list[Any]) -> A.Response:
        r: A.Response = c[0]
        return r

    alternative = otherwise

    def defeater(self, c: list[Any]) -> A.Defeater:
        return A.Defeater(c[1], c[2], span=tok_span(c[0]))

    def within(self, c: list[Any]) -> A.TimeLimit:
        return A.TimeLimit(c[0], None, span=c[0].span)

    def within_interval(self, c: list[Any]) -> A.TimeLimit:
        return A.TimeLimit(c[1], c[0], span=join(c[0].span, c[1].span))

    def duration(self, c: list[Any]) -> A.Duration:
        unit = c[1]
        return A.Duration(c[0], unit.value, span=join(_span_of(c[0]), tok_span(unit)))

    def time_unit(self, c: list[Any]) -> Any:
        return c[0]

    # -- expressions
    def and_(self, c: list[Any]) -> A.BinOp:
        return A.BinOp("and", c[0], c[1], span=join(_span_of(c[0]), _span_of(c[1])))

    def or_(self, c: list[Any]) -> A.BinOp:
        return A.BinOp("or", c[0], c[1], span=join(_span_of(c[0]), _span_of(c[1])))

    def not_(self, c: list[Any]) -> A.Not:
        return A.Not(c[1], span=join(tok_span(c[0]), _span_of(c[1])))

    def compare(self, c: list[Any]) -> A.Compare:
        op = c[1]
        return A.Compare(op.value, c[0], c[2], span=tok_span(op))

    def rel_op(self, c: list[Any]) -> Any:
        return c[0]

    def add(self, c: list[Any]) -> A.BinOp:
        return A.BinOp("+", c[0], c[1], span=join(_span_of(c[0]), _span_of(c[1])))

    def sub(self, c: list[Any]) -> A.BinOp:
        return A.BinOp("-", c[0], c[1], span=join(_span_of(c[0]), _span_of(c[1])))

    def mul(self, c: list[Any]) -> A.BinOp:
        return A.BinOp("*", c[0], c[1], span=join(_span_of(c[0]), _span_of(c[1])))

    def bool_lit(self, c: list[Any]) -> A.BoolLit:
        return A.BoolLit(c[0].type == "TRUE", span=tok_span(c[0]))

    def int_lit(self, c: list[Any]) -> A.IntLit:
        return A.IntLit(int(c[0].value), span=tok_span(c[0]))

    def signed_int(self, c: list[Any]) -> A.IntLit:
        sign, digits = c
        value = int(digits.value)
        return A.IntLit(
            -value if sign.value == "-" else value,
            sign=_sign(sign, digits),
            span=join(tok_span(sign), tok_span(digits)),
        )

    def sign(self, c: list[Any]) -> Any:
        return c[0]

    def decimal_lit(self, c: list[Any]) -> A.DecimalLit:
        return A.DecimalLit(c[0].value, span=tok_span(c[0]))

    def name(self, c: list[Any]) -> A.Name:
        return A.Name(ident(c[0]), span=tok_span(c[0]))

    def arrow_name(self, c: list[Any]) -> A.Name:
        return A.Name(ident(c[0]), arrow=True, span=tok_span(c[0]))

    def braced_name(self, c: list[Any]) -> A.Name:
        return A.Name(ident(c[0]), braced=True, span=tok_span(c[0]))

    def paren(self, c: list[Any]) -> A.Expr:
        """Count parentheses (they matter only to dialect checks and warnings)."""
        e = c[0]
        t = type(e)
        n = e.parenthesized + 1
        if t is A.Name:
            return A.Name(e.name, braced=e.braced, arrow=e.arrow, parenthesized=n, span=e.span)
        if t is A.BinOp:
            return A.BinOp(e.op, e.left, e.right, parenthesized=n, span=e.span)
        if t is A.Compare:
            return A.Compare(e.op, e.left, e.right, parenthesized=n, span=e.span)
        if t is A.Not:
            return A.Not(e.operand, parenthesized=n, span=e.span)
        if t is A.IntLit:
            return A.IntLit(e.value, sign=e.sign, parenthesized=n, span=e.span)
        if t is A.BoolLit:
            return A.BoolLit(e.value, parenthesized=n, span=e.span)
        return A.DecimalLit(e.text, parenthesized=n, span=e.span)

    # -- LEGOS concerns and purposes
    def situation(self, c: list[Any]) -> A.Situation:
        body: A.Situation = c[1]
        return replace(body, name=ident(c[0]), span=tok_span(c[0]))

    def exists_body(self, c: list[Any]) -> A.Situation:
        return A.Situation("", "exists", c[0], c[1] or (), c[2], span=c[0].span)

    def when_body(self, c: list[Any]) -> A.Situation:
        return A.Situation("", "when", c[0], c[1] or (), c[2], span=c[0].span)

    def meanwhile(self, c: list[Any]) -> A.Situation:
        s: A.Situation = c[0]
        return s

    def ext_response(self, c: list[Any]) -> tuple[A.Response, ...]:
        return tuple(c)

    # -- LEGOS relations
    def event_relation(self, c: list[Any]) -> A.EventRelation:
        return A.EventRelation(c[0].value, ident(c[1]), ident(c[2]), span=tok_span(c[0]))

    def measure_relation(self, c: list[Any]) -> A.MeasureRelation:
        return A.MeasureRelation(c[0].value, c[1], c[2], span=tok_span(c[0]))

    def measure_invariant(self, c: list[Any]) -> A.MeasureRelation:
        return A.MeasureRelation("invariant", c[0], None, span=_span_of(c[0]))

    def event_measure_relation(self, c: list[Any]) -> A.EventMeasureRelation:
        return A.EventMeasureRelation(c[0].value, ident(c[1]), c[2], span=tok_span(c[0]))

    def until_relation(self, c: list[Any]) -> A.UntilRelation:
        return A.UntilRelation(c[0], c[1], ident(c[2]), c[3], span=c[0].span)

    def for_relation(self, c: list[Any]) -> A.ForRelation:
        return A.ForRelation(c[0], c[1], c[2], span=c[0].span)

    def event_rel(self, c: list[Any]) -> Any:
        return c[0]

    measure_rel = event_rel
    event_measure_rel = event_rel


def _sign(sign: Any, digits: Any) -> str:
    """A number's sign as written: ``"-"`` or ``"+"``, with a space after it when anything
    (a space, a comment, a line break) separates it from the digits."""
    attached = sign.line == digits.line and sign.column + 1 == digits.column
    v: str = sign.value
    return v if attached else v + " "


def _span_of(node: Any) -> A.Span:
    s: A.Span = node.span
    return s

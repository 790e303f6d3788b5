"""The def block's checks (docs/reference/sleec-language.md §5): names, kinds, scales, constants.

:class:`Declarations` fills the scope's symbol table, its scale literals (with the measures
that own each) and every constant's value, so that the passes after it can resolve names;
:func:`check_name` is the one test of a name, declared here or naming a rule.

May import: the lang modules ast, diagnostics and scope.
"""

from __future__ import annotations

import re

from cosleec.lang import ast as A
from cosleec.lang.diagnostics import QUOTE_LIMIT, clip
from cosleec.lang.scope import Scope

# Names SLEEC-TK rejects because they clash with its CSP encoding (§3).
TK_RESERVED = frozenset({"STOP", "P", "Q", "c", "d"})

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def check_name(scope: Scope, name: str, span: A.Span) -> None:
    """A declared or rule name: a SLEEC identifier (a Specification built in Python may
    hold anything), and with ``tk_names`` not one SLEEC-TK rejects."""
    if not _IDENTIFIER.fullmatch(name):
        scope.sink.error(
            "malformed-name",
            f"`{clip(name)}` is not a SLEEC name",
            span,
            hint="a name is a letter or `_`, then letters, digits or `_`",
        )
        return
    # A keyword reaches the AST as a name only through SLEEC-TK's `^when` escape, which
    # makes it a name (docs/reference/sleec-language.md §3), or from the paper notation, which does
    # not reserve the DSL's words: either way it is a name. The printer escapes it.
    if scope.opt.tk_names and name in TK_RESERVED:
        scope.sink.warning(
            "tk-reserved",
            f"SLEEC-TK rejects the name `{clip(name)}` (it clashes with its CSP encoding)",
            span,
        )


class Declarations:
    """The checks of ``scope.spec``'s definitions, run once before every other pass."""

    def __init__(self, scope: Scope) -> None:
        self.scope = scope
        self.sink = scope.sink
        self._cycles: set[frozenset[str]] = set()

    def check(self) -> None:
        """Every definition in file order, then the scale literals, then the constants'
        values (a constant may name one declared after it)."""
        first: dict[str, A.Definition] = {}
        for d in self.scope.spec.definitions:
            self._definition(d, first)
        self._scale_literals(first)
        for c in self.scope.table.constants.values():
            self._constant_value(c.name, [])

    def _definition(self, d: A.Definition, first: dict[str, A.Definition]) -> None:
        """One definition: a name of its own (``first`` has the names declared so far), put
        in the table under its kind."""
        if isinstance(d, A.FluentDecl):
            self.sink.warning(
                "unsupported-fluent",
                f"`fluent {clip(d.name)}` is an extension of CPeluti/LEGOS-SLEEC (goal fluents for "
                "conflict explanation); cosleec ignores it",
                d.span,
            )
            return
        check_name(self.scope, d.name, d.span)
        if d.name in first:
            prev = first[d.name]
            if prev == d:  # the same declaration again: harmless, but worth cleaning up
                self.sink.warning(
                    "redeclared",
                    f"`{clip(d.name)}` is declared twice, identically",
                    d.span,
                    related=(("first declared here", prev.span),),
                )
                return
            self.sink.error(
                "duplicate-name",
                f"`{clip(d.name)}` is already declared as {kind_word(prev)}",
                d.span,
                related=((f"`{clip(d.name)}` first declared here", prev.span),),
            )
            return
        first[d.name] = d
        self._declare(d)

    def _declare(self, d: A.EventDecl | A.MeasureDecl | A.ConstantDecl) -> None:
        """Put ``d`` in the table; with ``lint``, warn about a name against its kind's convention."""
        t, lint = self.scope.table, self.scope.opt.lint
        if isinstance(d, A.EventDecl):
            t.events[d.name] = d
            if lint and not d.name[:1].isupper():
                self.sink.warning(
                    "naming", f"event `{clip(d.name)}` should start with an upper-case letter", d.span
                )
        elif isinstance(d, A.MeasureDecl):
            t.measures[d.name] = d
            if lint and not d.name[:1].islower():
                self.sink.warning(
                    "naming", f"measure `{clip(d.name)}` should start with a lower-case letter", d.span
                )
        else:
            t.constants[d.name] = d
            if lint and d.name != d.name.upper():
                self.sink.warning("naming", f"constant `{clip(d.name)}` should be ALL_CAPS", d.span)

    def _scale_literals(self, first: dict[str, A.Definition]) -> None:
        """Scale literals: unique within their scale, distinct from every declared name."""
        scope = self.scope
        for m in scope.table.measures.values():
            if not isinstance(m.type, A.ScaleType):
                continue
            seen: set[str] = set()
            spans = m.type.literal_spans or (m.span,) * len(m.type.literals)
            for lit, span in zip(m.type.literals, spans):
                if lit in seen:
                    self.sink.error(
                        "duplicate-literal",
                        f"`{clip(lit)}` appears twice in the scale of `{clip(m.name)}`",
                        span,
                    )
                else:
                    scope.owners_of.setdefault(lit, []).append(m.name)
                seen.add(lit)
                if lit in first:
                    self.sink.error(
                        "literal-clash",
                        f"scale literal `{clip(lit)}` of `{clip(m.name)}` has the name of "
                        f"{kind_word(first[lit])}",
                        span,
                    )
                check_name(scope, lit, span)
            scope.scale_literals |= seen

    def _constant_value(self, name: str, path: list[str]) -> int | None:
        """The value of constant ``name``, following references (``path``: the constants
        that led here, for a cycle, reported once)."""
        t = self.scope.table
        if name in t.constant_values:
            return t.constant_values[name]
        c = t.constants[name]
        if isinstance(c.value, int):
            t.constant_values[name] = c.value
            return c.value
        ref = c.value
        if name in path:
            members = frozenset(path)
            if path[0] == name and members not in self._cycles:
                self._cycles.add(members)
                cycle = clip(" -> ".join([*path, name]), 4 * QUOTE_LIMIT)
                self.sink.error(
                    "constant-cycle", f"constants refer to each other in a cycle: {cycle}", c.span
                )
            return None
        target = t.constants.get(ref)
        if target is None:
            self._bad_reference(c, ref)
            return None
        v = self._constant_value(ref, [*path, name])
        if v is not None:
            t.constant_values[name] = v
        return v

    def _bad_reference(self, c: A.ConstantDecl, ref: str) -> None:
        """Constant ``c`` refers to ``ref``, which is no constant."""
        kind = self.scope.table.kind(ref)
        if kind is not None:
            self.sink.error(
                "constant-ref",
                f"constant `{clip(c.name)}` refers to {kind} `{clip(ref)}`; only constants can",
                c.span,
            )
        else:
            self.sink.error(
                "undeclared",
                f"constant `{clip(c.name)}` refers to undeclared `{clip(ref)}`",
                c.span,
                hint=self.scope.did_you_mean(ref, "constants", "undeclared"),
            )


def kind_word(d: A.Definition) -> str:
    """What ``d`` declares, with its article, for a message: ``"an event"``."""
    if isinstance(d, A.EventDecl):
        return "an event"
    if isinstance(d, A.MeasureDecl):
        return "a measure"
    return "a constant"


__all__ = ["TK_RESERVED", "Declarations", "check_name", "kind_word"]

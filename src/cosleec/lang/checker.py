"""Static semantics of SLEEC (docs/reference/sleec-language.md §5): names, kinds, types, constants.

Every problem of a file is reported in one pass, as a diagnostic with a stable code. The
checker also resolves the information later stages need (constant values, each scale
literal's measure), exposed as a :class:`SymbolTable`.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from cosleec.errors import closest
from cosleec.lang import ast as A
from cosleec.lang import hedges
from cosleec.lang.compat import LegosReading, apply, fresh_name, holds, mirrored, ordinal
from cosleec.lang.diagnostics import QUOTE_LIMIT, DiagnosticSink, clip
from cosleec.lang.priorities import check_priorities

# Names SLEEC-TK rejects because they clash with its CSP encoding (§3).
TK_RESERVED = frozenset({"STOP", "P", "Q", "c", "d"})

BOOL = "bool"
NUM = "num"

MAX_LINT_CLAUSES = 12
"""The unreachable-clause lint asks :mod:`cosleec.lang.hedges` about a rule's clauses only
when the rule has at most this many (the real corpus has at most 6). The question costs far
more than n**2 per rule: :func:`hedges.reachable` tries every pair of clauses, and
:func:`hedges.blockers` asks it again once per other clause for each dead clause, so a
generated rule of 20,000 ``unless false`` clauses ran out of memory, and even a 16-clause
rule of unknown conditions and ``true`` took seconds (12 clauses: at most about one). A
longer rule gets only what holds under every semantics, at one look per clause: a clause
whose condition is the literal ``false`` never applies."""


@dataclass(frozen=True)
class Options:
    """What the checker should be strict about."""

    strict_precedence: bool = False  # mixed and/or without parentheses is an error
    strict_extensions: bool = False  # cosleec extensions (response conjunction, priorities) are errors
    lint: bool = False  # naming conventions and style suggestions
    tk_names: bool = False  # warn about names SLEEC-TK rejects
    semantics: hedges.HedgeSemantics = hedges.HedgeSemantics.LAST_WINS  # for the hedge lint
    # per rule (or concern, purpose), diagnostics of one code kept before the rest are
    # folded into one "... and N more" summary (DiagnosticSink.folding); 0 keeps them all
    repeat_limit: int = 20
    # read what LEGOS-SLEEC lets through as it does (cross-scale literals, scales compared
    # with numbers, duplicate rule, concern and purpose names): a warning each, and
    # check_and_read's specification carries LEGOS-SLEEC's reading (compat.py)
    legos_compat: bool = False


@dataclass
class SymbolTable:
    """What the names of a specification denote, after checking."""

    events: dict[str, A.EventDecl] = field(default_factory=dict)
    measures: dict[str, A.MeasureDecl] = field(default_factory=dict)
    constants: dict[str, A.ConstantDecl] = field(default_factory=dict)
    constant_values: dict[str, int] = field(default_factory=dict)

    def kind(self, name: str) -> str | None:
        """What ``name`` is declared as: ``"event"``, ``"measure"``, ``"constant"``, else None."""
        if name in self.events:
            return "event"
        if name in self.measures:
            return "measure"
        if name in self.constants:
            return "constant"
        return None


# An expression's type: BOOL, NUM, ("scale", measure) or ("lit", literal) -- a bare name
# that is no measure or constant and can only be a scale literal -- or None after an error.
Type = str | tuple[str, str] | None


class Checker:
    def __init__(self, spec: A.Specification, sink: DiagnosticSink, options: Options) -> None:
        self.spec = spec
        self.sink = sink
        self.opt = options
        self.table = SymbolTable()
        self.scale_literals: set[str] = set()
        self._owners_of: dict[str, list[str]] = {}  # scale literal -> the measures whose scale has it
        self._cycles: set[frozenset[str]] = set()
        self._suggestions: dict[tuple[str, str], str | None] = {}  # _did_you_mean's answers
        self.reading = LegosReading()  # what legos_compat reads differently (compat.py)
        self._taken: dict[int, set[str]] = {}  # id(a renames map of reading) -> names in use there

    # ------------------------------------------------------------------ entry point
    def run(self) -> SymbolTable:
        spec = self.spec
        if not spec.has_def_block:
            self.sink.error(
                "no-def-block",
                "no def block: events and measures are not declared",
                spec.rules[0].span if spec.rules else A.NO_SPAN,
                hint="add `def_start ... def_end`, or run with --infer-defs to infer the declarations",
            )
            return self.table
        self._definitions()
        self._constants()
        if not spec.rules and any(b.kind == "rule" for b in spec.blocks):
            mark = next(b for b in spec.blocks if b.kind == "rule")
            self.sink.error(
                "empty-rule-block", "empty rule block: a rule set needs at least one rule", mark.span
            )
        self._rules()
        self._situations()
        self._relations()
        check_priorities(
            spec,
            self.sink,
            kind=self.table.kind,
            strict=self.opt.strict_extensions,
            repeat_limit=self.opt.repeat_limit,
        )
        return self.table

    # ------------------------------------------------------------------ declarations
    def _definitions(self) -> None:
        t = self.table
        first: dict[str, A.Definition] = {}
        for d in self.spec.definitions:
            if isinstance(d, A.FluentDecl):
                self.sink.warning(
                    "unsupported-fluent",
                    f"`fluent {clip(d.name)}` is an extension of CPeluti/LEGOS-SLEEC (goal fluents for "
                    "conflict explanation); cosleec ignores it",
                    d.span,
                )
                continue
            self._check_name(d.name, d.span)
            if d.name in first:
                prev = first[d.name]
                if prev == d:  # the same declaration again: harmless, but worth cleaning up
                    self.sink.warning(
                        "redeclared",
                        f"`{clip(d.name)}` is declared twice, identically",
                        d.span,
                        related=(("first declared here", prev.span),),
                    )
                    continue
                self.sink.error(
                    "duplicate-name",
                    f"`{clip(d.name)}` is already declared as {_kind_word(prev)}",
                    d.span,
                    related=((f"`{clip(d.name)}` first declared here", prev.span),),
                )
                continue
            first[d.name] = d
            if isinstance(d, A.EventDecl):
                t.events[d.name] = d
                if self.opt.lint and not d.name[:1].isupper():
                    self.sink.warning(
                        "naming", f"event `{clip(d.name)}` should start with an upper-case letter", d.span
                    )
            elif isinstance(d, A.MeasureDecl):
                t.measures[d.name] = d
                if self.opt.lint and not d.name[:1].islower():
                    self.sink.warning(
                        "naming", f"measure `{clip(d.name)}` should start with a lower-case letter", d.span
                    )
            else:
                t.constants[d.name] = d
                if self.opt.lint and d.name != d.name.upper():
                    self.sink.warning("naming", f"constant `{clip(d.name)}` should be ALL_CAPS", d.span)
        # scale literals: unique within their scale, distinct from every declared name
        for m in t.measures.values():
            if isinstance(m.type, A.ScaleType):
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
                        self._owners_of.setdefault(lit, []).append(m.name)
                    seen.add(lit)
                    if lit in first:
                        self.sink.error(
                            "literal-clash",
                            f"scale literal `{clip(lit)}` of `{clip(m.name)}` has the name of "
                            f"{_kind_word(first[lit])}",
                            span,
                        )
                    self._check_name(lit, span)
                self.scale_literals |= seen

    def _check_name(self, name: str, span: A.Span) -> None:
        """A declared or rule name: a SLEEC identifier (a Specification built in Python may
        hold anything), and with ``tk_names`` not one SLEEC-TK rejects."""
        if not _IDENTIFIER.fullmatch(name):
            self.sink.error(
                "malformed-name",
                f"`{clip(name)}` is not a SLEEC name",
                span,
                hint="a name is a letter or `_`, then letters, digits or `_`",
            )
            return
        # A keyword reaches the AST as a name only through SLEEC-TK's `^when` escape, which
        # makes it a name (docs/reference/sleec-language.md §3), or from the paper notation, which does
        # not reserve the DSL's words: either way it is a name. The printer escapes it.
        if self.opt.tk_names and name in TK_RESERVED:
            self.sink.warning(
                "tk-reserved",
                f"SLEEC-TK rejects the name `{clip(name)}` (it clashes with its CSP encoding)",
                span,
            )

    def _constants(self) -> None:
        t = self.table
        for c in t.constants.values():
            self._constant_value(c.name, [])

    def _constant_value(self, name: str, path: list[str]) -> int | None:
        t = self.table
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
            kind = t.kind(ref)
            if kind is not None:
                self.sink.error(
                    "constant-ref",
                    f"constant `{clip(name)}` refers to {kind} `{clip(ref)}`; only constants can",
                    c.span,
                )
            else:
                self.sink.error(
                    "undeclared",
                    f"constant `{clip(name)}` refers to undeclared `{clip(ref)}`",
                    c.span,
                    hint=self._did_you_mean(ref, "constants", "undeclared"),
                )
            return None
        v = self._constant_value(ref, [*path, name])
        if v is not None:
            t.constant_values[name] = v
        return v

    # ------------------------------------------------------------------ rules
    def _rules(self) -> None:
        names: dict[str, A.Rule] = {}
        nth: dict[str, int] = {}
        for i, r in enumerate(self.spec.rules):
            if r.name in names:
                related = ((f"`{clip(r.name)}` first defined here", names[r.name].span),)
                if self.opt.legos_compat:
                    new = self._rename(self.reading.rules, i, r.name, nth, self.spec.rules)
                    self.sink.warning(
                        "duplicate-rule",
                        f"rule `{clip(r.name)}` is defined twice; LEGOS-SLEEC keeps both rules (it "
                        f"never compares rule names), and so does cosleec, calling this one `{clip(new)}`",
                        r.span,
                        related=related,
                        hint="give each rule a name of its own",
                    )
                else:
                    self.sink.error(
                        "duplicate-rule", f"rule `{clip(r.name)}` is defined twice", r.span, related=related
                    )
            else:
                names[r.name] = r
            self._check_name(r.name, r.span)
            # a rule's clauses can repeat one mistake thousands of times: report some, count the rest
            with self.sink.folding(f"rule `{clip(r.name)}`", self.opt.repeat_limit):
                self._trigger(r.trigger)
                self._response(r.response, top=True)

    def _trigger(self, trig: A.Trigger) -> None:
        self._event(trig.event, trig.span, "trigger")
        if trig.condition is not None:
            self._condition(trig.condition)

    def _event(self, name: str, span: A.Span, role: str) -> None:
        t = self.table
        if name in t.events:
            return
        kind = t.kind(name)
        if kind is not None:
            self.sink.error("not-an-event", f"{role} `{clip(name)}` is a {kind}, not an event", span)
        else:
            self.sink.error(
                "undeclared-event",
                f"{role} `{clip(name)}` is not declared as an event",
                span,
                hint=self._did_you_mean(name, "events", "undeclared-event"),
            )

    def _response(self, resp: A.Response, top: bool) -> None:
        if len(resp.items) > 1 and self.opt.strict_extensions:
            self.sink.error(
                "extension-conjunction",
                "`then A and B` (a conjunction of responses) is a cosleec extension, rejected by --strict",
                resp.items[1].span,
            )
        for item in resp.items:
            occ = item.occurrence
            self._event(occ.event, occ.span, "response")
            if occ.limit is not None:
                self._time_limit(occ.limit)
            if item.otherwise is not None:
                if occ.eventually:
                    self.sink.warning(
                        "unreachable-otherwise",
                        f"`otherwise` after `{clip(occ.event)} eventually` can never start",
                        item.otherwise.span,
                    )
                elif occ.limit is None:
                    self.sink.warning(
                        "untimed-otherwise",
                        f"`otherwise` after untimed `{clip(occ.event)}` is read as `within 0 seconds`",
                        item.otherwise.span,
                    )
                self._response(item.otherwise, top=False)
            if item.alternative is not None:
                self._response(item.alternative, top=False)
            if self.opt.lint and occ.negated and occ.limit is None and not occ.eventually:
                self.sink.warning(
                    "untimed-prohibition",
                    f"`not {clip(occ.event)}` forbids it only at the trigger instant",
                    occ.span,
                    hint="add `within T` or `eventually`",
                )
        for d in resp.defeaters:
            self._condition(d.condition)
            if d.response is not None:
                self._response(d.response, top=False)
        self._hedges(resp)

    def _hedges(self, resp: A.Response) -> None:
        """Warn about hedge clauses that no situation selects, under the chosen semantics.

        What is known statically -- conditions that are the literal `true` or `false`, and
        conditions that imply another (equal, or a conjunct of it) -- is handed to
        :func:`hedges.reachable`, which asks :func:`hedges.choose` about every situation
        consistent with it; a clause it never chooses gets a warning naming the cause.

        That is done only for a rule of at most :data:`MAX_LINT_CLAUSES` clauses, and gives
        an answer only when few enough conditions are unknown (``hedges.MAX_FREE_CONDITIONS``).
        Otherwise only clauses whose condition is the literal ``false`` are reported: no
        semantics chooses a clause whose condition does not hold (hedges' module docstring).
        """
        ds = resp.defeaters
        if not ds:
            return
        conds = [d.condition for d in ds]
        fixed = {i + 1: c.value for i, c in enumerate(conds) if isinstance(c, A.BoolLit)}
        implies = _implication(conds) if len(ds) <= MAX_LINT_CLAUSES else None
        chosen = None
        if implies is not None:
            chosen = hedges.reachable(len(ds), self.opt.semantics, fixed=fixed, implies=implies)
        if chosen is None or implies is None:
            for i, value in fixed.items():
                if not value:
                    self._never(ds, i)
            return
        for i in range(1, len(ds) + 1):
            if i not in chosen:
                self._unreachable(ds, i, fixed, implies)

    def _never(self, ds: tuple[A.Defeater, ...], i: int) -> None:
        """Report clause ``i``, whose condition is the literal ``false``."""
        self.sink.warning(
            "unreachable-hedge", f"clause {i}: condition is `false`, it never applies", ds[i - 1].span
        )

    def _unreachable(
        self, ds: tuple[A.Defeater, ...], i: int, fixed: dict[int, bool], implies: Callable[[int, int], bool]
    ) -> None:
        """Report clause ``i`` as never chosen, naming the clause that blocks it (found by
        :func:`hedges.blockers`, so that no semantics is restated here)."""
        span = ds[i - 1].span
        if fixed.get(i) is False:
            self._never(ds, i)
            return
        semantics = self.opt.semantics
        culprits = hedges.blockers(i, len(ds), semantics, fixed=fixed, implies=implies)
        if not culprits:
            self.sink.warning(
                "unreachable-hedge", f"clause {i} never applies under {semantics} semantics", span
            )
            return
        j = culprits[0]
        related = (("the clause that blocks it", ds[j - 1].span),)
        if ds[j - 1].condition == ds[i - 1].condition:
            self.sink.warning(
                "duplicate-hedge",
                f"clause {i} has the same condition as clause {j}; under {semantics} semantics "
                f"clause {i} never applies",
                span,
                related=related,
            )
            return
        if fixed.get(j) is not None:
            why = f"clause {j}'s condition is `{'true' if fixed[j] else 'false'}`"
        elif implies(i, j):
            why = f"whenever clause {i} holds, clause {j} holds too"
        else:
            why = f"what is known of clause {j}'s condition rules it out"
        self.sink.warning(
            "unreachable-hedge",
            f"clause {i} never applies under {semantics} semantics: {why}",
            span,
            related=related,
        )

    def _time_limit(self, lim: A.TimeLimit) -> None:
        hi = self._duration(lim.hi)
        if lim.lo is not None:
            lo = self._duration(lim.lo)
            if lo is not None and hi is not None and lo > hi:
                self.sink.error("bad-deadline", f"interval starts after it ends ({lo} s > {hi} s)", lim.span)

    def _duration(self, d: A.Duration) -> float | None:
        """Check a duration; return its length in seconds when it is constant."""
        unit = A.TIME_UNITS.get(d.unit)
        if unit is None:
            lower = d.unit.lower()
            plural = lower + "s"
            if lower in A.TIME_UNITS:  # `Seconds`, `MINUTES`: a keyword, and SLEEC's are lower-case
                hint: str | None = f"units are keywords, written in lower case: `{lower}`"
            elif plural in A.TIME_UNITS:
                hint = f"SLEEC uses plural units: `{plural}`"
            else:
                hint = None
            if hint is None:
                close = difflib.get_close_matches(d.unit, list(A.TIME_UNITS), n=1)
                hint = f"did you mean `{close[0]}`?" if close else "units are seconds, minutes, hours, days"
            # the unit is the span's last token, on its last line
            at = A.Span(d.span.end_line, d.span.end_col - len(d.unit), d.span.end_line, d.span.end_col)
            self.sink.error("bad-unit", f"`{clip(d.unit)}` is not a time unit", at, hint=hint)
        ty = self._expr(d.value)
        if ty is not None and ty != NUM:
            self.sink.error(
                "bad-deadline", f"a deadline must be a number, not {_type_word(ty)}", _span(d.value)
            )
            return None
        v = self._const_eval(d.value)
        if v is not None and unit is not None:
            if v < 0:
                self.sink.error(
                    "bad-deadline", f"negative deadline ({clip(str(v))} {d.unit})", _span(d.value)
                )
            return v * unit
        return None

    def _const_eval(self, e: A.Expr) -> int | None:
        if isinstance(e, A.IntLit):
            return e.value
        if isinstance(e, A.Name):
            return self.table.constant_values.get(e.name)
        if isinstance(e, A.BinOp) and e.op in A.ARITH_OPS:
            a, b = self._const_eval(e.left), self._const_eval(e.right)
            if a is None or b is None:
                return None
            return a + b if e.op == "+" else a - b if e.op == "-" else a * b
        return None

    # ------------------------------------------------------------------ expressions
    def _condition(self, e: A.Expr) -> None:
        ty = self._expr(e)
        if ty is not None and ty != BOOL:
            self.sink.error(
                "not-boolean", f"a condition must be true or false, not {_type_word(ty)}", _span(e)
            )

    def _expr(self, e: A.Expr) -> Type:
        if isinstance(e, A.Name):
            return self._name(e)
        if isinstance(e, A.BoolLit):
            return BOOL
        if isinstance(e, A.IntLit):
            return NUM
        if isinstance(e, A.DecimalLit):
            self.sink.error(
                "decimal",
                f"`{clip(e.text)}`: SLEEC numbers are integers (no decimal literals)",
                e.span,
                hint="scale the measure, e.g. tenths of a degree",
            )
            return NUM
        if isinstance(e, A.Not):
            ty = self._expr(e.operand)
            if ty is not None and ty != BOOL:
                self.sink.error("type", f"`not` needs a truth value, not {_type_word(ty)}", e.span)
            return BOOL
        if isinstance(e, A.BinOp | A.Compare) and e.op not in _OPERATORS[type(e)]:
            self.sink.error(  # only a Specification built in Python can hold one
                "malformed-expr",
                f"`{e.op}` is not a SLEEC operator; expected one of {', '.join(sorted(_OPERATORS[type(e)]))}",
                e.span,
            )
            return None
        if isinstance(e, A.BinOp):
            if e.op in A.BOOL_OPS:
                self._mixed(e)
                for side in (e.left, e.right):
                    ty = self._expr(side)
                    if ty is not None and ty != BOOL:
                        self.sink.error(
                            "type", f"`{e.op}` needs truth values, not {_type_word(ty)}", _span(side)
                        )
                return BOOL
            for side in (e.left, e.right):
                ty = self._expr(side)
                if ty is not None and ty != NUM:
                    self.sink.error(
                        "arith-type", f"arithmetic `{e.op}` needs numbers, not {_type_word(ty)}", _span(side)
                    )
            return NUM
        return self._compare(e)

    def _mixed(self, e: A.BinOp) -> None:
        left = e.left
        if isinstance(left, A.BinOp) and left.op in A.BOOL_OPS and left.op != e.op and not left.parenthesized:
            msg = (
                f"`{left.op}` and `{e.op}` mixed without parentheses: read left to right as "
                f"`(... {left.op} ...) {e.op} ...`"
            )
            hint = "add parentheses to say which you mean"
            if self.opt.strict_precedence:
                self.sink.error("mixed-and-or", msg, e.span, hint=hint)
            else:
                self.sink.warning("mixed-and-or", msg, e.span, hint=hint)

    def _name(self, n: A.Name) -> Type:
        t = self.table
        m = t.measures.get(n.name)
        if m is not None:
            if n.arrow:
                self.sink.error(
                    "kind",
                    f"`->{clip(n.name)}` refers to a constant, but `{clip(n.name)}` is a measure",
                    n.span,
                )
            if isinstance(m.type, A.BooleanType):
                return BOOL
            if isinstance(m.type, A.NumericType):
                return NUM
            return ("scale", n.name)
        if n.name in t.constants:
            if n.braced:
                self.sink.error(
                    "kind",
                    f"`{{{clip(n.name)}}}`: `{clip(n.name)}` is a constant; braces mark measures",
                    n.span,
                )
            return NUM
        if n.name in t.events:
            self.sink.error("not-a-measure", f"`{clip(n.name)}` is an event, not a measure", n.span)
            return None
        if n.name in self.scale_literals and not n.braced and not n.arrow:
            return ("lit", n.name)
        what = "constant" if n.arrow else "measure"
        self.sink.error(
            "undeclared",
            f"`{clip(n.name)}` is not declared (expected a {what})",
            n.span,
            hint=self._did_you_mean(n.name, "values", "undeclared"),
        )
        return None

    def _compare(self, e: A.Compare) -> Type:
        if self._unknown_literal(e):
            return BOOL
        lt, rt = self._expr(e.left), self._expr(e.right)
        if lt is None or rt is None:
            return BOOL
        # a scale literal takes the scale of the other side
        if isinstance(lt, tuple) and lt[0] == "lit":
            lt, rt = rt, lt
            lit_side, other = e.left, e.right
        else:
            lit_side, other = e.right, e.left
        if isinstance(rt, tuple) and rt[0] == "lit":
            lit = rt[1]
            if isinstance(lt, tuple) and lt[0] == "scale":
                m = self.table.measures[lt[1]]
                assert isinstance(m.type, A.ScaleType)
                if lit not in m.type.literals:
                    if self.opt.legos_compat and self._legos_literal(e, lit_side, lit, m.name, m.type):
                        return BOOL
                    owners = self._owners(lit)
                    self.sink.error(
                        "scale-literal",
                        f"`{clip(lit)}` is not in the scale of `{clip(lt[1])}` "
                        f"({clip(', '.join(m.type.literals), 4 * QUOTE_LIMIT)}); "
                        f"it is a literal of `{owners}`",
                        _span(lit_side),
                        hint="scale literals belong to their measure (LEGOS-SLEEC's global "
                        "literal table lets such cross-scale comparisons through)",
                    )
                return BOOL
            if isinstance(lt, tuple) and lt[0] == "lit":
                self.sink.error(
                    "type", f"`{e.op}` compares two scale literals; one side must be a measure", e.span
                )
                return BOOL
            if self.opt.legos_compat and lt == NUM and self._legos_number(lit_side, lit):
                return BOOL
            owners = self._owners(lit)
            self.sink.error(
                "type",
                f"scale literal `{clip(lit)}` (of `{owners}`) compared with {_type_word(lt)}",
                _span(lit_side),
            )
            return BOOL
        if lt == BOOL or rt == BOOL:
            if e.op in ("=", "<>") and lt == rt == BOOL:
                return BOOL
            self.sink.error(
                "bool-relop",
                f"`{e.op}` cannot order truth values"
                if e.op not in ("=", "<>")
                else f"`{e.op}` compares a truth value with {_type_word(rt if lt == BOOL else lt)}",
                e.span,
            )
            return BOOL
        if lt != rt:
            if self.opt.legos_compat and self._legos_scale_number(e, lt, rt):
                return BOOL
            self.sink.error("type", f"`{e.op}` compares {_type_word(lt)} with {_type_word(rt)}", e.span)
        del other
        return BOOL

    # ------------------------------------------------------------------ legos_compat
    # LEGOS-SLEEC reads a scale literal as its position in its own scale and a scale measure
    # as its position in its scale, and compares positions as integers (compat.py). Each
    # method below reads one such comparison that way, warns, records the reading and returns
    # True; it returns False (the caller reports the error) where LEGOS-SLEEC has no reading.

    def _unknown_literal(self, e: A.Compare) -> bool:
        """``m op x`` with ``m`` a scale measure and ``x`` a bare name declared nowhere, not
        even as a literal of another scale: ``x`` can only be a literal of ``m``'s scale, so
        report it as one that is not, listing that scale (and the closest literal)."""
        t = self.table
        for side, other in ((e.left, e.right), (e.right, e.left)):
            if not (isinstance(side, A.Name) and isinstance(other, A.Name)):
                continue
            m = t.measures.get(side.name)
            if m is None or not isinstance(m.type, A.ScaleType) or other.braced or other.arrow:
                continue
            lit = other.name
            if lit in self.scale_literals or t.kind(lit) is not None:
                continue
            self._expr(side)  # the measure's own checks (`->m`)
            literals = m.type.literals
            close = closest(lit, literals)
            shown = ", ".join(literals)
            self.sink.error(
                "scale-literal",
                f"`{clip(lit)}` is not in the scale of `{clip(m.name)}` ({clip(shown, 4 * QUOTE_LIMIT)})",
                other.span,
                hint=f"did you mean `{clip(close)}`?"
                if close
                else f"compare `{clip(m.name)}` with one of its literals: {clip(shown, 4 * QUOTE_LIMIT)}",
            )
            return True
        return False

    def _legos_position(self, lit: str) -> int | None:
        """``lit``'s position in LEGOS-SLEEC's one table of literals: its index in its scale,
        the same in every scale that has it (or None: LEGOS-SLEEC's table asserts that)."""
        found = set()
        for owner in self._owners_of.get(lit, ()):
            t = self.table.measures[owner].type
            assert isinstance(t, A.ScaleType)
            found.add(t.literals.index(lit))
        return found.pop() if len(found) == 1 else None

    def _legos_literal(self, e: A.Compare, node: A.Expr, lit: str, measure: str, scale: A.ScaleType) -> bool:
        """``{measure} op lit`` with ``lit`` a literal of another scale."""
        p = self._legos_position(lit)
        if p is None:
            return False
        owners = self._owners(lit)
        head = (
            f"`{clip(lit)}` is not in the scale of `{clip(measure)}` "
            f"({clip(', '.join(scale.literals), 4 * QUOTE_LIMIT)}); LEGOS-SLEEC reads a scale "
            f"literal as its position in its own scale, and `{clip(lit)}` is the {ordinal(p)} of "
            f"`{owners}`'s"
        )
        if p < len(scale.literals):
            new = scale.literals[p]
            self.reading.replace(node, _renamed(node, new))
            self.sink.warning(
                "scale-literal",
                f"{head}, so cosleec reads it as `{clip(new)}`, the {ordinal(p)} of `{clip(measure)}`'s",
                _span(node),
                hint=f"write `{clip(new)}` if that is what is meant",
            )
            return True
        op = e.op if node is e.right else mirrored(e.op)  # with the measure on the left
        value = holds(op, 0, p)  # every position of the scale is below p
        self._legos_constant(e, value)
        self.sink.warning(
            "scale-literal",
            f"{head}, beyond the {len(scale.literals)} of `{clip(measure)}`'s: LEGOS-SLEEC compares "
            f"the positions, so the comparison is always {str(value).lower()}, and cosleec reads it "
            f"as `{str(value).lower()}`",
            _span(node),
            hint=f"compare with a literal of `{clip(measure)}`: "
            f"{clip(', '.join(scale.literals), 4 * QUOTE_LIMIT)}",
        )
        return True

    def _legos_number(self, node: A.Expr, lit: str) -> bool:
        """A scale literal compared with a number (a numeric measure, say)."""
        p = self._legos_position(lit)
        if p is None:
            return False
        parens = node.parenthesized
        self.reading.replace(node, A.IntLit(p, parenthesized=parens, span=node.span))
        self.sink.warning(
            "type",
            f"scale literal `{clip(lit)}` (of `{self._owners(lit)}`) is compared with a number; "
            f"LEGOS-SLEEC reads a scale literal as its position in its scale, so cosleec reads it "
            f"as {p}",
            _span(node),
            hint="compare a number with a number, a scale measure with its own literals",
        )
        return True

    def _legos_scale_number(self, e: A.Compare, lt: Type, rt: Type) -> bool:
        """A scale measure compared with a constant number."""
        if isinstance(lt, tuple) and lt[0] == "scale" and rt == NUM:
            measure, number, op = lt[1], e.right, e.op
        elif isinstance(rt, tuple) and rt[0] == "scale" and lt == NUM:
            measure, number, op = rt[1], e.left, mirrored(e.op)
        else:
            return False
        c = self._const_eval(number)
        if c is None:
            return False
        scale = self.table.measures[measure].type
        assert isinstance(scale, A.ScaleType)
        shown = f"`{clip(number.name)}` = {c}" if isinstance(number, A.Name) else f"{c}"
        head = (
            f"`{e.op}` compares the scale of `{clip(measure)}` with a number ({shown}); LEGOS-SLEEC "
            f"compares the measure's position in its scale (0 to {len(scale.literals) - 1}) with it"
        )
        hint = (
            f"compare with a literal of `{clip(measure)}`: {clip(', '.join(scale.literals), 4 * QUOTE_LIMIT)}"
        )
        if 0 <= c < len(scale.literals):
            new = scale.literals[c]
            self.reading.replace(number, A.Name(new, parenthesized=number.parenthesized, span=number.span))
            self.sink.warning(
                "type",
                f"{head}, so cosleec reads {c} as `{clip(new)}`, the {ordinal(c)} of `{clip(measure)}`'s",
                e.span,
                hint=hint,
            )
            return True
        value = holds(op, 0, c)  # every position is on the same side of c
        self._legos_constant(e, value)
        self.sink.warning(
            "type",
            f"{head}: always {str(value).lower()}, and cosleec reads it as `{str(value).lower()}`",
            e.span,
            hint=hint,
        )
        return True

    def _legos_constant(self, e: A.Compare, value: bool) -> None:
        self.reading.replace(e, A.BoolLit(value, parenthesized=e.parenthesized, span=e.span))

    # ------------------------------------------------------------------ LEGOS blocks
    def _situations(self) -> None:
        for block, items, renames in (
            ("concern", self.spec.concerns, self.reading.concerns),
            ("purpose", self.spec.purposes, self.reading.purposes),
        ):
            seen: dict[str, A.Situation] = {}
            nth: dict[str, int] = {}
            for i, s in enumerate(items):
                if s.name in seen:
                    related = (("first defined here", seen[s.name].span),)
                    if self.opt.legos_compat:
                        new = self._rename(renames, i, s.name, nth, items)
                        self.sink.warning(
                            "duplicate-name",
                            f"{block} `{clip(s.name)}` is defined twice; LEGOS-SLEEC keeps both (it "
                            f"never compares {block} names), and so does cosleec, calling this one "
                            f"`{clip(new)}`",
                            s.span,
                            related=related,
                            hint=f"give each {block} a name of its own",
                        )
                    else:
                        self.sink.error(
                            "duplicate-name",
                            f"{block} `{clip(s.name)}` is defined twice",
                            s.span,
                            related=related,
                        )
                seen.setdefault(s.name, s)
                with self.sink.folding(f"{block} `{clip(s.name)}`", self.opt.repeat_limit):
                    cur: A.Situation | None = s
                    while cur is not None:
                        self._trigger(cur.trigger)
                        for r in cur.responses:
                            self._response(r, top=True)
                        cur = cur.meanwhile

    def _relations(self) -> None:
        for rel in self.spec.relations:
            if isinstance(rel, A.EventRelation):
                if rel.kind == "conflict":
                    self._nonstandard(rel.span, "conflict", "mutualExclusive")
                    continue
                self._event(rel.first, rel.span, "relation")
                self._event(rel.second, rel.span, "relation")
            elif isinstance(rel, A.MeasureRelation):
                if rel.kind == "conflict":
                    self._nonstandard(rel.span, "measure conflict", "measure mutualExclusive")
                    continue
                self._condition(rel.first)
                if rel.second is not None:
                    self._condition(rel.second)
            elif isinstance(rel, A.EventMeasureRelation):
                if rel.kind == "effect":
                    self._nonstandard(rel.span, "effect", "includes")
                    continue
                self._event(rel.event, rel.span, "relation")
                self._condition(rel.condition)
            elif isinstance(rel, A.UntilRelation):
                self._trigger(rel.trigger)
                self._condition(rel.condition)
                self._event(rel.until_event, rel.span, "relation")
                if rel.until_condition is not None:
                    self._condition(rel.until_condition)
            else:
                self._trigger(rel.trigger)
                self._condition(rel.condition)
                self._duration(rel.duration)

    def _rename(
        self,
        renames: dict[int, str],
        i: int,
        name: str,
        nth: dict[str, int],
        items: Sequence[A.Rule] | Sequence[A.Situation],
    ) -> str:
        """The new name of item ``i`` of ``items``, a later definition of ``name``
        (legos_compat): :func:`compat.fresh_name`, clear of every name of ``items`` and of
        the new names given so far; ``nth`` counts the definitions of each name."""
        taken = self._taken.get(id(renames))
        if taken is None:
            taken = self._taken[id(renames)] = {x.name for x in items}
        nth[name] = nth.get(name, 1) + 1
        new = fresh_name(name, nth[name], taken)
        taken.add(new)
        renames[i] = new
        return new

    def _owners(self, lit: str) -> str:
        """The measures whose scale has ``lit``, for a message: `` `a`, `b` `` without the outer
        backticks, cut to a bounded length. Looked up in a table built with the declarations,
        not by a walk over every measure per comparison."""
        return clip("`, `".join(self._owners_of.get(lit, ())), 4 * QUOTE_LIMIT)

    def _nonstandard(self, span: A.Span, word: str, instead: str) -> None:
        self.sink.error(
            "nonstandard-relation",
            f"`{word}` is not a relation in any published SLEEC grammar (it appears only in "
            "sleecvalDef's LLM-sanitised files)",
            span,
            hint=f"did you mean `{instead}`?",
        )

    def _did_you_mean(self, name: str, among: str, code: str) -> str | None:
        """A "did you mean" hint for an undeclared ``name``: the closest declared name among
        the ``events``, the ``constants`` or the ``values`` (measures and constants).

        The search reads every declared name, so it is done only for a diagnostic with
        ``code`` that will be shown (not folded, :meth:`DiagnosticSink.shown`), and once per
        name: otherwise thousands of clauses misnaming a measure, in a file declaring
        thousands, would cost their product.
        """
        if not self.sink.shown(code):
            return None
        key = (name, among)
        if key not in self._suggestions:
            t = self.table
            pool: list[str] = (
                list(t.events)
                if among == "events"
                else list(t.constants)
                if among == "constants"
                else [*t.measures, *t.constants]
            )
            close = closest(name, pool, cutoff=0.75)
            self._suggestions[key] = f"did you mean `{clip(close)}`?" if close else None
        return self._suggestions[key]


_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_OPERATORS: dict[type, frozenset[str]] = {A.BinOp: A.BOOL_OPS | A.ARITH_OPS, A.Compare: A.REL_OPS}


def _conjuncts(e: A.Expr) -> list[A.Expr]:
    """The operands of a chain of ``and`` (``e`` itself if it is no ``and``), left to right."""
    out: list[A.Expr] = []
    todo = [e]
    while todo:
        x = todo.pop()
        if isinstance(x, A.BinOp) and x.op == "and":
            todo += (x.right, x.left)
        else:
            out.append(x)
    return out


def _implication(conds: Sequence[A.Expr]) -> Callable[[int, int], bool]:
    """``implies(i, j)`` for the hedge lint: condition j (1-based) is condition i, or one of
    its conjuncts, so that it holds whenever condition i does.

    Conditions are compared by hashing (equal ASTs are equal meanings: spans do not take
    part), each numbered once, so a question is one set lookup and setting up costs one
    hash per condition and conjunct -- not a structural comparison per pair of clauses.
    """
    number: dict[A.Expr, int] = {}
    ids = [number.setdefault(c, len(number)) for c in conds]
    implied = [
        frozenset([ids[i], *(number[p] for p in _conjuncts(c) if p in number)]) for i, c in enumerate(conds)
    ]
    return lambda i, j: ids[j - 1] in implied[i - 1]


def _span(e: A.Expr) -> A.Span:
    return e.span


def _renamed(node: A.Expr, name: str) -> A.Name:
    """A scale literal ``node`` (a Name) read as the literal ``name``, written as it was."""
    assert isinstance(node, A.Name)
    return A.Name(name, parenthesized=node.parenthesized, span=node.span)


def _kind_word(d: A.Definition) -> str:
    if isinstance(d, A.EventDecl):
        return "an event"
    if isinstance(d, A.MeasureDecl):
        return "a measure"
    return "a constant"


def _type_word(ty: Type) -> str:
    if ty == BOOL:
        return "a truth value"
    if ty == NUM:
        return "a number"
    if isinstance(ty, tuple):
        return f"the scale of `{clip(ty[1])}`" if ty[0] == "scale" else f"scale literal `{clip(ty[1])}`"
    return "an unknown value"


def check(spec: A.Specification, sink: DiagnosticSink, options: Options | None = None) -> SymbolTable:
    """Check ``spec``; diagnostics go to ``sink``. Returns the resolved symbol table."""
    return Checker(spec, sink, options or Options()).run()


def check_and_read(
    spec: A.Specification, sink: DiagnosticSink, options: Options | None = None
) -> tuple[A.Specification, SymbolTable]:
    """:func:`check`, and the specification as the checks read it: ``spec`` itself, except
    under ``legos_compat``, where it is rebuilt with LEGOS-SLEEC's reading of the defects
    that option lets through (:mod:`cosleec.lang.compat`)."""
    checker = Checker(spec, sink, options or Options())
    table = checker.run()
    return apply(spec, checker.reading), table


__all__ = ["Options", "SymbolTable", "check", "check_and_read"]

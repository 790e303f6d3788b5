"""The checks of triggers and responses (docs/reference/sleec-language.md §5): what rules,
concerns and purposes are made of.

:class:`Responses` checks a trigger (an event, a condition), a response (its occurrences,
their deadlines, ``otherwise`` and ``else``, its ``unless`` clauses and which of them can
ever apply, unreachable.py) and a duration, whichever block they are in.

May import: the lang modules ast, diagnostics, expressions, scope and unreachable.
"""

from __future__ import annotations

import difflib

from cosleec.lang import ast as A
from cosleec.lang.diagnostics import clip
from cosleec.lang.expressions import NUM, Expressions, type_word
from cosleec.lang.mistakes import untimed_otherwise
from cosleec.lang.scope import Scope
from cosleec.lang.unreachable import check_clauses


class Responses:
    """Triggers, responses and durations of one specification (the declarations checked)."""

    def __init__(self, scope: Scope, expressions: Expressions) -> None:
        self.scope = scope
        self.sink = scope.sink
        self.opt = scope.opt
        self.expressions = expressions
        # the file's own clause semantics (its semantics block) comes first: the lint judges
        # the rules as they are meant; the option is for files that declare none
        self.declared = scope.spec.clause_semantics is not None
        self.semantics = scope.spec.clause_semantics or scope.opt.semantics

    def trigger(self, trig: A.Trigger) -> None:
        """A trigger: its event, and its condition if it has one."""
        self.event(trig.event, trig.span, "trigger")
        if trig.condition is not None:
            self.expressions.condition(trig.condition)

    def event(self, name: str, span: A.Span, role: str) -> None:
        """``name``, in ``role`` (``"trigger"``, ``"response"``, ``"relation"``), is a declared event."""
        t = self.scope.table
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
                hint=self.scope.did_you_mean(name, "events", "undeclared-event"),
            )

    def response(self, resp: A.Response) -> None:
        """A response: each item (its event, deadline, ``otherwise`` and ``else``), then each
        ``unless`` clause, then which clauses can ever apply."""
        if len(resp.items) > 1 and self.opt.strict_extensions:
            self.sink.error(
                "extension-conjunction",
                "`then A and B` (a conjunction of responses) is a cosleec extension, rejected by --strict",
                resp.items[1].span,
            )
        for item in resp.items:
            occ = item.occurrence
            self.event(occ.event, occ.span, "response")
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
                    message, fix = untimed_otherwise(item)
                    self.sink.warning(
                        "untimed-otherwise",
                        f"{message}, so it is read as `within 0 seconds`",
                        item.otherwise.span,
                        hint=fix,
                    )
                self._untimed_fallback(item.otherwise)
                self.response(item.otherwise)
            if item.alternative is not None:
                self.response(item.alternative)
            if self.opt.lint and occ.negated and occ.limit is None and not occ.eventually:
                self.sink.warning(
                    "untimed-prohibition",
                    f"`not {clip(occ.event)}` forbids it only at the trigger instant",
                    occ.span,
                    hint="add `within T` or `eventually`",
                )
        for d in resp.defeaters:
            self.expressions.condition(d.condition)
            if d.response is not None:
                self.response(d.response)
        check_clauses(self.sink, self.semantics, resp, declared=self.declared)

    def _untimed_fallback(self, fallback: A.Response) -> None:
        """Warn about each obligation of an ``otherwise`` written without ``within``: read with
        the default ``untimed="none"`` (the runtime's, ``analyse``'s and ``conforms``'), it stays
        pending for ever, so the fallback that should catch a failure can never fail itself.
        ``untimed="immediate"`` or a number of seconds gives it a deadline, hence "default"."""
        for item in fallback.items:
            occ = item.occurrence
            if occ.negated or occ.limit is not None or occ.eventually:
                continue
            name = clip(occ.event)
            self.sink.warning(
                "untimed-fallback",
                f"`otherwise {name}` has no deadline: read with the default `untimed` (none), it "
                "stays pending for ever and can never be violated",
                occ.span,
                hint=f"write `otherwise {name} within 1 minutes` (or give every untimed response a "
                "deadline with `--untimed immediate` or `--untimed SECONDS`)",
            )

    def _time_limit(self, lim: A.TimeLimit) -> None:
        hi = self.duration(lim.hi)
        if lim.lo is not None:
            lo = self.duration(lim.lo)
            if lo is not None and hi is not None and lo > hi:
                self.sink.error("bad-deadline", f"interval starts after it ends ({lo} s > {hi} s)", lim.span)

    def duration(self, d: A.Duration) -> float | None:
        """Check a duration; return its length in seconds when it is constant."""
        unit = A.TIME_UNITS.get(d.unit)
        if unit is None:
            self._bad_unit(d)
        ty = self.expressions.expr(d.value)
        if ty is not None and ty != NUM:
            self.sink.error("bad-deadline", f"a deadline must be a number, not {type_word(ty)}", d.value.span)
            return None
        v = self.expressions.const_eval(d.value)
        if v is not None and unit is not None:
            if v < 0:
                self.sink.error("bad-deadline", f"negative deadline ({clip(str(v))} {d.unit})", d.value.span)
            return v * unit
        return None

    def _bad_unit(self, d: A.Duration) -> None:
        """``d``'s unit is no time unit: say so at the unit, with the likeliest one meant."""
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


__all__ = ["Responses"]

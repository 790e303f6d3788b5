"""Rule priorities, cosleec's extension of SLEEC (docs/reference/sleec-language.md §13): ``H > L``.

A priority says which of two rules gives way when both are active: the runtime cancels the
lower rule's instance (at once, or -- conflict-aware -- only when keeping it would make the
higher rule impossible, §13.2 and §13.3). Priorities reach cosleec three ways: a file's
``priority_start ... priority_end`` block, the command line, and the ``Manager``. This module
is the one home of what they share:

- :func:`parse_priority` reads the command-line form (``"Rule21 > Rule3"``, ``"A > B > C"``);
- :class:`PrioritySemantics` says how a priority resolves a clash (``cancel`` or
  ``conflict-aware``; :data:`CANCEL` and :data:`CONFLICT_AWARE` are its members);
- :func:`pairs` gives a specification's declared pairs; :func:`closure` and :func:`cycle`
  answer the questions every consumer asks of a set of pairs (does H outrank L, even
  indirectly? is the order contradictory?);
- :func:`check_priorities` is the checker's part for a file's block: every name a rule, no
  rule above itself, no cycle, no pair declared twice, and no block at all under ``--strict``.

May import: errors, and the lang modules ast and diagnostics.
"""

from __future__ import annotations

import difflib
import re
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from enum import StrEnum
from itertools import pairwise

from cosleec.errors import ConfigurationError
from cosleec.lang import ast as A
from cosleec.lang.diagnostics import QUOTE_LIMIT, DiagnosticSink, clip

__all__ = [
    "CANCEL",
    "CONFLICT_AWARE",
    "PRIORITY_SEMANTICS",
    "PrioritySemantics",
    "check_priorities",
    "closure",
    "cycle",
    "pairs",
    "parse_priority",
]

Pair = tuple[str, str]
"""``(higher, lower)``: rule ``higher`` takes precedence over rule ``lower``."""


class PrioritySemantics(StrEnum):
    """How a priority ``H > L`` resolves a clash between an instance of H and one of L.

    One of the options every reading of rules takes (the Manager's ``priority_semantics``,
    ``--priority-semantics``, the audit log's ``options`` record). A member equals its
    string (``PrioritySemantics.CANCEL == "cancel"``), so a value given as text compares as
    the member does.
    """

    CANCEL = "cancel"  # SLEEC-TK's cancellation-based priority (§13.2): L is cancelled at once
    CONFLICT_AWARE = "conflict-aware"  # SLEEC-TK's conflict-aware priority (§13.3): L kept while it can be


CANCEL = PrioritySemantics.CANCEL
CONFLICT_AWARE = PrioritySemantics.CONFLICT_AWARE
PRIORITY_SEMANTICS = tuple(s.value for s in PrioritySemantics)
"""The choices as plain strings, for messages and ``argparse`` choices."""

_NAME = re.compile(r"\^?([A-Za-z_][A-Za-z0-9_]*)")  # a SLEEC name; SLEEC-TK's `^` escape dropped
_HINT = "write it as HIGHER > LOWER, e.g. `Rule21 > Rule3` (a chain `A > B > C` declares A > B and B > C)"
_RELATED_LIMIT = 8
"""How many of a cycle's other pairs a ``priority-cycle`` diagnostic points to (a generated
file can hold a cycle of any length; the message itself is clipped)."""


# ---------------------------------------------------------------------------- the public functions


def parse_priority(text: str) -> list[Pair]:
    """The pairs a command-line priority declares: ``"A > B > C"`` -> ``[("A", "B"), ("B", "C")]``.

    Use it for priorities given outside a rule file (a CLI option, a configuration value):
    it reads exactly what one entry of a file's priority block reads, spaces anywhere or
    nowhere (``"Rule21>Rule3"``). Only the form is checked here; whether the names are rules
    of a rule set, and whether the order is free of cycles, is for the caller who knows the
    rules (:func:`cycle`).

    Raises :class:`cosleec.errors.ConfigurationError` (a ``UserError`` and a ``ValueError``)
    when ``text`` is not two or more rule names separated by ``>``.

    Example::

        >>> parse_priority("Rule5 > Rule2 > Rule1")
        [('Rule5', 'Rule2'), ('Rule2', 'Rule1')]
    """
    shown = clip(text.strip())
    hint = _HINT
    if "<" in text:
        hint = "the higher rule comes first, with `>`: " + _HINT
    if not text.strip():
        raise ConfigurationError("empty priority", hint=hint)
    names = []
    for part in text.split(">"):
        word = part.strip()
        m = _NAME.fullmatch(word)
        if m is None:
            problem = (
                "a rule name is missing around `>`" if not word else f"`{clip(word)}` is not a rule name"
            )
            raise ConfigurationError(f"malformed priority `{shown}`: {problem}", hint=hint)
        names.append(m.group(1))
    if len(names) < 2:
        raise ConfigurationError(
            f"malformed priority `{shown}`: it names one rule; a priority orders two", hint=hint
        )
    return list(pairwise(names))


def pairs(spec: A.Specification) -> list[Pair]:
    """The pairs ``spec``'s priority block declares, in file order (chains expanded, repeats kept)."""
    return [(p.higher, p.lower) for p in spec.priorities]


def closure(pairs: Iterable[Pair]) -> frozenset[Pair]:
    """The transitive closure: ``(h, l)`` for every rule ``l`` below ``h`` through one or more pairs.

    Use it to ask whether one rule outranks another even indirectly (``A > B``, ``B > C``
    give ``A > C``). Its size can be quadratic in the number of rules. A rule on a cycle is
    below itself: ``(r, r)`` is in the closure exactly when :func:`cycle` would find one
    through ``r``.
    """
    succ = _successors(pairs)
    out: set[Pair] = set()
    for start, first in succ.items():
        seen: set[str] = set()
        todo = list(first)
        while todo:
            node = todo.pop()
            if node not in seen:
                seen.add(node)
                todo.extend(succ[node])
        out.update((start, node) for node in seen)
    return frozenset(out)


def cycle(pairs: Iterable[Pair]) -> list[str] | None:
    """A cycle of ``pairs`` as the names along it, the first repeated at the end, or None.

    ``[("A", "B"), ("B", "A")]`` gives ``["A", "B", "A"]``, and a rule above itself
    ``[("A", "A")]`` gives ``["A", "A"]``. Prioritised rules must form no cycle (no rule may
    be, even indirectly, above itself): a caller given priorities from outside a file checks
    them with this. Linear in the number of pairs; the cycle found is the shortest one
    through the first-named rule of the first cyclic group.
    """
    found = _cycles(_successors(pairs))
    return found[0] if found else None


# ---------------------------------------------------------------------------- the checker's part


def check_priorities(
    spec: A.Specification,
    sink: DiagnosticSink,
    *,
    kind: Callable[[str], str | None],
    strict: bool = False,
    repeat_limit: int = 20,
) -> None:
    """Check ``spec``'s priority block; diagnostics go to ``sink``. Called by the checker.

    Errors: ``extension-priority`` (with ``strict``, i.e. ``--strict``: the block is a cosleec
    extension), ``undeclared-rule`` (with a "did you mean" among the rule names),
    ``not-a-rule`` (``kind(name)`` says what the name is instead), ``priority-self``,
    ``priority-cycle`` (once per group of rules on a cycle, naming one cycle). Warning:
    ``duplicate-priority`` for a pair declared twice as it stands (``A > B`` again, not one
    implied by others). Pairs with an error take no part in the later checks.
    """
    mark = next((b.span for b in spec.blocks if b.kind == "priority"), None)
    if mark is None and not spec.priorities:
        return
    if strict:
        sink.error(
            "extension-priority",
            "a priority block (`priority_start`) is a cosleec extension, rejected by --strict",
            mark if mark is not None else spec.priorities[0].span,
        )
    rules = [r.name for r in spec.rules]
    known = set(rules)
    suggest = _Suggestions(rules, sink)
    first: dict[Pair, int] = {}  # a valid pair -> the index of its first declaration
    with sink.folding("the priority block", repeat_limit):
        for i, p in enumerate(spec.priorities):
            ok = _named(p.higher, _where(p.higher_span, p), known, kind, suggest, sink)
            if p.lower != p.higher:
                ok = _named(p.lower, _where(p.lower_span, p), known, kind, suggest, sink) and ok
            if not ok:
                continue
            if p.higher == p.lower:
                sink.error(
                    "priority-self",
                    f"rule `{clip(p.higher)}` is declared above itself",
                    p.span,
                    hint="a priority orders two different rules",
                )
                continue
            key = (p.higher, p.lower)
            if key in first:
                sink.warning(
                    "duplicate-priority",
                    f"`{clip(p.higher)} > {clip(p.lower)}` is declared twice",
                    p.span,
                    related=(("first declared here", spec.priorities[first[key]].span),),
                )
                continue
            first[key] = i
        for names in _cycles(_successors(first)):
            _report_cycle(names, first, spec.priorities, sink)


def _named(
    name: str,
    span: A.Span,
    known: set[str],
    kind: Callable[[str], str | None],
    suggest: _Suggestions,
    sink: DiagnosticSink,
) -> bool:
    """Is ``name`` a rule? If not, say so at ``span``."""
    if name in known:
        return True
    what = kind(name)
    if what is not None:
        sink.error(
            "not-a-rule",
            f"`{clip(name)}` in a priority is {'an' if what[0] in 'aeiou' else 'a'} {what}, not a rule",
            span,
            hint="a priority orders rules, by their names",
        )
    else:
        sink.error(
            "undeclared-rule",
            f"`{clip(name)}` in a priority is not a rule",
            span,
            hint=suggest(name, "undeclared-rule"),
        )
    return False


def _report_cycle(
    names: list[str], first: Mapping[Pair, int], decls: Sequence[A.Priority], sink: DiagnosticSink
) -> None:
    """One ``priority-cycle`` error at the cycle's last-declared pair, pointing to the others."""
    steps = sorted(first[(h, lo)] for h, lo in pairwise(names))
    closing = decls[steps[-1]]
    text = clip(" > ".join(names), 4 * QUOTE_LIMIT)
    sink.error(
        "priority-cycle",
        f"priorities form a cycle: {text}",
        closing.span,
        related=tuple(
            (f"`{clip(decls[i].higher)} > {clip(decls[i].lower)}` declared here", decls[i].span)
            for i in steps[:-1][:_RELATED_LIMIT]
        ),
        hint="no rule can be above itself, even through others: drop or reverse one of these pairs",
    )


def _where(span: A.Span, p: A.Priority) -> A.Span:
    """A name's own span, or the pair's when the name has none (a Priority built in Python)."""
    return span if span.line else p.span


class _Suggestions:
    """A "did you mean" among the rule names, computed only for a diagnostic that will be shown,
    and once per name (as the checker's own ``_did_you_mean``)."""

    def __init__(self, rules: list[str], sink: DiagnosticSink) -> None:
        self.rules = rules
        self.sink = sink
        self.memo: dict[str, str | None] = {}

    def __call__(self, name: str, code: str) -> str | None:
        if not self.sink.shown(code):
            return None
        if name not in self.memo:
            close = difflib.get_close_matches(name, self.rules, n=1, cutoff=0.75)
            self.memo[name] = f"did you mean `{clip(close[0])}`?" if close else None
        return self.memo[name]


# ---------------------------------------------------------------------------- graphs


def _successors(pairs: Iterable[Pair]) -> dict[str, list[str]]:
    """Each name -> the names directly below it, without repeats; every name is a key, in the
    order of first mention (so that results do not depend on hashing)."""
    succ: dict[str, list[str]] = {}
    seen: set[Pair] = set()
    for h, lo in pairs:
        succ.setdefault(h, [])
        succ.setdefault(lo, [])
        if (h, lo) not in seen:
            seen.add((h, lo))
            succ[h].append(lo)
    return succ


def _cycles(succ: Mapping[str, list[str]]) -> list[list[str]]:
    """One cycle per strongly connected group of names that has one, in order of the groups'
    first-mentioned names: the shortest cycle through that name."""
    order = {name: i for i, name in enumerate(succ)}
    out = []
    for group in _components(succ):
        start = min(group, key=order.__getitem__)
        if len(group) > 1 or start in succ[start]:
            out.append((order[start], _cycle_through(start, succ, set(group))))
    return [names for _, names in sorted(out)]


def _cycle_through(start: str, succ: Mapping[str, list[str]], members: set[str]) -> list[str]:
    """The shortest cycle from ``start`` back to it within ``members`` (breadth first)."""
    prev: dict[str, str] = {}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for nxt in succ[node]:
            if nxt == start:
                path = [node]
                while path[-1] != start:
                    path.append(prev[path[-1]])
                return [*reversed(path), start]
            if nxt in members and nxt not in prev:
                prev[nxt] = node
                queue.append(nxt)
    raise AssertionError(f"no cycle through {start!r} in its component")  # pragma: no cover


def _components(succ: Mapping[str, list[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components, without recursion (a chain of thousands of
    rules must not overflow the stack)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    for root in succ:
        if root in index:
            continue
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        work = [(root, 0)]
        while work:
            node, i = work[-1]
            below = succ[node]
            if i < len(below):
                work[-1] = (node, i + 1)
                nxt = below[i]
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, 0))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == node:
                        break
                out.append(group)
    return out

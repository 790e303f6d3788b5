"""Unless clauses that no situation selects, under the chosen semantics (``unreachable-hedge``,
``duplicate-hedge``): the checker's question to :mod:`cosleec.lang.hedges` about each response.

What is known statically -- conditions that are the literal ``true`` or ``false``, and
conditions that imply another (equal, or a conjunct of it) -- is handed to
:func:`hedges.reachable`, which asks :func:`hedges.choose` about every situation consistent
with it; a clause it never chooses gets a warning naming the cause.

May import: the lang modules ast, diagnostics and hedges.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from cosleec.lang import ast as A
from cosleec.lang import hedges
from cosleec.lang.diagnostics import DiagnosticSink

MAX_LINT_CLAUSES = 12
"""The unreachable-clause lint asks :mod:`cosleec.lang.hedges` about a rule's clauses only
when the rule has at most this many (the real corpus has at most 6). The question costs far
more than n**2 per rule: :func:`hedges.reachable` tries every pair of clauses, and
:func:`hedges.blockers` asks it again once per other clause for each dead clause, so a
generated rule of 20,000 ``unless false`` clauses ran out of memory, and even a 16-clause
rule of unknown conditions and ``true`` took seconds (12 clauses: at most about one). A
longer rule gets only what holds under every semantics, at one look per clause: a clause
whose condition is the literal ``false`` never applies."""


def check_clauses(
    sink: DiagnosticSink, semantics: hedges.HedgeSemantics, resp: A.Response, *, declared: bool = False
) -> None:
    """Warn about ``resp``'s hedge clauses that no situation selects under ``semantics``
    (``declared``: the file's semantics block chose it; otherwise the hint says how to).

    That is asked of :func:`hedges.reachable` only for a rule of at most
    :data:`MAX_LINT_CLAUSES` clauses, and it gives an answer only when few enough conditions
    are unknown (``hedges.MAX_FREE_CONDITIONS``). Otherwise only clauses whose condition is
    the literal ``false`` are reported: no semantics chooses a clause whose condition does
    not hold (hedges' module docstring).
    """
    ds = resp.defeaters
    if not ds:
        return
    conds = [d.condition for d in ds]
    fixed = {i + 1: c.value for i, c in enumerate(conds) if isinstance(c, A.BoolLit)}
    implies = _implication(conds) if len(ds) <= MAX_LINT_CLAUSES else None
    chosen = None
    if implies is not None:
        chosen = hedges.reachable(len(ds), semantics, fixed=fixed, implies=implies)
    if chosen is None or implies is None:
        for i, value in fixed.items():
            if not value:
                _never(sink, ds, i)
        return
    hint = _hint(semantics, declared)
    for i in range(1, len(ds) + 1):
        if i not in chosen:
            _unreachable(sink, semantics, ds, i, fixed, implies, hint)


def _hint(semantics: hedges.HedgeSemantics, declared: bool) -> str:
    """How to make a clause reachable: reorder, or -- the file declaring no semantics -- say
    that the rules are written for the other one."""
    order = (
        "reorder the unless clauses (the last that holds wins)"
        if semantics == hedges.HedgeSemantics.LAST_WINS
        else "reorder the unless clauses (each needs the ones before it)"
    )
    if declared:
        return order
    other = next(h for h in hedges.HedgeSemantics if h != semantics)
    return (
        f"{order}; or, if the rules are written for {other} semantics, declare it in the file: "
        f"`semantics_start unless {other} semantics_end` (check, analyse and the runtime read it)"
    )


def _never(sink: DiagnosticSink, ds: tuple[A.Defeater, ...], i: int) -> None:
    """Report clause ``i``, whose condition is the literal ``false``."""
    sink.warning("unreachable-hedge", f"clause {i}: condition is `false`, it never applies", ds[i - 1].span)


def _unreachable(
    sink: DiagnosticSink,
    semantics: hedges.HedgeSemantics,
    ds: tuple[A.Defeater, ...],
    i: int,
    fixed: dict[int, bool],
    implies: Callable[[int, int], bool],
    hint: str,
) -> None:
    """Report clause ``i`` as never chosen, naming the clause that blocks it (found by
    :func:`hedges.blockers`, so that no semantics is restated here)."""
    span = ds[i - 1].span
    if fixed.get(i) is False:
        _never(sink, ds, i)
        return
    culprits = hedges.blockers(i, len(ds), semantics, fixed=fixed, implies=implies)
    if not culprits:
        sink.warning(
            "unreachable-hedge", f"clause {i} never applies under {semantics} semantics", span, hint=hint
        )
        return
    j = culprits[0]
    related = (("the clause that blocks it", ds[j - 1].span),)
    if ds[j - 1].condition == ds[i - 1].condition:
        sink.warning(
            "duplicate-hedge",
            f"clause {i} has the same condition as clause {j}; under {semantics} semantics "
            f"clause {i} never applies",
            span,
            related=related,
            hint=hint,
        )
        return
    if fixed.get(j) is not None:
        why = f"clause {j}'s condition is `{'true' if fixed[j] else 'false'}`"
    elif implies(i, j):
        why = f"whenever clause {i} holds, clause {j} holds too"
    else:
        why = f"what is known of clause {j}'s condition rules it out"
    sink.warning(
        "unreachable-hedge",
        f"clause {i} never applies under {semantics} semantics: {why}",
        span,
        related=related,
        hint=hint,
    )


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


__all__ = ["MAX_LINT_CLAUSES", "check_clauses"]

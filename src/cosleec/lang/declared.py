"""The clause semantics a file declares it is written for: its semantics block.

SLEEC chooses a rule's ``unless`` clause by last-wins; the CO-SLEEC paper nests them
(:class:`~cosleec.lang.hedges.HedgeSemantics`). A rule file may say which it is written for,
in a block of its own (a cosleec extension, docs/reference/sleec-language.md §7.4)::

    semantics_start
      unless nested
    semantics_end

:func:`check_semantics` is the checker's pass over that block; :func:`clause_semantics_for`
is the one rule every reader of the rules applies -- ``cosleec check``, ``analyse``, the
runtime: the semantics asked for, else the file's, else last-wins, and a request that
contradicts the file is an error naming both and the fix.

May import: errors, and the lang modules ast, diagnostics and hedges.
"""

from __future__ import annotations

from cosleec.errors import ConfigurationError, closest
from cosleec.lang import ast as A
from cosleec.lang.diagnostics import DiagnosticSink
from cosleec.lang.hedges import HedgeSemantics

_VALUES = tuple(str(h) for h in HedgeSemantics)


def check_semantics(spec: A.Specification, sink: DiagnosticSink, *, strict: bool = False) -> None:
    """Check ``spec``'s semantics block: under ``strict`` (``--strict``) the block at all
    (``extension-semantics``); an unknown value (``unknown-semantics``, with a did-you-mean);
    the semantics declared twice (``duplicate-semantics``). An empty block is a warning
    (``empty-semantics``). A second block is the parser's ``duplicate-block``."""
    mark = next((b for b in spec.blocks if b.kind == "semantics"), None)
    if mark is None and not spec.semantics:
        return
    where = mark.span if mark is not None else spec.semantics[0].span
    if strict:
        sink.error(
            "extension-semantics",
            "a semantics block (`semantics_start`) is a cosleec extension, rejected by --strict",
            where,
            hint="leave out --strict, or remove the block and give the semantics as an option "
            "(`--semantics nested`)",
        )
    if not spec.semantics:
        sink.warning(
            "empty-semantics",
            "the semantics block declares nothing",
            where,
            hint="write `unless last-wins` or `unless nested` in it, or remove it",
        )
    first: A.SemanticsDecl | None = None
    for d in spec.semantics:
        if d.value not in _VALUES:
            near = closest(d.value, _VALUES)
            sink.error(
                "unknown-semantics",
                f"`{d.value}` is not a clause semantics; the choices are `last-wins` (SLEEC's) "
                "and `nested` (the CO-SLEEC paper's)",
                d.value_span,
                hint=f"did you mean `{near}`?" if near else "write `unless last-wins` or `unless nested`",
            )
        if first is None:
            first = d
        else:
            sink.error(
                "duplicate-semantics",
                f"the clause semantics is declared twice (`unless {first.value}`, then `unless {d.value}`)",
                d.span,
                related=(("the first declaration is here", first.span),),
                hint="keep one `unless` line",
            )


def clause_semantics_for(
    spec: A.Specification, given: HedgeSemantics | str | None = None, *, option: str = "semantics"
) -> HedgeSemantics:
    """The clause semantics to read ``spec`` with: ``given`` (an option the user set), else
    the file's declaration (:attr:`~cosleec.lang.ast.Specification.clause_semantics`), else
    last-wins, SLEEC's.

    Raises :class:`~cosleec.errors.ConfigurationError` when ``given`` is no semantics, or
    contradicts the file's declaration: the rules were written for one reading and would be
    judged by another. ``option`` names the setting in the message as the caller's user
    knows it (``--semantics``, ``semantics=``).
    """
    declared = spec.clause_semantics
    if given is None:
        return declared or HedgeSemantics.LAST_WINS
    if str(given) not in _VALUES:
        near = closest(given, _VALUES)
        raise ConfigurationError(
            f"{option} must be one of 'last-wins', 'nested', not {str(given)!r}",
            hint=f"did you mean {near!r}?"
            if near
            else "give 'last-wins' (SLEEC's) or 'nested' (the paper's)",
        )
    asked = HedgeSemantics(str(given))
    if declared is not None and declared != asked:
        mark = next((d.span for d in spec.semantics if d.value == str(declared)), A.NO_SPAN)
        where = f"{spec.path}:{mark.line}:{mark.col}" if mark.line else spec.path
        raise ConfigurationError(
            f"{option} {asked} contradicts the rule file, which declares `unless {declared}` in its "
            "semantics block",
            hint=f"leave out {option} (the file's `{declared}` is used), or change the file's "
            f"semantics block to `unless {asked}`",
            where=where,
        )
    return asked


__all__ = ["check_semantics", "clause_semantics_for"]

"""After a syntax error, the checks of every rule that did parse.

The parser already reports every syntax error of a file (lalr.py's panic-mode recovery), but
the tree it builds around skipped tokens is no faithful reading of the file, so no
specification comes out of it and, before this module, no check ran: a file with one
misplaced ``:`` hid its misspelt events. :func:`salvage` reads the file again with each rule
that holds a syntax error blanked out (spaces for its characters, its line breaks kept, so
that every span stays where it was): when that text parses, the checker's findings about
the rules left are findings about the file. :func:`keep` then drops what the blanking itself
caused -- an empty rule block, a priority naming a blanked rule.

The parser stays quiet for three tokens after an error (one mistake, one message), so an
error that close to another one is heard only here: when the blanked text still has syntax
errors, they are errors of other rules (``R3:`` just after ``not X for 10 minutes``), are
reported too (:attr:`Salvage.errors`), and their rules are blanked in turn, until what is
left parses (or :data:`ROUNDS` rounds have passed).

A rule runs from a name at the start of a line followed by ``when`` (or ``:``, a mistake
mistakes.py names) to the next such name or ``rule_end``, inside the rule block. An error
outside the rule block (in the def block, say) means no salvage: a missing declaration would
make every rule that uses it an error too. Only files with a syntax error come here, so a
file that parses costs nothing more.

May import: the lang modules ast, diagnostics, lexer, parser and transformer.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass

from cosleec.lang.diagnostics import Diagnostic, DiagnosticSink
from cosleec.lang.lexer import Token
from cosleec.lang.parser import SLEEC, parse_blocks
from cosleec.lang.transformer import Block

#: how many times the rules of newly heard errors are blanked before giving up
ROUNDS = 20


@dataclass(frozen=True)
class Salvage:
    """The blocks of a file with its broken rules blanked out, those rules' names, and the
    syntax errors heard only once the others' rules were blanked (``path`` is the caller's)."""

    blocks: list[Block] | None
    dropped: frozenset[str]
    errors: tuple[Diagnostic, ...] = ()


def salvage(text: str, errors: Sequence[Diagnostic]) -> Salvage | None:
    """The blocks of ``text`` without the rules that hold one of the syntax ``errors`` (and
    those of the errors heard once these are blanked; ``blocks`` None when what is left still
    does not parse); None when an error lies outside the rule block."""
    tokens = SLEEC.lexicon.tokens(text)
    starts, stop = _rule_starts(tokens)
    if not starts:
        return None
    line_at = [0] + [i + 1 for i, ch in enumerate(text) if ch == "\n"]
    cut: set[int] = set()
    heard: list[Diagnostic] = []
    pending = list(errors)
    for _ in range(ROUNDS):
        for d in pending:
            if d.span.line < 1 or d.span.line > len(line_at):
                return None if not heard else Salvage(None, frozenset(), tuple(heard))
            at = line_at[d.span.line - 1] + d.span.col - 1
            k = bisect.bisect_right(starts, at, key=lambda i: tokens[i].start_pos) - 1
            if k < 0 or at > stop:  # before the first rule or after the rule block: not a rule's
                return None if not heard else Salvage(None, frozenset(), tuple(heard))
            cut.add(k)
        sink = DiagnosticSink("<salvage>")
        blocks = parse_blocks(_blanked(text, tokens, starts, stop, cut), sink)
        names = frozenset(tokens[starts[k]].value.lstrip("^") for k in cut)
        if blocks is not None:
            return Salvage(blocks, names, tuple(heard))
        # at the end of the file: the first parse got there too and said what was missing
        pending = [d for d in sink.items if d.is_error and "end of file" not in d.message]
        if not pending:
            break
        heard += pending
    return Salvage(None, frozenset(), tuple(heard))


def _blanked(text: str, tokens: list[Token], starts: list[int], stop: int, cut: set[int]) -> str:
    """``text`` with the rules ``cut`` (indices into ``starts``) blanked: spaces, line breaks kept."""
    chars = list(text)
    for k in cut:
        end = tokens[starts[k + 1]].start_pos if k + 1 < len(starts) else stop
        for i in range(tokens[starts[k]].start_pos, end):
            if chars[i] != "\n":
                chars[i] = " "
    return "".join(chars)


def keep(d: Diagnostic, dropped: frozenset[str]) -> bool:
    """Whether ``d``, found in a salvaged file, is about the file and not about the blanking."""
    if d.code == "empty-rule-block":
        return False
    if d.code == "undeclared-rule":
        return not any(f"`{name}`" in d.message for name in dropped)
    return True


def _rule_starts(tokens: list[Token]) -> tuple[list[int], int]:
    """The indices of the tokens that start a rule, and the offset where the rule block ends
    (its ``rule_end``, else the end of the text)."""
    first = next((i for i, t in enumerate(tokens) if t.type == "RULE_START"), None)
    if first is None:
        return [], 0
    starts: list[int] = []
    stop = tokens[-1].start_pos + len(tokens[-1].value)
    for i in range(first + 1, len(tokens)):
        t = tokens[i]
        if t.type == "RULE_END":
            stop = t.start_pos
            break
        if (
            t.type == "NAME"
            and tokens[i - 1].line != t.line
            and i + 1 < len(tokens)
            and tokens[i + 1].value in ("when", ":")
        ):
            starts.append(i)
    return starts, stop


__all__ = ["Salvage", "keep", "salvage"]

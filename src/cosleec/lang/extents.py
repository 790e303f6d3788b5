"""Where each rule's text is: from its name to its last token, comments around it left out.

A rule's span is its name's (the parser keeps token spans, not extents). A tool that rewrites
one rule in place (``cosleec analyse --fix``) needs the whole stretch: it runs from the name
to the last token before the next rule's name, or before the ``rule_end`` word; a comment
after it -- on its last line or on lines of its own -- is not part of it.
"""

from __future__ import annotations

from cosleec.lang import ast as A
from cosleec.lang.parser import PAPER, SLEEC


def rule_extents(source: str, spec: A.Specification) -> dict[str, tuple[int, int]]:
    """Each rule of ``spec`` (parsed from ``source``) by name: the offsets ``(start, end)``
    of its text, end exclusive."""
    grammar = PAPER if spec.dialect is A.Dialect.PAPER else SLEEC
    tokens = grammar.lexicon.tokens(source)
    at = {(t.line, t.column): i for i, t in enumerate(tokens)}
    starts = [(r.name, at.get((r.span.line, r.span.col))) for r in spec.rules]
    firsts = sorted(i for _, i in starts if i is not None)
    out: dict[str, tuple[int, int]] = {}
    for name, i in starts:
        if i is None:
            continue
        nxt = next((j for j in firsts if j > i), len(tokens))
        end = i
        for j in range(i + 1, nxt):
            if tokens[j].value.lower() in _AFTER:
                break
            end = j
        last = tokens[end]
        out[name] = (tokens[i].start_pos, last.start_pos + len(last.value))
    return out


_AFTER = frozenset({"rule_end", "concern_start", "purpose_start", "relation_start", "priority_start"})
"""Words that end the rule block (the paper notation has no block words)."""


__all__ = ["rule_extents"]

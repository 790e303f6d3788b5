"""Edits of a rule file, written as its author would: a changed rule in the file's own
notation (LEGOS-SLEEC's ``{m}`` braces, SLEEC-TK's plain names), at the rule's place and
indentation, everything around it untouched.

Each function returns the :class:`~cosleec.repair.patch.Edit` that makes one change to the
text the :class:`Writer` was given; the operators (operators.py) combine them into patches.
"""

from __future__ import annotations

import re

from cosleec.lang import WIDTH, Printer, rule_extents
from cosleec.lang import ast as A
from cosleec.repair.patch import Edit, Text


class Writer:
    """Writes edits of one checked file: ``source`` is its text, ``spec`` what it parsed to."""

    def __init__(self, source: str, spec: A.Specification) -> None:
        self.text = Text(source)
        self.spec = spec
        self.extents = rule_extents(source, spec)
        self.printer = Printer(spec, spec.dialect)

    def rule_text(self, rule: A.Rule, indent: str) -> str:
        """``rule`` as the file would write it: one line, or one clause a line when long."""
        clauses = self.printer.rule_clauses(rule)
        line = " ".join(clauses)
        if len(indent.expandtabs(4)) + len(line) <= WIDTH:
            return line
        return f"\n{indent}    ".join(clauses)

    def expr(self, e: A.Expr) -> str:
        """A condition as the file's notation writes it."""
        return self.printer.expr(e)

    def replace_rule(self, old: A.Rule, new: A.Rule) -> Edit:
        """Rewrite rule ``old`` as ``new``, where it stands."""
        start, end = self.extents[old.name]
        return Edit(start, end, self.rule_text(new, self.text.indent(old.span.line)))

    def remove_rule(self, rule: A.Rule) -> Edit:
        """Delete ``rule`` (its lines, when it has them to itself)."""
        start, end = self.text.whole_lines(*self.extents[rule.name])
        return Edit(start, end, "")

    def add_rule(self, rule: A.Rule) -> Edit:
        """Insert ``rule`` on a line of its own after the last rule of the rule block."""
        last = self.spec.rules[-1]
        at = self.extents[last.name][1]
        indent = self.text.indent(last.span.line)
        return Edit(at, at, f"\n{indent}{self.rule_text(rule, indent)}")

    def add_priority(self, higher: str, lower: str) -> Edit:
        """Declare ``higher > lower`` (see :meth:`add_priorities`)."""
        return self.add_priorities([(higher, lower)])

    def add_priorities(self, pairs: list[tuple[str, str]]) -> Edit:
        """Declare each ``higher > lower`` of ``pairs``: lines in the priority block, or a new
        block at the end of the file (the block comes last in every dialect that has it)."""
        lines = [f"{self.printer.name(h)} > {self.printer.name(low)}" for h, low in pairs]
        if self.spec.priorities:
            last = self.spec.priorities[-1].span
            at = self.text.line_end(last.end_line)
            indent = self.text.indent(last.line)
            return Edit(at, at, "".join(f"\n{indent}{line}" for line in lines))
        source = self.text.source
        at = len(source)
        lead = "" if source.endswith("\n") else "\n"
        body = "".join(f"    {line}\n" for line in lines)
        return Edit(at, at, f"{lead}\npriority_start\n{body}priority_end\n")

    def fresh_name(self, base: str, taken: set[str] | None = None) -> str:
        """A rule name not used in the file (nor in ``taken``): ``base``, else ``base_2``..."""
        used = {r.name for r in self.spec.rules} | {d.name for d in self.spec.definitions}
        used |= taken or set()
        if base not in used:
            return base
        n = 2
        while f"{base}_{n}" in used:
            n += 1
        return f"{base}_{n}"


def joined(edits: tuple[Edit, ...]) -> tuple[Edit, ...]:
    """``edits`` with the new priority blocks that two patches insert at the end of a file
    made one block (a file has at most one): what applying the patches together writes."""
    blocks = [e for e in edits if e.start == e.end and _BLOCK.fullmatch(e.text)]
    if len(blocks) < 2:
        return edits
    rest = tuple(e for e in edits if e not in blocks)
    lines = "".join(m.group(2) for e in blocks if (m := _BLOCK.fullmatch(e.text)) is not None)
    first = _BLOCK.fullmatch(blocks[0].text)
    lead = first.group(1) if first is not None else "\n"
    return (*rest, Edit(blocks[0].start, blocks[0].end, f"{lead}priority_start\n{lines}priority_end\n"))


_BLOCK = re.compile(r"(\n?\n)priority_start\n((?:    .*\n)+)priority_end\n")
"""A priority block :meth:`Writer.add_priorities` inserts: its lead, then its lines."""


__all__ = ["Writer", "joined"]

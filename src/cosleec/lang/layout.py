"""Where a file's comments and blank lines go when it is printed again (``cosleec fmt``).

The parser drops comments and line breaks; the printer rebuilds text from the AST. A
formatter people adopt must keep both, so this module reads them from the source and
attaches each to an *anchor* the printer prints: an item of a block (a declaration, a
rule, a relation, a priority pair, ...) or a block's start or end word.

The rules, chosen so that formatting twice changes nothing (``fmt(fmt(x)) == fmt(x)``):

- A comment after code on its line *trails* that code and is printed at the end of the
  line that prints it; in a rule printed one clause per line, at the end of its clause's line.
- A comment on a line of its own *leads* the item whose first token follows it. Between two
  tokens of one rule, it leads the ``unless`` clause it sits in (printed on its own line
  before that clause); anywhere else inside an item, it leads the item.
- Comments after the last token close the file.
- One or more blank lines before an item or an own-line comment are kept, as one.

Items are found by their spans, which start at the item's name (``event A`` starts at
``A``): a keyword written before the name on the same line belongs to the item too.

May import: the lexer and the AST.
"""

from __future__ import annotations

import bisect
from collections.abc import Iterator
from dataclasses import dataclass, field

from cosleec.lang import ast as A
from cosleec.lang.lexer import Lexicon

Key = tuple[str, int | str]
"""An anchor: ``("rule", 3)`` (an item of a block, by kind and index in the AST), or
``("start", "rule")`` / ``("end", "rule")`` (a block's start and end words)."""

ITEM_KINDS = ("def", "rule", "concern", "purpose", "relation", "priority", "semantics")
_PREFIXES = frozenset({"EVENT", "MEASURE", "CONSTANT", "FLUENT", "WHEN"})  # keywords before a name


def items(spec: A.Specification) -> Iterator[tuple[Key, object]]:
    """Every item of ``spec`` with its key, in the order the printer prints them."""
    groups: tuple[tuple[object, ...], ...] = (
        spec.definitions,
        spec.rules,
        spec.concerns,
        spec.purposes,
        spec.relations,
        spec.priorities,
        spec.semantics,
    )
    for kind, group in zip(ITEM_KINDS, groups, strict=True):
        for i, node in enumerate(group):
            yield (kind, i), node


@dataclass(frozen=True)
class Comment:
    """One comment as written (line comments without trailing spaces), where it was, and
    whether a blank line came before it (own-line comments only)."""

    text: str
    offset: int
    blank_before: bool = False


@dataclass
class Layout:
    """The comments and blank lines of one source, by anchor (see the module docstring).

    Build one with :meth:`read`; an empty one (no source) prints the canonical form.
    """

    leading: dict[Key, list[Comment]] = field(default_factory=dict)
    trailing: dict[tuple[Key, int], list[Comment]] = field(default_factory=dict)
    inner: dict[tuple[Key, int], list[Comment]] = field(default_factory=dict)
    blank: set[Key] = field(default_factory=set)
    closing: list[Comment] = field(default_factory=list)

    def comments_outside(self, keys: set[Key]) -> list[Comment]:
        """Every comment attached to an anchor not in ``keys``, in source order: the comments
        of what a notation does not print (the paper notation has no def block)."""
        found = [c for k, cs in self.leading.items() if k not in keys for c in cs]
        for table in (self.trailing, self.inner):
            found += [c for (k, _), cs in table.items() if k not in keys for c in cs]
        return sorted(found, key=lambda c: c.offset)

    def has_comments(self, key: Key) -> bool:
        """Whether any comment leads or trails ``key``."""
        return key in self.leading or any(k == key for (k, _) in self.trailing)

    def trailing_clauses(self, key: Key) -> set[int]:
        """The clauses of ``key`` that have a trailing comment."""
        return {clause for (k, clause) in self.trailing if k == key}

    def has_inner(self, key: Key) -> bool:
        """Whether a comment sits on its own line inside the item, before a later clause."""
        return any(k == key for (k, _) in self.inner)

    @classmethod
    def read(cls, source: str, spec: A.Specification, lexicon: Lexicon) -> Layout:
        """Attach the comments and blank lines of ``source`` (the text ``spec`` was parsed
        from, by the grammar of ``lexicon``) to the anchors of ``spec``."""
        return _Reader(source, spec, lexicon).layout()


class _Reader:
    def __init__(self, source: str, spec: A.Specification, lexicon: Lexicon) -> None:
        self.source = source
        self.line_starts = [0] + [i + 1 for i, ch in enumerate(source) if ch == "\n"]
        self.tokens = lexicon.tokens(source)
        self.token_offsets = [t.start_pos for t in self.tokens]
        self.raw_comments = lexicon.comments(source)
        anchors: list[tuple[int, int, Key]] = []
        written = {b.kind for b in spec.blocks} | {"rule"}  # inferred declarations were not
        for order, (key, node) in enumerate(items(spec)):
            if key[0] not in written:
                continue
            span: A.Span = node.span  # type: ignore[attr-defined]
            if isinstance(node, A.Priority) and node.lower_span.line:
                span = node.lower_span  # in a chain `A > B > C`, B ends one pair and starts the next
            at = self.offset(span.line, span.col)
            if isinstance(node, A.Rule) and spec.dialect is A.Dialect.PAPER:
                k = bisect.bisect_left(self.token_offsets, at)
                if k > 0 and self.tokens[k - 1].type == "WHEN":
                    at = self.tokens[k - 1].start_pos  # an unnamed paper rule starts at its WHEN
            anchors.append((at, order, key))
        kinds = {b.kind for b in spec.blocks}
        for t in self.tokens:
            word = t.value.lower()
            for end in ("start", "end"):
                kind = word.removesuffix(f"_{end}")
                if word.endswith(f"_{end}") and kind in kinds and t.type == word.upper():
                    anchors.append((t.start_pos, -1, (end, kind)))
        anchors.sort()
        self.anchors = anchors
        self.anchor_offsets = [a[0] for a in anchors]
        self.anchor_at = {a[0]: a[2] for a in reversed(anchors)}
        self.clauses: dict[Key, list[int]] = {}
        for key, node in items(spec):
            if isinstance(node, A.Rule):
                self.clauses[key] = [self.offset(d.span.line, d.span.col) for d in node.response.defeaters]
        self.ink = self._ink_lines()
        self.first_ink = self.ink.index(True) if True in self.ink else len(self.ink)
        self.first_on_line: dict[int, int] = {}  # line -> offset of its first token or comment
        for offset in sorted([*self.token_offsets, *(o for o, _ in self.raw_comments)]):
            self.first_on_line.setdefault(self.line(offset), offset)

    # ------------------------------------------------------------------ positions
    def offset(self, line: int, col: int) -> int:
        return self.line_starts[line - 1] + col - 1

    def line(self, offset: int) -> int:
        return bisect.bisect_right(self.line_starts, offset)

    def _ink_lines(self) -> list[bool]:
        """Per line (1-based), whether a token or a comment is on it."""
        ink = [False] * (len(self.line_starts) + 2)
        for t in self.tokens:
            ink[t.line] = True
        for offset, text in self.raw_comments:
            first = self.line(offset)
            for line in range(first, first + text.count("\n") + 1):
                ink[line] = True
        return ink

    def blank_before(self, line: int) -> bool:
        """Whether a blank line separates ``line`` from ink above it."""
        return not self.ink[line - 1] and self.first_ink < line - 1

    # ------------------------------------------------------------------ ownership
    def owner_of_next(self, offset: int) -> Key:
        """The anchor a token at ``offset`` belongs to, when a comment precedes it: an
        anchor starting later on the same line (the token is a keyword before its name),
        else the last anchor at or before it."""
        i = bisect.bisect_left(self.anchor_offsets, offset)
        if i < len(self.anchors) and self.line(self.anchors[i][0]) == self.line(offset):
            return self.anchors[i][2]
        return self.anchors[max(i - 1, 0)][2]

    def owner_of_prev(self, k: int) -> Key:
        """The anchor the ``k``-th token belongs to, when a comment follows it: the last anchor
        at or before it -- or, for the keyword that starts a declaration (``event /* c */ A``),
        the anchor it starts."""
        t = self.tokens[k]
        if t.type in _PREFIXES and k + 1 < len(self.tokens):
            after = self.tokens[k + 1]
            if after.line == t.line and after.start_pos in self.anchor_at:
                return self.anchor_at[after.start_pos]
        i = bisect.bisect_right(self.anchor_offsets, t.start_pos)
        return self.anchors[max(i - 1, 0)][2]

    def clause(self, key: Key, offset: int) -> int:
        """The clause of rule ``key`` that ``offset`` is in: 0 the head, k the k-th ``unless``."""
        return bisect.bisect_right(self.clauses.get(key, []), offset)

    # ------------------------------------------------------------------ attachment
    def layout(self) -> Layout:
        out = Layout()
        if not self.anchors:
            out.closing = [self.comment(o, t, own_line=True) for o, t in self.raw_comments]
            return out
        for offset, text in self.raw_comments:
            i = bisect.bisect_left(self.token_offsets, offset)
            prev = self.tokens[i - 1] if i > 0 else None
            nxt = self.tokens[i] if i < len(self.tokens) else None
            line = self.line(offset)
            if prev is not None and prev.line == line:
                key = self.owner_of_prev(i - 1)
                at = (key, self.clause(key, prev.start_pos))
                out.trailing.setdefault(at, []).append(self.comment(offset, text, own_line=False))
                continue
            comment = self.comment(offset, text, own_line=True)
            if nxt is None:
                out.closing.append(comment)
                continue
            key = self.owner_of_next(nxt.start_pos)
            inside = prev is not None and self.owner_of_prev(i - 1) == key
            clause = self.clause(key, nxt.start_pos) if inside else 0
            if clause:
                out.inner.setdefault((key, clause), []).append(comment)
            else:
                out.leading.setdefault(key, []).append(comment)
        for t in self.tokens:
            if t.start_pos != self.first_on_line[t.line] or not self.blank_before(t.line):
                continue
            i = bisect.bisect_left(self.anchor_offsets, t.start_pos)
            if i < len(self.anchors) and self.line(self.anchors[i][0]) == t.line:
                out.blank.add(self.anchors[i][2])  # a blank line inside an item is not kept
        return out

    def comment(self, offset: int, text: str, own_line: bool) -> Comment:
        text = text.replace("\r\n", "\n")  # the printer writes "\n"; fmt restores CRLF files
        if text.startswith("//"):
            text = text.rstrip()
        line = self.line(offset)
        blank = own_line and self.first_on_line[line] == offset and self.blank_before(line)
        return Comment(text, offset, blank)

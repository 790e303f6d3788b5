"""What the language server answers, as plain functions of a :class:`Document` and a place:
diagnostics, hover, definition, references, completion, the outline, rename, formatting,
and the on-save repairs as code actions.

Each returns ``lsprotocol`` values and knows nothing of the connection (server.py wires
them); a request the file cannot answer (rename to a keyword, formatting a file with
errors) raises :class:`Refusal`, which the server sends back as the request's error.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

from lsprotocol import types as T

from cosleec.errors import UserError
from cosleec.lang import (
    CONTEXTUAL_KEYWORDS,
    KEYWORDS,
    PAPER_KEYWORDS,
    Diagnostic,
    Severity,
    SleecError,
    format_source,
)
from cosleec.lang import ast as A
from cosleec.lsp.document import Document
from cosleec.lsp.fixes import Offer, text_edits
from cosleec.lsp.index import Extent, Index, Kind, Role, Use

SOURCE = "cosleec"
ANALYSE_SOURCE = "cosleec analyse"
FIX_ALL = "source.cosleec.fixAll"
"""The kind of the "fix all" action: a source action of its own, not ``source.fixAll``, so
that an editor set to run every ``source.fixAll`` on save never removes or rewrites rules
unasked."""
LIST_LIMIT = 12
"""How many rules a hover lists for one role before it says how many more."""


class Refusal(UserError):
    """A request the document cannot answer as asked (the server replies with its message)."""


# ---------------------------------------------------------------- diagnostics

_SEVERITY = {
    Severity.ERROR: T.DiagnosticSeverity.Error,
    Severity.WARNING: T.DiagnosticSeverity.Warning,
    Severity.NOTE: T.DiagnosticSeverity.Information,
}


def to_lsp(d: Diagnostic, doc: Document, source: str = SOURCE) -> T.Diagnostic:
    """A cosleec diagnostic as the editor shows it: the same code, place, message and hint."""
    lines = doc.lines
    message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
    related = [
        T.DiagnosticRelatedInformation(
            location=T.Location(uri=doc.uri, range=lines.span_range(span)), message=note
        )
        for note, span in d.related
    ]
    return T.Diagnostic(
        range=lines.span_range(d.span),
        message=message,
        severity=_SEVERITY[d.severity],
        code=d.code,
        source=source,
        related_information=related or None,
    )


def diagnostics(doc: Document) -> list[T.Diagnostic]:
    """``cosleec check``'s diagnostics of the current text, and the last on-save analysis's
    findings while the text is the one analysed."""
    out = [to_lsp(d, doc) for d in doc.result().diagnostics]
    if doc.findings_text == doc.text:
        out += [to_lsp(d, doc, ANALYSE_SOURCE) for d in doc.findings]
    return out


# ---------------------------------------------------------------- code actions


def code_actions(doc: Document, params: T.CodeActionParams) -> list[T.CodeAction]:
    """The verified fixes of the findings asked about (the request's diagnostics of the
    analysis, or else the findings its range touches), best first, rank 1 preferred; and
    "fix all", the patch set that verifies applied together. Nothing once the text is not
    the one repaired: the fixes' offsets would land in the wrong places."""
    repaired = doc.repairs
    if repaired is None or repaired.text != doc.text or doc.findings_text != doc.text:
        return []
    only = params.context.only
    asked = [(d.code, d.range) for d in params.context.diagnostics if d.source == ANALYSE_SOURCE]
    out: list[T.CodeAction] = []
    if _wanted(T.CodeActionKind.QuickFix.value, only):
        for finding, offers in repaired.fixes:
            if finding not in doc.findings:
                continue
            shown = to_lsp(finding, doc, ANALYSE_SOURCE)
            if (shown.code, shown.range) in asked if asked else _touches(shown.range, params.range):
                out += [_action(doc, o, o.title, T.CodeActionKind.QuickFix, [shown]) for o in offers]
    together = repaired.together
    if together is not None and _wanted(FIX_ALL, only):
        out.append(_action(doc, together, "Fix all (verified together)", FIX_ALL, None))
    return out


def _action(
    doc: Document, offer: Offer, title: str, kind: str, diagnostics: list[T.Diagnostic] | None
) -> T.CodeAction:
    return T.CodeAction(
        title=title,
        kind=kind,
        diagnostics=diagnostics,
        is_preferred=True if offer.rank == 1 else None,
        edit=T.WorkspaceEdit(changes={doc.uri: text_edits(doc.lines, offer.edits)}),
    )


def _wanted(kind: str, only: Sequence[T.CodeActionKind | str] | None) -> bool:
    """Whether a client asking for the kinds ``only`` (None: any) wants an action of ``kind``
    (``quickfix`` is wanted by ``quickfix``, ``source.cosleec.fixAll`` by ``source`` too)."""
    names = [k.value if isinstance(k, T.CodeActionKind) else k for k in only or ()]
    return only is None or any(kind == k or kind.startswith(f"{k}.") for k in names)


def _touches(a: T.Range, b: T.Range) -> bool:
    """Whether two ranges share a position (a cursor at a range's end touches it)."""
    return (a.start.line, a.start.character) <= (b.end.line, b.end.character) and (
        b.start.line,
        b.start.character,
    ) <= (a.end.line, a.end.character)


# ---------------------------------------------------------------- hover


def hover(doc: Document, pos: T.Position) -> T.Hover | None:
    """What the name under the cursor is: its declaration, type or value, and the rules that
    read or produce it (or, on a rule's name, the rule)."""
    index = doc.index()
    use = index.at(doc.lines.to_offset(pos))
    if use is None:
        return None
    kind, name = use.key
    uses = index.uses_of(use.key)
    parts: list[str]
    if kind is Kind.RULE:
        parts = _rule_hover(index, name)
    elif kind is Kind.SCALE_VALUE:
        measure, _, value = name.rpartition(".")
        m = index.measure(measure)
        scale = m.type if m is not None and isinstance(m.type, A.ScaleType) else None
        rank = f", value {scale.literals.index(value) + 1} of {len(scale.literals)}" if scale else ""
        parts = [
            f"**scale value** `{value}` of measure `{measure}`" + (f" : `{scale}`{rank}" if scale else "")
        ]
        parts += _roles(uses, {Role.READ: "read by"})
    else:
        parts = [_declaration(index, kind, name)]
        if kind is Kind.EVENT:
            parts += _roles(
                uses,
                {Role.TRIGGERS: "triggers", Role.OBLIGED: "produced (obliged) by", Role.FORBIDDEN: "forbidden by",
                 Role.NAMED: "named by"},
            )  # fmt: skip
        else:
            parts += _roles(uses, {Role.READ: "read by", Role.NAMED: "named by"})
    decl = index.declarations.get(use.key)
    if decl is not None:
        line, _ = doc.lines.line_col(decl.start)
        parts.append(f"declared at line {line}")
    return T.Hover(
        contents=T.MarkupContent(kind=T.MarkupKind.Markdown, value="\n\n".join(parts)),
        range=doc.lines.range(use.start, use.end),
    )


def _declaration(index: Index, kind: Kind, name: str) -> str:
    spec = index.spec
    assert spec is not None  # an index with uses was built from a specification
    if kind is Kind.MEASURE:
        m = index.measure(name)
        return f"**measure** `{name}` : `{m.type}`" if m is not None else f"`{name}`: not declared"
    if kind is Kind.CONSTANT:
        symbols = index.result.symbols
        value = symbols.constant_values.get(name) if symbols is not None else None
        return f"**constant** `{name}`" + (f" = `{value}`" if value is not None else "")
    if kind is Kind.EVENT:
        declared = any(e.name == name for e in spec.events)
        return f"**event** `{name}`" if declared else f"`{name}`: not declared as an event"
    return f"**{kind}** `{name}`"


def _roles(uses: Iterable[Use], labels: dict[Role, str]) -> list[str]:
    out = []
    for role, label in labels.items():
        where = list(dict.fromkeys(u.where for u in uses if u.role is role and u.where))
        if where:
            more = f" and {len(where) - LIST_LIMIT} more" if len(where) > LIST_LIMIT else ""
            out.append(f"{label}: {', '.join(where[:LIST_LIMIT])}{more}")
    return out


def _rule_hover(index: Index, name: str) -> list[str]:
    extent = next((e for e in index.outline if e.key == (Kind.RULE, name)), None)
    parts = [f"**rule** `{name}`"]
    if extent is not None:
        text = index.lines.text[extent.start : extent.end].splitlines()
        shown = "\n".join(text[:15]) + ("\n..." if len(text) > 15 else "")
        parts.append(f"```sleec\n{shown}\n```")
    spec = index.spec
    if spec is not None:
        above = [p.lower for p in spec.priorities if p.higher == name]
        below = [p.higher for p in spec.priorities if p.lower == name]
        if above:
            parts.append(f"takes precedence over: {', '.join(above)}")
        if below:
            parts.append(f"gives way to: {', '.join(below)}")
    return parts


# ---------------------------------------------------------------- definition, references


def definition(doc: Document, pos: T.Position) -> T.Location | None:
    """Where the name under the cursor is declared (in the paper notation: first used)."""
    index = doc.index()
    use = index.at(doc.lines.to_offset(pos))
    decl = index.declarations.get(use.key) if use is not None else None
    if decl is None:
        return None
    return T.Location(uri=doc.uri, range=doc.lines.range(decl.start, decl.end))


def references(doc: Document, pos: T.Position, include_declaration: bool) -> list[T.Location]:
    """Every place the name under the cursor is used, in file order."""
    index = doc.index()
    use = index.at(doc.lines.to_offset(pos))
    if use is None:
        return []
    return [
        T.Location(uri=doc.uri, range=doc.lines.range(u.start, u.end))
        for u in index.uses_of(use.key)
        if include_declaration or u.role is not Role.DECLARED
    ]


# ---------------------------------------------------------------- completion

_COMPARED = re.compile(r"\{?(\^?[A-Za-z_][A-Za-z0-9_]*)\}?\s*(?:<=|>=|<>|=|<|>)\s*[A-Za-z_0-9]*$")
_WORD_BEFORE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s+\^?[A-Za-z_0-9]*$")
_EVENT_NEXT = frozenset({"when", "then", "otherwise", "else", "and", "witness", "until"})
_CONDITION_NEXT = frozenset({"unless", "or", "not", "and"})
_ITEM_KIND = {
    Kind.EVENT: T.CompletionItemKind.Event,
    Kind.MEASURE: T.CompletionItemKind.Variable,
    Kind.CONSTANT: T.CompletionItemKind.Constant,
    Kind.RULE: T.CompletionItemKind.Function,
}


def completion(doc: Document, pos: T.Position) -> T.CompletionList:
    """Declared names, scale values and keywords; after ``m =`` for a scale measure ``m``,
    only its values, in order; after ``measure x :``, the types."""
    text = doc.text
    offset = doc.lines.to_offset(pos)
    line = text[text.rfind("\n", 0, offset) + 1 : offset]
    known = doc.known_names()
    scales = _scales(doc)
    compared = _COMPARED.search(line)
    if compared and compared.group(1).lstrip("^") in scales:
        values = scales[compared.group(1).lstrip("^")]
        return T.CompletionList(
            is_incomplete=False,
            items=[
                T.CompletionItem(
                    label=v,
                    kind=T.CompletionItemKind.EnumMember,
                    detail=f"scale value {i} of {len(values)}",
                    sort_text=f"{i:04d}",
                )
                for i, v in enumerate(values, start=1)
            ],
        )
    if re.search(r"\bmeasure\s+\^?\w+\s*:\s*\w*$", line):
        return T.CompletionList(
            is_incomplete=False,
            items=[
                T.CompletionItem(label=t, kind=T.CompletionItemKind.TypeParameter)
                for t in ("boolean", "numeric", "scale")
            ],
        )
    before = _WORD_BEFORE.search(line)
    previous = before.group(1).lower() if before else ""
    in_priorities = text.rfind("priority_start", 0, offset) > text.rfind("priority_end", 0, offset)
    first = {Kind.RULE} if in_priorities else {Kind.EVENT} if previous in _EVENT_NEXT else set()
    if previous in _CONDITION_NEXT and not in_priorities:
        first = {Kind.MEASURE, Kind.CONSTANT} | (first if previous == "and" else set())
    items: list[T.CompletionItem] = []
    for kind, name, detail in known:
        if kind is Kind.RULE and not in_priorities:
            continue
        rank = 0 if kind in first else 1
        items.append(
            T.CompletionItem(label=name, kind=_ITEM_KIND[kind], detail=detail, sort_text=f"{rank}{name}")
        )
    for measure, values in scales.items():
        for v in values:
            items.append(
                T.CompletionItem(
                    label=v,
                    kind=T.CompletionItemKind.EnumMember,
                    detail=f"scale value of {measure}",
                    sort_text=f"2{v}",
                )
            )
    items += [
        T.CompletionItem(label=k, kind=T.CompletionItemKind.Keyword, sort_text=f"3{k}")
        for k in _keywords(doc, offset)
    ]
    return T.CompletionList(is_incomplete=False, items=items)


def _scales(doc: Document) -> dict[str, list[str]]:
    spec = doc.result().spec
    if spec is None:
        return {}
    return {m.name: list(m.type.literals) for m in spec.measures if isinstance(m.type, A.ScaleType)}


def _keywords(doc: Document, offset: int) -> list[str]:
    if doc.is_paper:
        return sorted({k.upper() for k in PAPER_KEYWORDS} | {"IN WHICH CASE"})
    words = set(KEYWORDS)
    if doc.text.rfind("relation_start", 0, offset) > doc.text.rfind("relation_end", 0, offset):
        words |= CONTEXTUAL_KEYWORDS
    return sorted(words)


# ---------------------------------------------------------------- outline

_SYMBOL = {
    Kind.EVENT: T.SymbolKind.Event,
    Kind.MEASURE: T.SymbolKind.Variable,
    Kind.CONSTANT: T.SymbolKind.Constant,
    Kind.RULE: T.SymbolKind.Function,
    Kind.CONCERN: T.SymbolKind.Interface,
    Kind.PURPOSE: T.SymbolKind.Interface,
}
_GROUPS = (
    ("definitions", (Kind.EVENT, Kind.MEASURE, Kind.CONSTANT)),
    ("rules", (Kind.RULE,)),
    ("concerns", (Kind.CONCERN,)),
    ("purposes", (Kind.PURPOSE,)),
)


def document_symbols(doc: Document) -> list[T.DocumentSymbol]:
    """The outline: the declarations and the rules (then concerns and purposes), each group
    one symbol whose children are in file order; a scale measure's children are its values."""
    index = doc.index()
    lines = doc.lines
    out = []
    for label, kinds in _GROUPS:
        members = [e for e in index.outline if e.key[0] in kinds]
        if not members:
            continue
        children = [_symbol(index, e) for e in members]
        whole = lines.range(min(e.start for e in members), max(e.end for e in members))
        out.append(
            T.DocumentSymbol(
                name=label, kind=T.SymbolKind.Namespace, range=whole, selection_range=whole, children=children
            )
        )
    return out


def _symbol(index: Index, e: Extent) -> T.DocumentSymbol:
    lines = index.lines
    kind, name = e.key
    children = None
    if kind is Kind.MEASURE:
        m = index.measure(name)
        if m is not None and isinstance(m.type, A.ScaleType):
            values = [
                d
                for v in m.type.literals
                if (d := index.declarations.get((Kind.SCALE_VALUE, f"{name}.{v}"))) is not None
            ]
            children = [
                T.DocumentSymbol(
                    name=u.name,
                    kind=T.SymbolKind.EnumMember,
                    range=lines.range(u.start, u.end),
                    selection_range=lines.range(u.start, u.end),
                )
                for u in values
            ]
    return T.DocumentSymbol(
        name=name,
        kind=_SYMBOL[kind],
        detail=e.detail or None,
        range=lines.range(e.start, e.end),
        selection_range=lines.range(e.name_start, e.name_end),
        children=children,
    )


# ---------------------------------------------------------------- rename

_RENAMEABLE = frozenset({Kind.EVENT, Kind.MEASURE, Kind.CONSTANT, Kind.RULE, Kind.CONCERN, Kind.PURPOSE})
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def prepare_rename(doc: Document, pos: T.Position) -> T.Range | None:
    """The name under the cursor, when it can be renamed (not a scale value, not in a file
    that does not parse)."""
    use = _renameable(doc, pos)
    return doc.lines.range(use.start, use.end)


def rename(doc: Document, pos: T.Position, new: str) -> T.WorkspaceEdit:
    """Rename the event, measure, constant, rule, concern or purpose under the cursor
    everywhere in the file; refused for a name that is not an identifier, is a keyword, or
    is already declared."""
    use = _renameable(doc, pos)
    old = use.key[1]
    if not _IDENT.fullmatch(new):
        raise Refusal(f"`{new}` is not a name: a name is letters, digits and `_`, not starting with a digit")
    reserved = {k.lower() for k in PAPER_KEYWORDS} if doc.is_paper else KEYWORDS
    if (new.lower() if doc.is_paper else new) in reserved:
        raise Refusal(f"`{new}` is a keyword")
    taken = {n for _, n, _ in doc.known_names()} | {d.name for d in _declared(doc)}
    if new != old and new in taken:
        raise Refusal(f"`{new}` is already declared in this file", hint="choose a name no declaration uses")
    index = doc.index()
    edits = [T.TextEdit(range=doc.lines.range(u.start, u.end), new_text=new) for u in index.uses_of(use.key)]
    return T.WorkspaceEdit(changes={doc.uri: edits})


def _declared(doc: Document) -> Sequence[A.Definition | A.Situation]:
    spec = doc.result().spec
    return [*spec.definitions, *spec.concerns, *spec.purposes] if spec is not None else []


def _renameable(doc: Document, pos: T.Position) -> Use:
    if doc.result().spec is None:
        raise Refusal("the file does not parse: fix its syntax errors before renaming")
    use = doc.index().at(doc.lines.to_offset(pos))
    if use is None:
        raise Refusal("no name to rename here")
    if use.key[0] not in _RENAMEABLE:
        raise Refusal(f"a {use.key[0]} cannot be renamed on its own", hint="rename it in its measure's scale")
    return use


# ---------------------------------------------------------------- formatting


def formatting(doc: Document) -> list[T.TextEdit]:
    """``cosleec fmt`` of the current text: one edit covering what differs (none when the
    text is formatted)."""
    result = doc.result()
    if result.spec is None or not result.ok:
        raise Refusal(
            f"{doc.path} has errors: cosleec fmt formats a file that checks",
            hint="fix the errors shown first",
        )
    try:
        text = format_source(result.source, result.spec, None, doc.settings.format_width)
    except SleecError as e:
        raise Refusal(e.diagnostics[0].message if e.diagnostics else str(e)) from None
    source = doc.text
    if source.startswith("\ufeff"):  # as cosleec fmt writes it: the BOM and CRLF are kept
        text = "\ufeff" + text
    if "\r\n" in source:
        text = text.replace("\n", "\r\n")
    if text == source:
        return []
    start = 0
    limit = min(len(text), len(source))
    while start < limit and text[start] == source[start]:
        start += 1
    start = source.rfind("\n", 0, start) + 1  # whole lines: never between a `\r` and its `\n`
    end = 0
    while end < limit - start and text[-1 - end] == source[-1 - end]:
        end += 1
    while end and source[len(source) - end - 1] != "\n":
        end -= 1
    return [
        T.TextEdit(range=doc.lines.range(start, len(source) - end), new_text=text[start : len(text) - end])
    ]

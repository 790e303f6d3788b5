"""What ``cosleec fmt`` prints: a rule file in canonical form, its comments and blank lines
kept, in its own notation or another one -- or, when the other notation cannot say what the
file says, the reasons why not, each at its place in the file.

A formatter people adopt must never change what a file means. The paper notation has no
def block and fewer constructs; SLEEC-TK has none of LEGOS-SLEEC's blocks, ``else`` or
intervals; LEGOS-SLEEC's parser cuts some names in two. Each is refused here with a
diagnostic rather than printed wrong.
"""

from __future__ import annotations

import textwrap

from cosleec.lang import ast as A
from cosleec.lang.deep import deeply
from cosleec.lang.diagnostics import Diagnostic, Severity, SleecError
from cosleec.lang.dialect import collect, legos_misreads
from cosleec.lang.frontend import analyse
from cosleec.lang.layout import Layout
from cosleec.lang.parser import KEYWORDS, PAPER, SLEEC
from cosleec.lang.printer import WIDTH, PaperPrinter, Printer


def format_source(
    source: str,
    spec: A.Specification,
    dialect: A.Dialect | str | None = None,
    width: int = WIDTH,
) -> str:
    """``spec`` in canonical form, keeping the comments and blank lines of ``source`` (the
    text it was parsed from); a rule longer than ``width`` is printed one clause per line.
    By default in the file's own notation, the paper notation included.

    Raises :class:`~cosleec.lang.diagnostics.SleecError` when ``dialect`` cannot say what
    ``spec`` says (see the module docstring).
    """
    out = A.Dialect(dialect) if dialect is not None else spec.dialect
    grammar = PAPER if spec.dialect is A.Dialect.PAPER else SLEEC
    layout = Layout.read(source, spec, grammar.lexicon)
    if out is A.Dialect.PAPER:
        paper = PaperPrinter(spec, layout, width)
        text: str = deeply(paper.specification)
        marks = [  # a name spelt like a block word would make the file read as a DSL file
            (f"`{name}` would make the file read as a DSL file, not the paper notation", span)
            for name, span in _names(spec)
            if name in ("def_start", "rule_start")
        ]
        problems = [*paper.problems, *marks]
        _refuse(spec, source, problems, "print it in a DSL dialect (--dialect tk or legos)")
        if spec.dialect is not A.Dialect.PAPER:
            text = _same_declarations(spec, source, text)
        return text
    if out is not spec.dialect:
        _refuse(spec, source, deeply(lambda: _cannot(spec, out)), f"keep the file in {_NAMES[spec.dialect]}")
    elif out is A.Dialect.LEGOS:
        hint = "rename it: LEGOS-SLEEC would read the printed file differently"
        _refuse(spec, source, deeply(lambda: legos_misreads(spec)), hint)
    text = deeply(Printer(spec, out, layout, width).specification)
    if out is not spec.dialect:  # what the checks above missed, the printed file shows
        back = analyse(text, spec.path)
        if not back.ok or (out is A.Dialect.TK and back.dialect is A.Dialect.LEGOS):
            wrong = [(f"printed in {_NAMES[out]}: {d.message}", A.NO_SPAN) for d in back.errors]
            _refuse(spec, source, wrong or [(f"{_NAMES[out]} cannot say this", A.NO_SPAN)], "")
    return text


_NAMES = {A.Dialect.TK: "SLEEC-TK", A.Dialect.LEGOS: "LEGOS-SLEEC", A.Dialect.PAPER: "the paper notation"}
_SPELLING = ("braces", "->")  # LEGOS constructs that are only spelling: `{m}` is `m` in TK


def _cannot(spec: A.Specification, out: A.Dialect) -> list[tuple[str, A.Span]]:
    """What ``spec`` says that dialect ``out``'s own tool would not read, each at its place."""
    facts = collect(spec, "")
    if out is A.Dialect.TK:
        return [
            *(
                (f"{what} is LEGOS-SLEEC only: SLEEC-TK has no way to write it", span)
                for what, span in facts.legos
                if not any(s in what for s in _SPELLING)
            ),
            *facts.tk_rejects,
        ]
    escaped = [  # SLEEC-TK escapes a keyword used as a name (`^when`); LEGOS-SLEEC cannot
        (f"`{name}` is a keyword: LEGOS-SLEEC has no way to use it as a name", span)
        for name, span in _names(spec)
        if name in KEYWORDS
    ]
    return [*escaped, *facts.legos_rejects, *facts.legos_misreads]


def _names(spec: A.Specification) -> list[tuple[str, A.Span]]:
    """Every name ``spec`` declares (rules, events, measures, constants, scale literals)."""
    found = [(r.name, r.span) for r in spec.rules]
    for d in spec.definitions:
        found.append((d.name, d.span))
        if isinstance(d, A.MeasureDecl) and isinstance(d.type, A.ScaleType):
            spans = d.type.literal_spans or (d.span,) * len(d.type.literals)
            found += zip(d.type.literals, spans, strict=False)
    return found


def _refuse(
    spec: A.Specification,
    source: str,
    problems: list[tuple[str, A.Span]] | tuple[tuple[str, A.Span], ...],
    hint: str,
) -> None:
    if problems:
        raise SleecError(
            [
                Diagnostic(
                    severity=Severity.ERROR,
                    code="fmt-cannot",
                    message=message,
                    span=span,
                    path=spec.path,
                    hint=hint or None,
                )
                for message, span in problems
            ],
            source,
        )


def _same_declarations(spec: A.Specification, source: str, text: str) -> str:
    """The paper notation has no def block: a reader infers the declarations from use.
    Refuse a file whose declarations would be read back differently; list those no rule
    uses in a comment at the top (the notation has no other place for them)."""
    back = analyse(text, spec.path, dialect="paper").spec
    if back is None or deeply(lambda: back.rules != spec.rules):  # the printer's own guarantee, checked
        raise AssertionError(f"the paper notation of {spec.path} does not read back as its rules")
    inferred = {d.name: d for d in back.definitions}
    show = Printer(A.Specification((), ()), A.Dialect.TK).definition
    problems = [
        (
            f"the paper notation has no def block, and `{show(d)}` would be read as `{show(inferred[d.name])}`",
            d.span,
        )
        for d in spec.definitions
        if d.name in inferred and inferred[d.name] != d
    ]
    _refuse(spec, source, problems, "print it in a DSL dialect (--dialect tk or legos)")
    unused = [show(d) for d in spec.definitions if d.name not in inferred]
    if unused:
        listed = textwrap.wrap(", ".join(unused), 76, break_long_words=False, break_on_hyphens=False)
        text = (
            "".join(f"{line}\n" for line in ["// declared, used by no rule:", *[f"//   {x}" for x in listed]])
            + text
        )
    return text

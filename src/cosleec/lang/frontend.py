"""The front end as one straight pass: text -> parse -> assemble -> dialect facts -> checks.

``analyse`` is the pipeline; ``analyse_file``, ``parse`` and ``load`` wrap it for files and
for callers that want an exception. Each stage reads the text or the AST once: the parser
builds the AST as it parses (transformer.py), :func:`cosleec.lang.dialect.collect` walks it
once for everything dialect detection and the dialect checks need, the checker walks it once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

from cosleec.bulk import paused_gc
from cosleec.errors import ConfigurationError
from cosleec.lang import ast as A
from cosleec.lang.checker import Options, SymbolTable, check_and_read
from cosleec.lang.deep import deeply
from cosleec.lang.diagnostics import Diagnostic, DiagnosticSink, Severity, SleecError
from cosleec.lang.dialect import check_mixed, check_strict, collect, detect
from cosleec.lang.infer import infer_definitions
from cosleec.lang.parser import assemble, looks_like_paper, parse_blocks, parse_paper_rules
from cosleec.lang.recovery import keep, salvage
from cosleec.lang.transformer import Block

DIALECTS = ("auto", "tk", "legos", "paper")
"""The values of ``analyse(dialect=...)`` (and of the CLI's ``--dialect``)."""


@dataclass(kw_only=True)
class CheckResult:
    """Everything known about one file after parsing and checking it; what :func:`analyse`
    returns. ``spec`` is None when the file does not parse.

    Its :meth:`to_json` is a summary for ``cosleec check --json``, not a wire format: the
    specification stays in the process (there is no ``from_json``).
    """

    path: str
    source: str
    spec: A.Specification | None
    dialect: A.Dialect | None
    diagnostics: list[Diagnostic] = field(default_factory=list)
    symbols: SymbolTable | None = None

    @property
    def ok(self) -> bool:
        """No errors (warnings and notes allowed)."""
        return not any(d.is_error for d in self.diagnostics)

    @property
    def errors(self) -> list[Diagnostic]:
        """Only the error diagnostics (no warnings or notes), in report order."""
        return [d for d in self.diagnostics if d.is_error]

    def render(self) -> str:
        """Every diagnostic, compiler style, with the offending source lines."""
        return "\n".join(d.render(self.source) for d in self.diagnostics)

    def to_json(self) -> dict[str, object]:
        """A JSON-ready summary (``cosleec check --json``): ok, dialect, counts, diagnostics."""
        spec = self.spec
        return {
            "path": self.path,
            "ok": self.ok,
            "dialect": str(self.dialect) if self.dialect else None,
            "rules": len(spec.rules) if spec else 0,
            "events": len(spec.events) if spec else 0,
            "measures": len(spec.measures) if spec else 0,
            "diagnostics": [d.to_json() for d in self.diagnostics],
        }


def analyse(
    text: str,
    path: str = "<string>",
    *,
    dialect: str = "auto",
    strict: bool = False,
    infer_defs: bool = False,
    options: Options | None = None,
    legos_compat: bool = False,
) -> CheckResult:
    """Parse and check SLEEC text. Never raises for bad input: problems are diagnostics.

    Use it when you want every finding (an editor, ``cosleec check``); use :func:`parse` or
    :func:`load` when a bad file should stop you. ``dialect`` is one of :data:`DIALECTS`:
    ``auto`` detects it, ``tk``/``legos`` also report what that tool would reject, ``paper``
    reads the CO-SLEEC paper's notation. ``strict`` rejects cosleec's extensions;
    ``infer_defs`` infers the declarations of a file without a def block. ``legos_compat``
    (or ``Options(legos_compat=True)``) accepts what LEGOS-SLEEC accepts -- scale literals
    compared across scales, scales compared with numbers, duplicate rule, concern and purpose
    names -- with a warning each, and the result's ``spec`` carries LEGOS-SLEEC's reading of
    them (docs/reference/sleec-language.md §11 item 18).
    """
    return analyse_with(
        parse_blocks,
        text,
        path,
        dialect=dialect,
        strict=strict,
        infer_defs=infer_defs,
        options=options,
        legos_compat=legos_compat,
    )


BlockParser = Callable[[str, DiagnosticSink], "list[Block] | None"]
"""How DSL text becomes blocks: :func:`~cosleec.lang.parser.parse_blocks`, or a reading that
returns exactly what it returns (lang/incremental.py's, which parses only what changed)."""


def analyse_with(
    parse_dsl: BlockParser,
    text: str,
    path: str = "<string>",
    *,
    dialect: str = "auto",
    strict: bool = False,
    infer_defs: bool = False,
    options: Options | None = None,
    legos_compat: bool = False,
) -> CheckResult:
    """:func:`analyse`, reading DSL text into blocks with ``parse_dsl``: everything after
    parsing is the same pass, so the result is :func:`analyse`'s whenever ``parse_dsl``
    returns what ``parse_blocks`` returns."""
    if dialect not in DIALECTS:
        raise ConfigurationError(f"unknown dialect {dialect!r}; expected one of {', '.join(DIALECTS)}")
    with paused_gc():  # bulk construction: the collector would scan a growing heap for nothing
        return _analyse(parse_dsl, text, path, dialect, strict, infer_defs, options, legos_compat)


def _analyse(
    parse_dsl: BlockParser,
    text: str,
    path: str,
    dialect: str,
    strict: bool,
    infer_defs: bool,
    options: Options | None,
    legos_compat: bool,
) -> CheckResult:
    """:func:`analyse_with` once its arguments are checked."""
    opts = options or Options()
    if strict:
        opts = replace(opts, strict_extensions=True)
    if legos_compat:
        opts = replace(opts, legos_compat=True)
    if dialect == "tk":
        opts = replace(opts, tk_names=True)
    sink = DiagnosticSink(path)
    paper = dialect == "paper" or (dialect == "auto" and looks_like_paper(text))
    parsed: list[A.Rule] | list[Block] | None
    parsed = parse_paper_rules(text, sink) if paper else parse_dsl(text, sink)
    if parsed is None:
        if not paper:
            _check_what_parsed(text, path, dialect, infer_defs, opts, sink)
        return CheckResult(
            path=path,
            source=text,
            spec=None,
            dialect=A.Dialect.PAPER if paper else None,
            diagnostics=sink.sorted(),
        )
    # Parsing uses no recursion; the passes after it recurse once per level of an
    # expression: for a generated one 10,000 deep they run again in a deep thread (deep.py),
    # without the diagnostics of the attempt that met Python's recursion limit.
    mark = len(sink.items)

    def passes() -> CheckResult:
        del sink.items[mark:]
        return _passes(text, path, dialect, paper, parsed, infer_defs, opts, sink)

    return deeply(passes)


def _check_what_parsed(
    text: str, path: str, dialect: str, infer_defs: bool, opts: Options, sink: DiagnosticSink
) -> None:
    """After syntax errors, add to ``sink`` what the checks find in the rules that parsed
    (recovery.py); the file still has no specification."""
    found = salvage(text, sink.items)
    if found is None:
        return
    sink.items.extend(replace(d, path=path) for d in found.errors)  # heard once others were blanked
    blocks = found.blocks
    if blocks is None:
        return
    rest = DiagnosticSink(path)
    deeply(lambda: _passes(text, path, dialect, False, blocks, infer_defs, opts, rest))
    sink.items.extend(d for d in rest.items if keep(d, found.dropped))


def _passes(
    text: str,
    path: str,
    dialect: str,
    paper: bool,
    parsed: list[A.Rule] | list[Block],
    infer_defs: bool,
    opts: Options,
    sink: DiagnosticSink,
) -> CheckResult:
    """Everything after parsing: assembling, inferring, the dialect facts and checks, the checker."""
    spec: A.Specification
    if paper:
        rules: list[A.Rule] = parsed  # type: ignore[assignment]
        spec = A.Specification((), tuple(rules), dialect=A.Dialect.PAPER, path=path)
        spec = infer_definitions(spec, sink)
        detected = A.Dialect.PAPER
    else:
        blocks: list[Block] = parsed  # type: ignore[assignment]
        spec = assemble(blocks, path, sink)
        if infer_defs and not spec.definitions:
            spec = infer_definitions(spec, sink)
        facts = collect(spec, text)
        detected, evidence = detect(facts)
        if dialect in ("tk", "legos"):
            # under --strict the checker reports cosleec's extensions itself: not twice
            check_strict(facts, A.Dialect(dialect), sink, extensions=not opts.strict_extensions)
        elif evidence is not None:
            check_mixed(facts, evidence, sink)
        spec = replace(spec, dialect=detected)
    spec, symbols = check_and_read(spec, sink, opts)
    _said_once(sink)
    return CheckResult(
        path=path, source=text, spec=spec, dialect=detected, diagnostics=sink.sorted(), symbols=symbols
    )


def _said_once(sink: DiagnosticSink) -> None:
    """Drop the checker's ``untimed-otherwise`` warning where the mixed-dialect check has
    already made that ``otherwise`` an error with the same words (dialect.check_mixed)."""
    mixed = {d.span for d in sink.items if d.code == "mixed-dialect"}
    if mixed:
        sink.items[:] = [d for d in sink.items if not (d.code == "untimed-otherwise" and d.span in mixed)]


def read_source(path: str | Path) -> tuple[str | None, Diagnostic | None]:
    """Read a rule file as UTF-8; a problem comes back as a diagnostic, not an exception."""
    p = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        return None, Diagnostic(
            severity=Severity.ERROR, code="io", message=f"cannot read file: {e.strerror or e}", path=p
        )
    try:
        return data.decode("utf-8"), None
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        return None, Diagnostic(
            severity=Severity.ERROR,
            code="encoding",
            message="file is not UTF-8 text",
            span=A.Span(line, col, line, col + 1),
            path=p,
        )


def analyse_file(
    path: str | Path,
    *,
    dialect: str = "auto",
    strict: bool = False,
    infer_defs: bool = False,
    options: Options | None = None,
    legos_compat: bool = False,
) -> CheckResult:
    """:func:`analyse` a rule file; an unreadable file is a diagnostic too."""
    text, problem = read_source(path)
    if text is None:
        assert problem is not None
        return CheckResult(path=str(path), source="", spec=None, dialect=None, diagnostics=[problem])
    return analyse(
        text,
        str(path),
        dialect=dialect,
        strict=strict,
        infer_defs=infer_defs,
        options=options,
        legos_compat=legos_compat,
    )


def parse(
    text: str,
    path: str = "<string>",
    *,
    dialect: str = "auto",
    strict: bool = False,
    infer_defs: bool = False,
    options: Options | None = None,
    legos_compat: bool = False,
) -> A.Specification:
    """Parse and check; raise :class:`SleecError` carrying every diagnostic on any error."""
    result = analyse(
        text,
        path,
        dialect=dialect,
        strict=strict,
        infer_defs=infer_defs,
        options=options,
        legos_compat=legos_compat,
    )
    if not result.ok or result.spec is None:
        raise SleecError(result.diagnostics, text)
    return result.spec


def load(
    path: str | Path,
    *,
    dialect: str = "auto",
    strict: bool = False,
    infer_defs: bool = False,
    options: Options | None = None,
    legos_compat: bool = False,
) -> A.Specification:
    """Read, parse and check a rule file; raise :class:`SleecError` on any error."""
    result = analyse_file(
        path,
        dialect=dialect,
        strict=strict,
        infer_defs=infer_defs,
        options=options,
        legos_compat=legos_compat,
    )
    if not result.ok or result.spec is None:
        raise SleecError(result.diagnostics, result.source)
    return result.spec

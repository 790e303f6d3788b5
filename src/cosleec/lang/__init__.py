"""The SLEEC language: parsing (both dialects and the paper notation), checking, printing.

Typical use::

    from cosleec.lang import load
    spec = load("rules.sleec")          # raises SleecError with every diagnostic

    result = analyse_file("rules.sleec")  # never raises for bad input
    print(result.render())
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from cosleec.lang import ast
from cosleec.lang.ast import Dialect, Specification
from cosleec.lang.checker import Options, SymbolTable, check
from cosleec.lang.diagnostics import Diagnostic, DiagnosticSink, Severity, SleecError
from cosleec.lang.dialect import check_mixed, check_strict, detect
from cosleec.lang.infer import infer_definitions
from cosleec.lang.parser import assemble, looks_like_paper, parse_blocks, parse_paper_rules

DIALECTS = ("auto", "tk", "legos", "paper")


@dataclass
class CheckResult:
    """Everything known about one file after parsing and checking it."""

    path: str
    source: str
    spec: Specification | None
    dialect: Dialect | None
    diagnostics: list[Diagnostic] = field(default_factory=list)
    symbols: SymbolTable | None = None

    @property
    def ok(self) -> bool:
        return not any(d.is_error for d in self.diagnostics)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    def render(self) -> str:
        return "\n".join(d.render(self.source) for d in self.diagnostics)

    def to_json(self) -> dict[str, object]:
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
) -> CheckResult:
    """Parse and check SLEEC text. Never raises for bad input: problems are diagnostics."""
    if dialect not in DIALECTS:
        raise ValueError(f"unknown dialect {dialect!r}; expected one of {', '.join(DIALECTS)}")
    opts = options or Options()
    if strict:
        opts = replace(opts, strict_extensions=True)
    if dialect == "tk":
        opts = replace(opts, tk_names=True)
    sink = DiagnosticSink(path)
    spec: Specification | None
    if dialect == "paper" or (dialect == "auto" and looks_like_paper(text)):
        rules = parse_paper_rules(text, sink)
        if rules is None:
            return CheckResult(path, text, None, Dialect.PAPER, sink.sorted())
        spec = Specification((), tuple(rules), dialect=Dialect.PAPER, path=path)
        spec = infer_definitions(spec, sink)
        detected = Dialect.PAPER
    else:
        blocks = parse_blocks(text, sink)
        if blocks is None:
            return CheckResult(path, text, None, None, sink.sorted())
        spec = assemble(blocks, path, sink)
        if infer_defs and not spec.definitions:
            spec = infer_definitions(spec, sink)
        detected, evidence = detect(spec)
        if dialect in ("tk", "legos"):
            check_strict(spec, Dialect(dialect), text, sink)
        elif evidence is not None:
            check_mixed(spec, evidence, text, sink)
        spec = replace(spec, dialect=detected)
    symbols = check(spec, sink, opts)
    return CheckResult(path, text, spec, detected, sink.sorted(), symbols)


def read_source(path: str | Path) -> tuple[str | None, Diagnostic | None]:
    """Read a rule file as UTF-8; a problem comes back as a diagnostic, not an exception."""
    p = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        return None, Diagnostic(Severity.ERROR, "io", f"cannot read file: {e.strerror or e}", path=p)
    try:
        return data.decode("utf-8"), None
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        return None, Diagnostic(
            Severity.ERROR, "encoding", "file is not UTF-8 text", ast.Span(line, col, line, col + 1), p
        )


def analyse_file(path: str | Path, **kw: object) -> CheckResult:
    text, problem = read_source(path)
    if text is None:
        assert problem is not None
        return CheckResult(str(path), "", None, None, [problem])
    return analyse(text, str(path), **kw)  # type: ignore[arg-type]


def parse(text: str, path: str = "<string>", **kw: object) -> Specification:
    """Parse and check; raise :class:`SleecError` carrying every diagnostic on any error."""
    result = analyse(text, path, **kw)  # type: ignore[arg-type]
    if not result.ok or result.spec is None:
        raise SleecError(result.diagnostics, text)
    return result.spec


def load(path: str | Path, **kw: object) -> Specification:
    """Read, parse and check a rule file; raise :class:`SleecError` on any error."""
    result = analyse_file(path, **kw)
    if not result.ok or result.spec is None:
        raise SleecError(result.diagnostics, result.source)
    return result.spec


__all__ = [
    "CheckResult",
    "Diagnostic",
    "Dialect",
    "Options",
    "SleecError",
    "Specification",
    "analyse",
    "analyse_file",
    "ast",
    "load",
    "parse",
]

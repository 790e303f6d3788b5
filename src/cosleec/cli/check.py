"""``cosleec check``: parse and check rule files, report compiler-style diagnostics."""

from __future__ import annotations

import argparse
import json

from rich.text import Text

from cosleec.cli.common import add_clause_options, console, expand
from cosleec.errors import ConfigurationError
from cosleec.lang import (
    CheckResult,
    Diagnostic,
    HedgeSemantics,
    Options,
    Severity,
    analyse_file,
    ast,
    clause_semantics_for,
)


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec check`` and its options."""
    p = sub.add_parser("check", help="parse and check SLEEC rule files")
    p.add_argument(
        "files", nargs="+", metavar="FILE", help="rule files (a directory means its *.sleec files)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    p.add_argument(
        "--dialect",
        choices=["auto", "tk", "legos", "paper"],
        default="auto",
        help="force a dialect: tk/legos also check that tool's grammar strictly",
    )
    p.add_argument("--strict", action="store_true", help="reject cosleec extensions (response conjunction)")
    p.add_argument(
        "--infer-defs", action="store_true", help="infer declarations for files without a def block"
    )
    p.add_argument(
        "--strict-precedence", action="store_true", help="mixed and/or without parentheses is an error"
    )
    p.add_argument("--lint", action="store_true", help="also warn about naming conventions and style")
    p.add_argument(
        "--legos-compat",
        action="store_true",
        help="accept what LEGOS-SLEEC accepts (cross-scale literals, scales compared with numbers, "
        "duplicate rule/concern/purpose names) with a warning each, read as LEGOS-SLEEC reads them",
    )
    add_clause_options(
        p,
        unknown=False,
        semantics_help="clause semantics the unreachable-clause warnings assume (as the runtime's); "
        "default: the file's semantics block, else last-wins; one that contradicts the file is an error",
    )
    p.set_defaults(run=run, semantics=None)  # None: the file's own (its semantics block)


def run(args: argparse.Namespace) -> int:
    """Check every file and print its diagnostics, as text or one JSON document.

    Returns 0 when no file has an error (warnings do not count), 1 otherwise. A file's
    semantics block decides the clause semantics unless ``--semantics`` is given; one given
    that contradicts the file is an error of that file.
    """
    files = expand(args.files)
    opts = Options(
        strict_precedence=args.strict_precedence,
        lint=args.lint,
        semantics=HedgeSemantics(args.semantics or HedgeSemantics.LAST_WINS),
        legos_compat=args.legos_compat,
    )
    results = [
        analyse_file(f, dialect=args.dialect, strict=args.strict, infer_defs=args.infer_defs, options=opts)
        for f in files
    ]
    for r in results:
        _agree(r, args.semantics)
    if args.json:
        print(json.dumps({"files": [r.to_json() for r in results]}, indent=2))
    else:
        out = console()
        for r in results:
            for d in r.diagnostics:
                lines = d.render(r.source).split("\n")
                sev = f" {d.severity}: "
                loc, _, msg = lines[0].partition(sev)
                style = {"error": "bold red", "warning": "yellow", "note": "cyan"}[str(d.severity)]
                out.print(Text.assemble(loc, (sev, style), msg))
                for extra in lines[1:]:
                    out.print(Text(extra))
            n_err = len(r.errors)
            n_warn = sum(1 for d in r.diagnostics if str(d.severity) == "warning")
            if r.spec is not None and n_err == 0:
                extra = f", {n_warn} warnings" if n_warn else ""
                out.print(
                    Text(
                        f"{r.path}: ok ({r.dialect}, {len(r.spec.rules)} rules, {len(r.spec.events)} "
                        f"events, {len(r.spec.measures)} measures{extra})"
                    )
                )
            else:
                out.print(
                    Text.assemble(f"{r.path}: ", (f"{n_err} error{'s' if n_err != 1 else ''}", "bold red"))
                )
    return 0 if all(r.ok for r in results) else 1


def _agree(result: CheckResult, given: str | None) -> None:
    """An error on ``result`` when ``--semantics`` contradicts the file's semantics block."""
    if given is None or result.spec is None:
        return
    try:
        clause_semantics_for(result.spec, given, option="--semantics")
    except ConfigurationError as e:
        declared = next(
            (d for d in result.spec.semantics if d.value == str(result.spec.clause_semantics)), None
        )
        result.diagnostics.append(
            Diagnostic(
                severity=Severity.ERROR,
                code="semantics-conflict",
                message=e.message,
                span=declared.span if declared is not None else ast.NO_SPAN,
                path=result.path,
                hint=e.hint,
            )
        )

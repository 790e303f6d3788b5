"""``cosleec fmt``: print a rule file in canonical form, in either dialect."""

from __future__ import annotations

import argparse
import sys

from cosleec.lang import Diagnostic, Dialect, Severity, analyse_file, format_spec, legos_misreads


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec fmt`` and its options."""
    p = sub.add_parser("fmt", help="print a rule file in canonical form (converts between dialects)")
    p.add_argument("file", metavar="FILE", help="the rule file to print")
    p.add_argument(
        "--dialect",
        choices=["tk", "legos"],
        default=None,
        help="dialect to print in (default: the file's own; the paper notation prints as TK)",
    )
    p.add_argument(
        "--infer-defs", action="store_true", help="infer declarations for files without a def block"
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the file in canonical form; on errors print the diagnostics to stderr and return 1.

    Printing in the LEGOS dialect, a name that LEGOS-SLEEC's parser would cut in two
    (``notStop`` read as ``not Stop``, docs/reference/sleec-language.md §11 item 10) is an error:
    the file would not mean to LEGOS-SLEEC what it means to cosleec.
    """
    result = analyse_file(args.file, infer_defs=args.infer_defs)
    if result.spec is None or not result.ok:
        print(result.render(), file=sys.stderr)
        return 1
    out = Dialect(args.dialect) if args.dialect else result.spec.dialect
    if out is Dialect.LEGOS:
        misread = [
            Diagnostic(
                severity=Severity.ERROR,
                code="legos-keyword-prefix",
                message=message,
                span=span,
                path=result.path,
                hint="rename it: LEGOS-SLEEC would read the printed file differently",
            )
            for message, span in legos_misreads(result.spec)
        ]
        if misread:
            print("\n".join(d.render(result.source) for d in misread), file=sys.stderr)
            return 1
    sys.stdout.write(format_spec(result.spec, args.dialect))
    return 0

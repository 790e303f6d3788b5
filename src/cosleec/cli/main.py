"""``cosleec`` entry point: sub-commands, exit codes, and no tracebacks for users.

Exit codes are a contract: 0 success, 1 the input has errors (rules, mapping, launch
file) or a refusal such as unsafe network settings, 2 usage errors (including
``cosleec decide`` values it cannot use, or a decision it could not make for lack of a
value), 130 interrupted. An unexpected internal failure prints one line and exits 70.

A usage error names the command or option closest to the one misspelt (``cosleec chekc``:
did you mean ``check``?); ``cosleec --version`` prints the installed version.
"""

from __future__ import annotations

import argparse
import difflib
import re
import sys
from collections.abc import Sequence
from importlib import metadata

from cosleec.cli import analyse, check, conforms, decide, demo, fmt, graph, lsp, ros, scaffold, timeline
from cosleec.errors import UserError
from cosleec.lang import SleecError

USAGE_ERROR = 2
INTERNAL_ERROR = 70


def _did_you_mean(word: str, choices: Sequence[str]) -> str:
    """`` (did you mean 'check'?)`` when ``word`` is close to one of ``choices``, else ``""``."""
    close = difflib.get_close_matches(word, list(choices), n=2, cutoff=0.6)
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""


class _Parser(argparse.ArgumentParser):
    """An argparse parser whose errors exit 2 and suggest the option or command meant."""

    def error(self, message: str) -> None:  # type: ignore[override]
        """Print the usage and ``message`` (with a did-you-mean for a misspelt choice); exit 2."""
        bad = re.search(r"invalid choice: '(.*?)' \(choose from (.*)\)$", message)
        if bad:
            message += _did_you_mean(bad.group(1), re.findall(r"'([^']*)'", bad.group(2)))
        self.print_usage(sys.stderr)
        print(f"cosleec: error: {message}\n  hint: `{self.prog} --help` lists what it takes", file=sys.stderr)
        raise SystemExit(USAGE_ERROR)

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        """As argparse's, noting on the result the innermost (sub-)parser, for :meth:`parse_args`."""
        ns, extras = super().parse_known_args(args, namespace)
        if not hasattr(ns, _PARSER):  # the innermost sub-parser finishes first and is kept
            setattr(ns, _PARSER, self)
        return ns, extras

    def parse_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        """As argparse's; an unknown argument is reported by the sub-command it was given to,
        with the option it is closest to (``--jsn``: did you mean ``--json``?)."""
        ns, extras = self.parse_known_args(args, namespace)
        parser: _Parser = getattr(ns, _PARSER, self)
        delattr(ns, _PARSER)
        if extras:
            options = [o for o in parser._option_string_actions if o.startswith("--")]
            said = [_unrecognized(a, options) for a in extras]
            parser.error(f"unrecognized argument{'s' if len(extras) > 1 else ''}: {', '.join(said)}")
        return ns


_PARSER = "_cosleec_parser"


def _unrecognized(arg: str, options: list[str]) -> str:
    """An unknown argument as the error names it: ``--jsn (did you mean '--json'?)``, or ``'extra'``."""
    if not (arg.startswith("-") and len(arg) > 1):
        return repr(arg)
    # compared without the dashes that every option shares, and without a value (--jsn=1)
    close = difflib.get_close_matches(arg.split("=", 1)[0].lstrip("-"), [o[2:] for o in options], n=2)
    return arg if not close else f"{arg} (did you mean {' or '.join(repr('--' + c) for c in close)}?)"


def _version() -> str:
    try:
        return metadata.version("cosleec")
    except metadata.PackageNotFoundError:  # pragma: no cover - running from a source tree, not installed
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    """The ``cosleec`` parser with every sub-command; its usage errors exit 2."""
    p = _Parser(prog="cosleec", description="Operationalise SLEEC rules with context-oriented programming.")
    p.add_argument(
        "--version", action="version", version=f"cosleec {_version()}", help="print the version and exit"
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    check.add_parser(sub)
    fmt.add_parser(sub)
    decide.add_parser(sub)
    conforms.add_parser(sub)
    analyse.add_parser(sub)
    demo.add_parser(sub)
    scaffold.add_parser(sub)
    graph.add_parser(sub)
    timeline.add_parser(sub)
    lsp.add_parser(sub)
    ros.add_parser(sub, "ros2")
    ros.add_parser(sub, "ros1")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``cosleec`` on ``argv`` (default: the process's arguments) and return the exit code.

    It returns instead of exiting, so tests and programs can call it, and never shows a
    traceback: a :class:`~cosleec.errors.UserError` prints its message, place and hint.
    """
    parser = build_parser()
    try:
        given = list(sys.argv[1:] if argv is None else argv)
        rest, ros_args = ros.split_ros_args(given) if given[:1] in (["ros1"], ["ros2"]) else (given, [])
        args = parser.parse_args(rest)
        args.ros_args = ros_args
        rc: int = args.run(args)
        return rc
    except SystemExit as e:
        if isinstance(e.code, str):  # a refusal with its reason (e.g. unsafe network settings)
            print(e.code, file=sys.stderr)
            return 1
        return int(e.code) if isinstance(e.code, int) else 0
    except UserError as e:  # a mistake the user can fix: the message, where, and the hint
        print(e.render() if isinstance(e, SleecError) else f"cosleec: {e.render()}", file=sys.stderr)
        return 1
    except RecursionError:  # only input nested past Python's limit gets here (20,000 `not`s)
        print(
            "cosleec: the input is nested too deeply to read (an expression thousands of levels deep)"
            "\n  hint: split the expression, or name its parts as measures",
            file=sys.stderr,
        )
        return 1
    except ValueError as e:
        if "integer string conversion" not in str(e):  # Python's 4,300-digit limit, met in the input
            return _internal(e)  # (a `raise` here would escape the `except Exception` below)
        print(
            "cosleec: a number in the input has more than 4,300 digits"
            "\n  hint: no deadline or measure needs that many; write a smaller number",
            file=sys.stderr,
        )
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
    except OSError as e:
        if e.filename is None:  # not about a path the user gave: a bug, reported below
            return _internal(e)
        print(  # a path given on the command line that cannot be read or written
            f"cosleec: {e.filename}: {e.strerror or e}"
            "\n  hint: check the path, that its directory exists, and its permissions",
            file=sys.stderr,
        )
        return 1
    except Exception as e:  # never show a traceback to a user
        return _internal(e)


def _internal(e: BaseException) -> int:
    """A bug of ours: one line, never a traceback, exit 70."""
    print(f"cosleec: internal error: {type(e).__name__}: {e} (please report this)", file=sys.stderr)
    return INTERNAL_ERROR


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

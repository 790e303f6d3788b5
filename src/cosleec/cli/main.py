"""``cosleec`` entry point: sub-commands, exit codes, and no tracebacks for users.

Exit codes are a contract: 0 success, 1 the input has errors (rules, mapping, launch
file) or a refusal such as unsafe network settings, 2 usage errors (including
``cosleec decide`` values it cannot use, or a decision it could not make for lack of a
value), 130 interrupted. An unexpected internal failure prints one line and exits 70.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from cosleec.cli import analyse, check, conforms, decide, demo, fmt, ros
from cosleec.errors import UserError
from cosleec.lang import SleecError

USAGE_ERROR = 2
INTERNAL_ERROR = 70


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        print(f"cosleec: error: {message}", file=sys.stderr)
        raise SystemExit(USAGE_ERROR)


def build_parser() -> argparse.ArgumentParser:
    """The ``cosleec`` parser with every sub-command; its usage errors exit 2."""
    p = _Parser(prog="cosleec", description="Operationalise SLEEC rules with context-oriented programming.")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    check.add_parser(sub)
    fmt.add_parser(sub)
    decide.add_parser(sub)
    conforms.add_parser(sub)
    analyse.add_parser(sub)
    demo.add_parser(sub)
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
            raise
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
    except Exception as e:  # never show a traceback to a user
        print(f"cosleec: internal error: {type(e).__name__}: {e} (please report this)", file=sys.stderr)
        return INTERNAL_ERROR


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

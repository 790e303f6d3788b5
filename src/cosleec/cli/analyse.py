"""``cosleec analyse``: conflicting, redundant and dead rules, found before the robot runs them.

Exit codes: 0 nothing found (or only findings below ``--fail-on``), 1 a finding at or above
``--fail-on`` (``error``, ``warning`` -- the default -- or ``note``: a note alone does not
fail CI unless asked), 2 a usage or input error (a file with errors among them), 3 nothing
that fails found but the analysis is partial: ``--deadline`` passed before every check had
decided every rule (what was not decided is listed; 1 wins over 3, a finding is proved
whether or not the run finished). ``--timeout`` bounds each solver question,
``--deadline`` the whole run. Text output is compiler style (file:line:col, the line with a caret, notes at the
rules involved, a hint), then whether the finding is proved or holds up to a bound, and the
witness as a timeline; ``--json`` prints one document; ``--sarif FILE`` writes SARIF 2.1.0;
``--witnesses DIR`` writes each witness as a trace ``cosleec conforms`` reads.

``--fix`` repairs as well (:mod:`cosleec.repair`): under each finding its verified fixes,
best first, with what else they change and their unified diffs, then the file's patch set
(the fixes that verify applied together) and what it leaves unrepaired; ``--fix --write``
writes each file's patch set to it, atomically (cli/patching.py). The exit code is the
analysis' own, of the files as they were read.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import importlib.util
import json
import math
import os
import re
import sys
from dataclasses import replace
from pathlib import Path
from types import ModuleType

from rich.text import Text

from cosleec.analysis import (
    CHECKS,
    DEFAULT_BOUND,
    MORE,
    Coverage,
    Deadline,
    FileReport,
    Settings,
    analyse_file,
    sarif,
)
from cosleec.cli.common import add_clause_options, add_priority_options, console, expand, input_file
from cosleec.cli.fixes import add_fixes, as_file_report, show_fixes, show_patch_set
from cosleec.cli.patching import write_patch_sets
from cosleec.errors import ConfigurationError, UserError
from cosleec.lang import (
    HedgeSemantics,
    PrioritySemantics,
    SleecError,
    Untimed,
    clause_semantics_for,
    cycle,
    load,
    parse_priority,
    parse_untimed,
)
from cosleec.lang import analyse_file as check_file
from cosleec.repair import Budget, RepairReport, repair_file, with_fixes

USAGE_ERROR = 2
PARTIAL = 3
"""Nothing found, but the deadline passed before the analysis was complete."""
STYLE = {"error": "bold red", "warning": "yellow", "note": "cyan"}
FAIL_ON = ("error", "warning", "note")
"""The levels ``--fail-on`` takes, most serious first: a finding at or above the one given fails the run."""
LEGOS_DEFECTS = frozenset({"scale-literal", "duplicate-rule", "duplicate-name"})
"""Errors of files LEGOS accepts: ``--legos-compat`` reads them as LEGOS does."""


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec analyse`` and its options."""
    p = sub.add_parser(
        "analyse",
        aliases=["analyze"],
        help="find conflicting, redundant and dead rules (z3), with minimal causes and witnesses",
        description="Analyse rule sets with z3 on the reference semantics. Exit 0: nothing found (or only "
        "findings below --fail-on); 1: a finding at or above --fail-on; 2: a usage or input error; 3: "
        "nothing that fails found, but --deadline passed before the analysis was complete (what was "
        "not decided is listed). Checks: " + "; ".join(f"{k}: {v}" for k, v in CHECKS.items()),
    )
    p.add_argument(
        "files", nargs="+", metavar="FILE", help="rule files (a directory means its *.sleec files)"
    )
    p.add_argument(
        "--check",
        metavar="LIST",
        help="comma-separated checks to run (default: all): " + ", ".join(CHECKS),
    )
    p.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    p.add_argument("--sarif", metavar="FILE", help="also write the findings as SARIF 2.1.0 to FILE")
    p.add_argument("--witnesses", metavar="DIR", help="write each witness as a JSON Lines trace in DIR")
    p.add_argument(
        "--fail-on",
        choices=FAIL_ON,
        default="warning",
        help="exit 1 when a finding of this severity or a more serious one is found (default: warning; "
        "a note alone exits 0)",
    )
    _add_limits(p)
    p.add_argument(
        "--untimed",
        default="none",
        metavar="none|S",
        help="an untimed obligation: none = must happen some time (default), or within S seconds "
        "(0: at the same instant, as LEGOS/N-Check)",
    )
    add_clause_options(
        p,
        unknown=False,
        semantics_help="how the unless clauses of a rule combine (default: the file's semantics block, else "
        "last-wins, as SLEEC); one that contradicts the file's semantics block is an error",
    )
    p.set_defaults(semantics=None)  # not given: each file's own declaration (_file_settings)
    add_priority_options(p)
    _add_inputs(p)
    _add_fix(p)
    p.set_defaults(run=run)


def _add_fix(p: argparse.ArgumentParser) -> None:
    """``--fix``, ``--write``, ``--fix-tries`` and ``--fix-keep``: repairs, and applying them."""
    p.add_argument(
        "--fix",
        action="store_true",
        help="under each finding, its verified repairs, best first, as unified diffs with what else "
        "they change; per file, the set of fixes that verifies applied together",
    )
    p.add_argument(
        "--write",
        action="store_true",
        help="with --fix: apply each file's patch set to the file (atomically; comments and layout kept)",
    )
    p.add_argument(
        "--fix-tries",
        type=_positive,
        default=None,
        metavar="N",
        help=f"with --fix: candidates verified per finding, at most (default {Budget().tried})",
    )
    p.add_argument(
        "--fix-keep",
        type=_positive,
        default=None,
        metavar="N",
        help=f"with --fix: verified fixes kept per finding (default {Budget().kept})",
    )


def _fix_options(args: argparse.Namespace) -> None:
    """Refuse the combinations of --fix's options that mean nothing (UserError)."""
    if not args.fix:
        for option, given in (("--write", args.write), ("--fix-tries", args.fix_tries is not None),
                              ("--fix-keep", args.fix_keep is not None)):  # fmt: skip
            if given:
                raise UserError(f"{option} needs --fix", hint=f"cosleec analyse --fix {option} ...")
    elif args.check is not None:
        raise UserError(
            "--check cannot be used with --fix: a fix is verified against every check",
            hint="leave out --check (--fix runs all checks)",
        )


def _add_limits(p: argparse.ArgumentParser) -> None:
    """``--bound``, ``--timeout`` and ``--deadline``: how far the search goes, how long it may take."""
    p.add_argument(
        "--bound",
        type=_positive,
        default=DEFAULT_BOUND,
        metavar="N",
        help=f"occurrences per event the search may use (default {DEFAULT_BOUND}); a result that needs "
        "more says 'up to bound N'",
    )
    p.add_argument(
        "--timeout",
        type=_seconds,
        default=5.0,
        metavar="S",
        help="seconds each solver question may take (default 5); unanswered ones are listed. "
        "--deadline bounds the whole run",
    )
    p.add_argument(
        "--deadline",
        type=_seconds,
        default=None,
        metavar="S",
        help="seconds the whole run may take, every file and check (default: no limit); when it passes, "
        "the findings so far are printed with what was not decided, and the exit code is 3 if "
        "nothing was found",
    )


def _add_inputs(p: argparse.ArgumentParser) -> None:
    """How the files are read, and what else the rules are held against (tasks, a mapping)."""
    p.add_argument(
        "--infer-defs", action="store_true", help="infer declarations for files without a def block"
    )
    p.add_argument(
        "--legos-compat",
        action="store_true",
        help="read files as LEGOS does (cross-scale literals, duplicate names), with warnings",
    )
    p.add_argument(
        "--tasks",
        metavar="MODULE",
        help="a module (dotted name, or a .py file) with install(manager): report unimplemented clauses",
    )
    p.add_argument(
        "--mapping", metavar="YAML", help="a Context Listener mapping: report inputs it never produces"
    )


def _positive(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a whole number") from None
    if not 1 <= n <= 1000:
        raise argparse.ArgumentTypeError(f"{n} is out of range (1 to 1000)")
    return n


def _seconds(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a number of seconds") from None
    if not math.isfinite(x) or x <= 0:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a positive number of seconds")
    return x


def _checks(text: str | None) -> list[str]:
    if text is None:
        return list(CHECKS)
    out = []
    for name in (n.strip() for n in text.split(",")):
        if not name:
            continue
        if name not in CHECKS:
            close = (
                difflib.get_close_matches(name, list(CHECKS), n=1)
                or [c for c in CHECKS if difflib.get_close_matches(name, c.split("-"), n=1, cutoff=0.7)][:2]
            )
            raise UserError(
                f"unknown check {name[:40]!r}" + (f" (did you mean {' or '.join(close)}?)" if close else ""),
                hint="one or more of: " + ", ".join(CHECKS),
            )
        out.append(name)
    if not out:
        raise UserError("--check names no check", hint="one or more of: " + ", ".join(CHECKS))
    return out


def _untimed(text: str) -> Untimed | float:
    """``--untimed``: none or a finite, non-negative number of seconds (:func:`parse_untimed`
    without ``immediate``: the analysis reads a run's rules, not its tolerance)."""
    try:
        value: Untimed | float | None = parse_untimed(text)
    except ConfigurationError:
        value = None
    if value is None or value == Untimed.IMMEDIATE:
        raise UserError(f"--untimed {text[:40]!r} is neither none nor a non-negative number of seconds")
    return value


def run(args: argparse.Namespace) -> int:
    """Analyse every file; print the findings; write SARIF and witnesses when asked."""
    try:
        checks = _checks(args.check)
        untimed = _untimed(args.untimed)
        given = [pair for text in args.priority for pair in parse_priority(text)]
        _fix_options(args)
    except UserError as e:
        print(f"cosleec: {e.render()}", file=sys.stderr)
        return USAGE_ERROR
    except SleecError as e:
        print(e.render(), file=sys.stderr)
        return USAGE_ERROR
    loop = cycle(given)
    if loop:
        print(f"cosleec: the priorities given form a cycle: {' > '.join(loop)}", file=sys.stderr)
        return USAGE_ERROR
    files = expand(args.files)
    unknown = _unknown_rules(given, files, args.legos_compat)
    if unknown:
        print(f"cosleec: {unknown}", file=sys.stderr)
        return USAGE_ERROR
    settings = Settings(
        semantics=HedgeSemantics(args.semantics or HedgeSemantics.LAST_WINS),  # per file: _file_settings
        untimed=untimed,
        bound=args.bound,
        timeout=args.timeout,
        priorities=frozenset(given),
        priority_semantics=PrioritySemantics(args.priority_semantics),
    )
    try:
        reports, repaired = _analyse(args, files, settings, checks)
    except UserError as e:  # an input error (a module, a mapping, an output path): exit 2
        print(f"cosleec: {e.render()}", file=sys.stderr)
        return USAGE_ERROR
    return _report(args, reports, repaired)


def _report(args: argparse.Namespace, reports: list[FileReport], repaired: list[RepairReport] | None) -> int:
    """Print the reports (and, with --fix --write, write the patch sets); the exit code."""
    written: list[RepairReport] = []
    problem = None
    if args.write and repaired is not None:
        written, problem = write_patch_sets(repaired)
    if args.json:
        doc = _json(reports)
        if repaired is not None:
            add_fixes(doc, repaired, written)
        print(json.dumps(doc, indent=2))
    else:
        _text(reports, repaired)
        for r in written:
            assert r.plan is not None
            n = len(r.plan.fixes)
            print(f"{r.path}: wrote the patch set ({n} fix{'es' if n != 1 else ''}); "
                  f"cosleec analyse {r.path} checks the result")  # fmt: skip
    if problem is not None:
        print(f"cosleec: {problem.render()}", file=sys.stderr)
        return USAGE_ERROR
    if any(r.failed for r in reports):
        return USAGE_ERROR  # a rule file that cannot be analysed is an input error
    if _fails(reports, args.fail_on):
        return 1
    return PARTIAL if any(not r.complete for r in reports) else 0


def _fails(reports: list[FileReport], level: str) -> bool:
    """Is a finding of severity ``level`` (``--fail-on``) or a more serious one among ``reports``?"""
    worst = FAIL_ON.index(level)
    return any(FAIL_ON.index(str(f.severity)) <= worst for r in reports for f in r.findings)


def _analyse(
    args: argparse.Namespace, files: list[Path], settings: Settings, checks: list[str]
) -> tuple[list[FileReport], list[RepairReport] | None]:
    """Every file's report (and with --fix its repairs), under one ``--deadline``; then the
    witnesses and the SARIF file written when asked (UserError: a module, a mapping or an
    output path that fails)."""
    reports = []
    repaired: list[RepairReport] | None = None
    deadline = Deadline.after(args.deadline) if args.deadline is not None else None
    if args.fix:
        repaired = _repair(args, files, settings, deadline)
        reports = [as_file_report(r) for r in repaired]
    else:
        for f in files:
            coverage = _coverage(args, f)
            own = _file_settings(args, f, settings)
            reports.append(
                analyse_file(
                    f, own, checks, legos_compat=args.legos_compat, infer_defs=args.infer_defs,
                    coverage=coverage, deadline=deadline,
                )
            )  # fmt: skip
    if args.witnesses:
        _write_witnesses(Path(args.witnesses), reports)
    if args.sarif:
        try:
            log = sarif(reports, checks)
            text = json.dumps(log if repaired is None else with_fixes(log, repaired), indent=2) + "\n"
            Path(args.sarif).write_text(text, encoding="utf-8")
        except OSError as e:
            raise UserError(
                f"cannot write the SARIF file: {e.strerror or e}",
                where=args.sarif,
                hint="give a path in a directory that exists and that you can write",
            ) from None
    return reports, repaired


def _repair(
    args: argparse.Namespace, files: list[Path], settings: Settings, deadline: Deadline | None
) -> list[RepairReport]:
    """``--fix``: every file analysed and repaired, with the limits the options set."""
    default = Budget()
    budget = Budget(
        tried=args.fix_tries or default.tried,
        kept=args.fix_keep or default.kept,
        deadline=deadline,
        workers=os.cpu_count() or 1,  # findings repaired side by side, one process per core
    )
    return [
        repair_file(
            f, own, legos_compat=args.legos_compat, infer_defs=args.infer_defs,
            coverage=_coverage(args, f), budget=budget,
        )
        for f in files
        for own in (_file_settings(args, f, settings),)
    ]  # fmt: skip


def _file_settings(args: argparse.Namespace, path: Path, settings: Settings) -> Settings:
    """``settings`` with the clause semantics to analyse ``path`` under: ``--semantics`` when
    given, else the file's semantics block, else last-wins (:func:`clause_semantics_for`).

    UserError when ``--semantics`` contradicts the file's block, naming both: the rules were
    written for one reading and would be analysed under the other. A file that does not
    parse keeps ``settings``: the analysis reports its errors.
    """
    spec = check_file(path, legos_compat=args.legos_compat, infer_defs=args.infer_defs).spec
    if spec is None:
        return settings
    return replace(settings, semantics=clause_semantics_for(spec, args.semantics, option="--semantics"))


def _unknown_rules(given: list[tuple[str, str]], files: list[Path], legos_compat: bool) -> str:
    """A message naming a --priority rule no file declares (with the closest names), or ''."""
    if not given:
        return ""
    names: set[str] = set()
    for f in files:
        result = check_file(f, legos_compat=legos_compat)
        if result.spec is not None:
            names.update(r.name for r in result.spec.rules)
    for pair in given:
        for name in pair:
            if name not in names:
                close = difflib.get_close_matches(name, sorted(names), n=3)
                return f"--priority names rule {name[:40]!r}, which no file declares" + (
                    f" (did you mean {', '.join(close)}?)" if close else ""
                )
    return ""


def _coverage(args: argparse.Namespace, path: Path) -> Coverage | None:
    if not args.tasks and not args.mapping:
        return None
    unimplemented: tuple[str, ...] | None = None
    measures = events = None
    try:
        spec = load(path, legos_compat=args.legos_compat)
    except SleecError:
        return None  # the file's own errors are reported by the analysis
    if args.tasks:
        from cosleec.runtime import Manager, RuleSet  # the runtime is needed only to bind the tasks

        try:
            module = _import(args.tasks)
        except ImportError as e:
            raise UserError(
                f"cannot import the task module {args.tasks!r}: {e}",
                hint="give a module on the Python path (PYTHONPATH) that defines install(manager)",
            ) from None
        except (Exception, SystemExit) as e:  # the module's own code failed: say so, never a traceback
            raise UserError(
                f"the task module {args.tasks!r} failed while importing: {type(e).__name__}: {e}",
                hint="fix the module (python -c 'import MODULE' shows the traceback)",
            ) from None
        install = getattr(module, "install", None)
        if not callable(install):
            raise UserError(f"module {args.tasks!r} has no install(manager) function")
        rules = RuleSet.from_spec(spec)
        manager = Manager(rules)
        try:
            install(manager)
        except (Exception, SystemExit) as e:
            raise UserError(
                f"install(manager) of {args.tasks!r} failed: {type(e).__name__}: {e}",
                hint="fix install(); it should only bind tasks and capabilities",
            ) from None
        unimplemented = tuple(manager.implementations.missing())
    if args.mapping:
        from cosleec.nodes import Mapping
        from cosleec.runtime import RuleSet

        rules = RuleSet.from_spec(spec)
        m = Mapping.load(
            input_file(args.mapping, "the mapping", text=True),
            dict(rules.measures),
            frozenset(e.name for e in spec.events),
        )
        measures = frozenset(e.name for e in m.entries if e.kind == "measure")
        events = frozenset(e.name for e in m.entries if e.kind == "event")
    return Coverage(unimplemented, measures, events)


def _import(name: str) -> ModuleType:
    """A module by dotted name (on the Python path) or by file (``path/tasks.py``)."""
    if not name.endswith(".py"):
        return importlib.import_module(name)
    path = Path(name)
    if not path.is_file():
        raise ImportError(f"no file {name}")
    spec = importlib.util.spec_from_file_location(path.stem, path)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has a loader
        raise ImportError(f"cannot load {name}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _write_witnesses(d: Path, reports: list[FileReport]) -> None:
    try:
        d.mkdir(parents=True, exist_ok=True)
        for r in reports:
            stem = Path(r.path).stem
            for f in r.findings:
                if f.witness is not None:
                    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{stem}--{f.code}--{f.subject}") + ".jsonl"
                    (d / name).write_text(f.witness.jsonl(), encoding="utf-8")
    except OSError as e:
        raise UserError(
            f"cannot write the witnesses: {e.strerror or e}",
            where=str(d),
            hint="give a directory (it is created if missing), not a file",
        ) from None


def _json(reports: list[FileReport]) -> dict[str, object]:
    return {
        "files": [
            {
                "path": r.path,
                "ok": not r.failed,
                "diagnostics": [d.to_json() for d in r.diagnostics if d.is_error],
                "findings": [f.to_json() for f in r.findings],
                "unknown": r.unknown,
                "complete": r.complete,
                "undecided": r.undecided,
                "seconds": {k: round(v, 4) for k, v in r.seconds.items()},
            }
            for r in reports
        ]
    }


def _text(reports: list[FileReport], repaired: list[RepairReport] | None = None) -> None:
    """The reports as text; with ``repaired`` (--fix), each finding's fixes and each file's
    patch set."""
    out = console()
    for i, r in enumerate(reports):
        for d in r.diagnostics:  # the file's own errors and warnings, as `cosleec check` shows them
            if d.is_error or str(d.severity) == "warning":
                out.print(Text(d.render(r.source)))
        if r.failed:
            legos = any(d.code in LEGOS_DEFECTS for d in r.diagnostics if d.is_error)
            out.print(
                Text.assemble(
                    f"{r.path}: ",
                    ("has errors, not analysed", "bold red"),
                    " (--legos-compat reads them as LEGOS does)" if legos else "",
                )
            )
            continue
        for f in r.findings:
            lines = f.diagnostic().render(r.source).split("\n")
            sev = f" {f.severity}: "
            loc, _, msg = lines[0].partition(sev)
            out.print(Text.assemble(loc, (sev, STYLE[str(f.severity)]), (f"[{f.code}] ", "bold"), msg))
            for extra in lines[1:]:
                out.print(Text(extra))
            if f.situation:
                out.print(Text(f"    situation: {f.situation}"))
            if f.witness is not None:
                out.print(Text("    witness" + ("" if f.witness.confirmed else " (NOT confirmed by the reference "
                                                 "semantics: please report this)") + ":"))  # fmt: skip
                for line in f.witness.timeline:
                    out.print(Text(f"      {line}"))
            if repaired is not None:
                show_fixes(out, repaired[i], f)
        for u in r.unknown:
            label = "note" if "which the analysis does not model" in u else "undecided"  # a known limit
            out.print(Text.assemble(f"{r.path}: ", (label, "yellow"), f": {u}"))
        for line in _not_decided(r):
            out.print(Text.assemble(f"{r.path}: ", ("undecided", "yellow"), f": {line}"))
        if repaired is not None:
            show_patch_set(out, repaired[i])
        n = len(r.findings)
        summary = "no findings" if n == 0 else f"{n} finding{'s' if n != 1 else ''}"
        partial = "" if r.complete else ", partial: the deadline passed"
        out.print(Text(f"{r.path}: {summary}{partial} ({r.seconds.get('total', 0.0):.2f} s)"))


def _not_decided(r: FileReport, shown: int = 5) -> list[str]:
    """What the deadline left open in ``r``, one line per check that began, one for the rest."""
    lines = []
    for code, subjects in r.undecided.items():
        if subjects is not None:
            listed = [x for x in subjects if x != MORE]
            more = (
                f" and {len(listed) - shown}{'+' if MORE in subjects else ''} more"
                if len(listed) > shown
                else ""
            )
            lines.append(
                f"{code}: the deadline passed before {', '.join(listed[:shown])}{more} could be decided"
            )
    skipped = [code for code, subjects in r.undecided.items() if subjects is None]
    if skipped:
        what = "the file was not read" if not r.source else "not run"
        lines.append(f"{', '.join(skipped)}: {what}, the deadline had passed")
    return lines

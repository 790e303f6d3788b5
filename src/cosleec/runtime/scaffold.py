"""From rules to code: the Python module a developer fills in to implement a rule set.

The CO-SLEEC paper's developer implements each constrained task as a default behaviour plus
one variant per hedge. :func:`scaffold` writes that module for a rule set: per rule a
:class:`~cosleec.runtime.Task` with ``default`` and one ``@hedge(i)`` method per clause
(the layer ``R.i``), each with its clause's condition and obligations as its docstring and a
body that reports the obliged events; a ``fallback`` when the rule has ``otherwise``
responses; ``install(node)`` for a ROS task node (``--module``) or ``Manager.bind``; and an
entry point that runs it as a ROS 2 task node. The result passes the completeness check as
it is: the developer replaces each report with the robot's action, then the report.
"""

from __future__ import annotations

import json
import keyword
import re
import textwrap
from collections.abc import Iterable
from pathlib import Path

from cosleec.lang import Printer
from cosleec.lang import ast as A
from cosleec.runtime.model import CompiledRule, ItemSpec, ResponseSpec
from cosleec.runtime.ruleset import RuleSet

STYLES = ("task", "capability")


def _identifier(name: str, taken: set[str]) -> str:
    """A Python identifier for ``name`` (a rule or event), unique among ``taken``."""
    out = re.sub(r"\W", "_", name) or "rule"
    if out[0].isdigit() or keyword.iskeyword(out):
        out = f"r_{out}"
    base, n = out, 2
    while out in taken:
        out, n = f"{base}_{n}", n + 1
    taken.add(out)
    return out


def _doc(text: str, indent: str) -> str:
    """``text`` as a docstring body at ``indent`` (no triple quotes or backslashes left to break it)."""
    safe = text.replace("\\", "\\\\").replace('"""', "'''")
    lines = safe.splitlines() or [""]
    return "\n".join(f"{indent}{line}".rstrip() for line in lines)


def _str(text: str) -> str:
    """``text`` as a double-quoted Python string literal (as ruff formats them)."""
    return json.dumps(text, ensure_ascii=False)


def _docstring(text: str, indent: str, width: int = 96) -> list[str]:
    """A docstring at ``indent``: one line when it fits, else wrapped with the quotes on their own line."""
    one = f'{indent}"""{_doc(text, "")}"""'
    if len(one) <= width + 8 and "\n" not in text:
        return [one]
    wrapped = textwrap.wrap(_doc(text, ""), width - len(indent)) or [""]
    return [f'{indent}"""{wrapped[0]}', *(f"{indent}{w}" for w in wrapped[1:]), f'{indent}"""']


def _reports(spec: ResponseSpec | None, indent: str) -> list[str]:
    """The body: report each event the response obliges (prohibitions need no action)."""
    events = [it.event for it in (spec.items if spec is not None else ()) if not it.negated]
    if not events:
        return [f"{indent}pass  # nothing to do: this response only forbids, or requires nothing"]
    out = [f"{indent}# TODO: make the robot do it, then report it: obligations are judged by reports"]
    out += [f"{indent}self.event({_str(ev)})" for ev in dict.fromkeys(events)]
    return out


def _otherwise_events(spec: ResponseSpec | None, into: set[str]) -> None:
    for it in spec.items if spec is not None else ():
        _item_otherwise(it, into)
    for c in spec.clauses if spec is not None else ():
        _otherwise_events(c.response, into)


def _item_otherwise(it: ItemSpec, into: set[str]) -> None:
    if it.otherwise is not None:
        for o in it.otherwise.items:
            if not o.negated:
                into.add(o.event)
        _otherwise_events(it.otherwise, into)
    if it.alternative is not None:
        _otherwise_events(it.alternative, into)


def _rule_text(printer: Printer, rule: A.Rule) -> str:
    return printer.rule(rule).strip()


_MODULE_NAMES = frozenset(
    {"install", "TASKS", "TYPE_CHECKING", "Decision", "Task", "hedge", "main", "sys", "Manager", "TaskNode"}
)
"""The names a task-style module defines or imports: no task class may take one."""

_TASK_MEMBERS = frozenset({"default", "rule", "fallback", "event", "request", "clauses", "manager"})
"""The names a task class has already (its own and :class:`~cosleec.runtime.Task`'s): no clause
method may take one."""


def scaffold(
    rules: RuleSet,
    *,
    only: Iterable[str] | None = None,
    rules_path: str = "RULES.sleec",
    style: str = "task",
) -> str:
    """The Python module implementing ``rules`` (the names in ``only``, or every rule).

    ``style`` ``task``: one task per rule, a method per clause (the paper's style);
    ``capability``: one handler per event the rules oblige, shared by every rule that obliges
    it. ``rules_path`` is written into the module's entry point, which runs it as a ROS 2
    task node (``python module.py`` = ``cosleec ros2 task RULES --module module.py``).
    ValueError for a style that is neither, or a name in ``only`` that no rule has.
    """
    if style not in STYLES:
        raise ValueError(f"style {style!r} is not one of {', '.join(STYLES)}")
    chosen = _chosen(rules, only)
    if style == "capability":
        return _capabilities(chosen, rules_path)
    return _tasks(rules, chosen, rules_path)


def _chosen(rules: RuleSet, only: Iterable[str] | None) -> list[CompiledRule]:
    """The rules named in ``only`` (every rule when None), in file order; ValueError for a
    name no rule has."""
    wanted = set(only) if only is not None else None
    missing = sorted((wanted or set()) - {r.name for r in rules.rules})
    if missing:
        raise ValueError(f"no rule {', '.join(missing)} in these rules")
    return [r for r in rules.rules if wanted is None or r.name in wanted]


def _tasks(rules: RuleSet, chosen: list[CompiledRule], rules_path: str) -> str:
    """The task style: the module's head, a task class per rule, ``TASKS`` and ``install``."""
    printer = Printer(rules.spec, rules.spec.dialect)
    taken = set(_MODULE_NAMES)
    lines = _tasks_head(rules_path)
    classes = []
    for r in chosen:
        cls = _identifier(r.name, taken)
        classes.append(cls)
        lines += _task_class(printer, r, cls)
    lines += [
        "",
        "",
        "TASKS = [" + ", ".join(f"{c}()" for c in classes) + "]",
        "",
        "",
        "def install(node: Manager | TaskNode) -> None:",
        '    """Bind every task: a cosleec task node calls it (`--module`), or pass a Manager."""',
        "    node.bind(*TASKS)",
    ]
    return "\n".join([*lines, *_entry_point(rules_path)])


def _tasks_head(rules_path: str) -> list[str]:
    """The task-style module's docstring and imports."""
    return [
        f'"""Implementations of the rules in {Path(rules_path).name} (written by `cosleec scaffold`).',
        "",
        "Each rule is a task: `default` implements the rule's default response and each `@hedge(i)`",
        "method its clause i (the COP layer R.i). Replace each TODO with the robot's action and keep",
        "the report: deadlines are judged by the events reported, not by a method returning.",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "import sys",
        "from typing import TYPE_CHECKING",
        "",
        "from cosleec.runtime import Decision, Task, hedge",
        "",
        "if TYPE_CHECKING:",
        "    from cosleec.nodes import TaskNode",
        "    from cosleec.runtime import Manager",
    ]


def _task_class(printer: Printer, r: CompiledRule, cls: str) -> list[str]:
    """Rule ``r``'s task class ``cls``: the rule as its docstring, ``default``, a ``@hedge(i)``
    method per clause with a response, and a ``fallback`` when the rule has ``otherwise``."""
    lines = ["", "", f"class {cls}(Task):", *_docstring(_rule_text(printer, r.ast), "    ")]
    lines += ["", f"    rule = {_str(r.name)}", ""]
    lines += _method(r, None, "default")
    methods = set(_TASK_MEMBERS)
    for c in r.clauses:
        if c.response is None:
            continue  # `unless c` with no response: nothing is required, nothing to implement
        name = _identifier(f"clause_{c.index}", methods)
        lines += ["", f"    @hedge({c.index})"]
        lines += _method(r, c.index, name)
    return lines + _fallback(r)


def _fallback(r: CompiledRule) -> list[str]:
    """The ``fallback`` method of ``r``'s task (nothing when ``r`` has no ``otherwise``)."""
    fallbacks: set[str] = set()
    _otherwise_events(r.default, fallbacks)
    for c in r.clauses:
        _otherwise_events(c.response, fallbacks)
    if not fallbacks:
        return []
    return [
        "",
        "    def fallback(self, decision: Decision) -> None:",
        '        """The `otherwise` responses (a missed obligation\'s fallback): '
        + ", ".join(sorted(fallbacks))
        + '."""',
        "        # TODO: make the robot do what the fallback obliges, then report it",
        "        for ob in decision.obligations:",
        "            if not ob.negated:",
        "                self.event(ob.event)",
    ]


def _capabilities(chosen: list[CompiledRule], rules_path: str) -> str:
    """The capability style: a handler per event, with the rules and clauses that oblige it."""
    by_event: dict[str, list[str]] = {}
    for r in chosen:
        for where, spec in ((f"{r.name} default", r.default), *((c.layer, c.response) for c in r.clauses)):
            events: set[str] = set()
            for it in spec.items if spec is not None else ():
                if not it.negated:
                    events.add(it.event)
            _otherwise_events(spec, events)
            for ev in sorted(events):
                by_event.setdefault(ev, []).append(where)
    taken: set[str] = {"install", "TYPE_CHECKING", "Decision", "Obligation", "main", "sys", "node", "Manager"}
    lines = [
        f'"""Capabilities for the rules in {Path(rules_path).name} (written by `cosleec scaffold`).',
        "",
        "One handler per event the rules oblige the robot to do, shared by every rule that obliges",
        "it. Replace each TODO with the robot's action and keep the report: deadlines are judged by",
        "the events reported, not by a handler returning.",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "import sys",
        "from typing import TYPE_CHECKING",
        "",
        "from cosleec.runtime import Decision, Obligation",
        "",
        "if TYPE_CHECKING:",
        "    from cosleec.nodes import TaskNode",
        "    from cosleec.runtime import Manager",
        "",
        "",
        "def install(node: Manager | TaskNode) -> None:",
        '    """Register every capability: a cosleec task node calls it (`--module`), or pass a Manager."""',
    ]
    for ev, obliging in sorted(by_event.items()):
        fn = _identifier(f"do_{ev}", taken)
        lines += [
            "",
            f"    @node.capability({_str(ev)})",
            f"    def {fn}(obligation: Obligation, decision: Decision) -> None:",
            *_docstring(f"{ev}: obliged by {', '.join(obliging)}.", "        "),
            "        # TODO: make the robot do it, then report it: obligations are judged by reports",
            f"        node.event({_str(ev)})",
        ]
    if not by_event:
        lines += ["    pass  # these rules oblige no action (only prohibitions)"]
    return "\n".join([*lines, *_entry_point(rules_path)])


def _entry_point(rules_path: str) -> list[str]:
    """The module's end: run as a script, it is a ROS 2 task node of these rules."""
    return [
        "",
        "",
        'if __name__ == "__main__":  # run as a ROS 2 task node of these rules',
        "    from cosleec.cli.main import main",
        "",
        f"    rules = {_str(rules_path)}",
        '    sys.exit(main(["ros2", "task", rules, "--module", __file__, *sys.argv[1:]]))',
        "",
    ]


def _method(r: CompiledRule, clause: int | None, name: str) -> list[str]:
    """A task method: the default response (``clause`` None) or clause ``clause``'s."""
    spec: ResponseSpec | None
    if clause is None:
        spec, what = r.default, f"{r.name}, the default response (no layer)"
    else:
        c = r.clauses[clause - 1]
        spec, what = c.response, f"{c.layer}: unless {c.text}"
    head = f"    def {name}(self, decision: Decision) -> None:"
    items = spec.items if spec is not None else ()
    obliged = "; ".join(_item(it) for it in items) or "nothing is required"
    return [head, *_docstring(f"{what}: {obliged}.", "        "), *_reports(spec, "        ")]


def _item(it: ItemSpec) -> str:
    what = f"not {it.event}" if it.negated else it.event
    return what + (" (otherwise a fallback)" if it.otherwise is not None else "")

"""Explanations for people: the sentences a rule's author (or a translator) gives each case of a rule.

An ``ExplainWhy`` obligation makes a robot explain itself to the person in front of it,
who has never read the rules. The author writes what the robot says, beside the rules, in
a YAML file (one per language if they like)::

    R1:
      default: Here is your medication information.
      1: "I can't share this, {requesterName}: only the patient or a nurse may hear it."
      otherwise: I could not reach a nurse in time, so I am raising the alarm.
    R2: I won't record video in your room without your consent.   # every case of R2

Under a rule: ``default`` (its own response), the clause numbers ``1..n`` (clause i is
layer ``R.i``), ``otherwise`` (what it does when an obligation is missed); a sentence
alone is said in every case. ``{name}`` is the value of measure ``name`` when the rule
decided (:func:`~cosleec.runtime.plain.value_words`: ``yes``/``no``, numbers as written,
``unknown``). :meth:`Explanations.check` holds the file to the rules when the Manager is
built, so a typo is an :class:`ExplanationsError` at ``file:line:col`` with the fix, not
a robot that silently says the generated sentence.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from cosleec.errors import UserError, closest, show
from cosleec.runtime.model import CompiledRule
from cosleec.runtime.ruleset import RuleSet

__all__ = ["EVERY_CASE", "Explanations", "ExplanationsError"]

EVERY_CASE = "*"
"""The case of a sentence given alone for a rule (``R2: ...``): said in every case of it."""

PLACEHOLDER = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")
"""``{name}`` in a sentence: the value of measure ``name``."""


class ExplanationsError(UserError):
    """An explanations file the rules do not fit: the message starts with ``file:line:col``,
    the hint says the fix."""


@dataclass(frozen=True)
class Sentence:
    """One sentence of the file: for ``case`` of ``rule``, written at ``where`` (``file:line:col``);
    its rule's name is written at ``rule_at``, its case's at ``case_at``."""

    rule: str
    case: str  # EVERY_CASE, "default", "otherwise" or a clause number ("1")
    text: str
    where: str
    rule_at: str = ""
    case_at: str = ""


class Explanations:
    """The sentences for people of one rule set, by rule and case (see the module docstring).

    Build it with :meth:`load` (a file), :meth:`parse` (YAML text) or :meth:`of` (a mapping
    already read); the Manager checks it against its rules (:meth:`check`) and hands it
    to every decision (:attr:`Decision.for_people <cosleec.runtime.decision.Decision.for_people>`).
    """

    def __init__(self, sentences: list[Sentence], source: str) -> None:
        self.source = source
        self.sentences = sentences
        self._by: dict[tuple[str, str], str] = {(s.rule, s.case): s.text for s in sentences}

    @classmethod
    def load(cls, path: str | Path) -> Explanations:
        """The explanations file at ``path``; ExplanationsError when it cannot be read or is not one."""
        try:
            text = Path(path).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            why = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
            raise ExplanationsError(
                f"{path}: cannot read the explanations file: {why}",
                hint="give the path of a YAML file of sentences (relative paths are from the current directory)",
            ) from None
        return cls.parse(text, str(path))

    @classmethod
    def parse(cls, text: str, source: str = "<explanations>") -> Explanations:
        """The explanations in YAML ``text``, ``source`` naming it in errors."""
        loader = yaml.SafeLoader(text)
        try:
            root = loader.get_single_node()
            return cls(list(_sentences(loader, root, source)), source)
        except yaml.MarkedYAMLError as e:
            mark = e.problem_mark or e.context_mark
            what = "; ".join(str(x) for x in (e.context, e.problem) if x)
            raise ExplanationsError(
                f"{_at(source, mark)}: not valid YAML: {what}",
                hint='quote a sentence that holds a colon followed by a space: R1: "I can\'t: ..."',
            ) from None
        except yaml.YAMLError as e:
            raise ExplanationsError(
                f"{source}: not valid YAML: {e}", hint="check the file's syntax"
            ) from None
        finally:
            loader.dispose()

    @classmethod
    def of(cls, given: Mapping[str, Any], source: str = "<explanations>") -> Explanations:
        """The explanations in a mapping already read (the shape of the file)."""
        return cls.parse(yaml.safe_dump(dict(given), allow_unicode=True, sort_keys=False), source)

    def sentence(self, rule: str, case: str) -> str | None:
        """The author's sentence for ``case`` of ``rule`` (its own, else the rule's sentence
        for every case), unfilled; None when the file gives none."""
        return self._by.get((rule, case)) or self._by.get((rule, EVERY_CASE))

    def reads(self, rule: str) -> tuple[str, ...]:
        """The measures the sentences of ``rule`` name (``{name}``), sorted: a decision of the
        rule keeps their values, to fill them in."""
        return tuple(
            sorted({n for s in self.sentences if s.rule == rule for n in PLACEHOLDER.findall(s.text)})
        )

    def check(self, rules: RuleSet) -> Explanations:
        """Returns ``self`` when every sentence fits the rules; else ExplanationsError naming
        each sentence that does not, at its ``file:line:col``, with its fix (all of them in
        one error: a translator fixes the file in one pass): an unknown rule, a clause the
        rule does not have, ``otherwise`` for a rule without one, an unknown measure in
        ``{...}``."""
        found = [e for s in self.sentences for e in _misfits(s, rules)]
        if len(found) == 1:
            raise found[0]
        if found:
            listed = "\n".join(f"  {e.message}\n    hint: {e.hint}" for e in found)
            raise ExplanationsError(
                f"{len(found)} sentences of {self.source} do not fit the rules:\n{listed}",
                hint="fix each one at its file:line:col",
            )
        return self


def _misfits(s: Sentence, rules: RuleSet) -> list[ExplanationsError]:
    """What is wrong with sentence ``s`` against ``rules`` (nothing: an empty list)."""
    rule = rules.by_name.get(s.rule)
    if rule is None:
        near = closest(s.rule, rules.by_name)
        return [
            ExplanationsError(
                f"{s.rule_at}: {show(s.rule)} is not a rule of the rules",
                hint=f"did you mean {near}?" if near else f"the rules are {_names(rules.by_name)}",
            )
        ]
    out: list[ExplanationsError] = []
    try:
        _check_case(s, rule)
    except ExplanationsError as e:
        out.append(e)
    for name in PLACEHOLDER.findall(s.text):
        if name not in rules.measures:
            near = closest(name, rules.measures)
            out.append(
                ExplanationsError(
                    f"{s.where}: {{{name}}} is not a measure the rules declare",
                    hint=f"did you mean {{{near}}}?"
                    if near
                    else "write {NAME} with NAME a measure of the def block, or {{ for a brace",
                )
            )
    return out


def _check_case(s: Sentence, rule: CompiledRule) -> None:
    """ExplanationsError unless ``s.case`` is a case ``rule`` has."""
    n = len(rule.clauses)
    if s.case.isdigit():
        if not 1 <= int(s.case) <= n:
            has = f"clauses 1 to {n}" if n > 1 else "one clause (1)" if n == 1 else "no unless clause"
            raise ExplanationsError(
                f"{s.case_at}: {rule.name} has no clause {s.case}: it has {has}",
                hint=f"clause i is the i-th `unless` of the rule (layer {rule.name}.i)",
            )
    elif s.case == "otherwise" and not any(
        it.otherwise is not None for r in rule.responses() for it in r.walk()
    ):
        raise ExplanationsError(
            f"{s.case_at}: {rule.name} has no `otherwise`: this sentence would never be said",
            hint="remove it, or give the rule an `otherwise` (A within 5 minutes otherwise B)",
        )


_CASES = ("default", "otherwise")


def _sentences(loader: yaml.SafeLoader, root: yaml.Node | None, source: str) -> Iterator[Sentence]:
    """Every sentence of the document ``root`` (None: an empty file), with where it is written."""
    if root is None:
        return
    if not isinstance(root, yaml.MappingNode):
        raise ExplanationsError(
            f"{_at(source, root.start_mark)}: an explanations file maps rule names to sentences",
            hint="write `R1: I will ...` or `R1:` followed by `default:`, `1:`, `otherwise:` lines",
        )
    seen: set[str] = set()
    for key, value in root.value:
        rule = _key(loader, key, source, seen)
        rule_at = _at(source, key.start_mark)
        if isinstance(value, yaml.MappingNode):
            cases: set[str] = set()
            for k, v in value.value:
                case = _key(loader, k, source, cases)
                if not (case.isdigit() or case in _CASES):
                    near = closest(case, _CASES)
                    raise ExplanationsError(
                        f"{_at(source, k.start_mark)}: {show(case)} is not a case of a rule",
                        hint=(f"did you mean {near}? " if near else "")
                        + "the cases are default, the clause numbers 1, 2, ... and otherwise",
                    )
                text = _text(loader, v, source)
                yield Sentence(
                    rule, case, text, _at(source, v.start_mark), rule_at, _at(source, k.start_mark)
                )
        else:
            text = _text(loader, value, source)
            yield Sentence(rule, EVERY_CASE, text, _at(source, value.start_mark), rule_at, rule_at)


def _key(loader: yaml.SafeLoader, node: yaml.Node, source: str, seen: set[str]) -> str:
    """A rule name or a case, as text (``1:`` is clause 1); ExplanationsError when given twice."""
    value = loader.construct_object(node, deep=True) if isinstance(node, yaml.ScalarNode) else None
    if value is None or isinstance(value, bool | float) or not isinstance(value, str | int):
        raise ExplanationsError(
            f"{_at(source, node.start_mark)}: {show(value)} names no rule and no case",
            hint="keys are rule names (R1), and under a rule: default, a clause number, otherwise",
        )
    key = str(value)
    if key in seen:
        raise ExplanationsError(
            f"{_at(source, node.start_mark)}: {key} is given twice (the second would replace the first)",
            hint="keep one of them",
        )
    seen.add(key)
    return key


def _text(loader: yaml.SafeLoader, node: yaml.Node, source: str) -> str:
    """A sentence: a non-empty string; ExplanationsError for anything else (a number, a list, yes/no)."""
    value = loader.construct_object(node, deep=True) if isinstance(node, yaml.ScalarNode) else None
    if not isinstance(value, str) or not value.strip():
        got = "a list or mapping" if not isinstance(node, yaml.ScalarNode) else show(value)
        raise ExplanationsError(
            f"{_at(source, node.start_mark)}: a sentence must be text, not {got}",
            hint='write the sentence in quotes: "..." (yes, no, numbers and an empty value are not text in YAML)',
        )
    return value.strip()


def _at(source: str, mark: yaml.Mark | None) -> str:
    return f"{source}:{mark.line + 1}:{mark.column + 1}" if mark is not None else source


def _names(names: Mapping[str, object]) -> str:
    shown = sorted(names)[:10]
    return ", ".join(shown) + (f" ... ({len(names)} in all)" if len(names) > len(shown) else "")

"""Build one piece of the runtime from a :class:`~cosleec.runtime.core.Core`, never a Manager.

The parts' tests share this: a core on a :class:`VirtualClock` for a few SLEEC rules, the
records its steps deliver, and the two steps a Manager takes around every piece -- values
applied, an event's rules decided and put in force -- written as plainly as the façade
writes them (``Manager.update``, ``Manager._occur``), so that each test drives the piece
it tests and nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosleec.records import Kind, RuntimeEvent
from cosleec.runtime.clock import VirtualClock
from cosleec.runtime.context import Context
from cosleec.runtime.core import Core
from cosleec.runtime.enforcer import Enforcer
from cosleec.runtime.gate import Gate
from cosleec.runtime.jobs import Job
from cosleec.runtime.journal import Journal
from cosleec.runtime.permission import Answers
from cosleec.runtime.priorities import Priorities
from cosleec.runtime.restore import open_journal
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.steps import Step

DEFS = (
    "def_start event E event F event G event Rec event Help "
    "measure a : boolean measure b : boolean measure n : numeric measure s : scale(low, high) "
)


def ruleset(rules: str, defs: str = "", base: str = DEFS) -> RuleSet:
    """The rule set of ``rules`` (rule_start ... rule_end) over ``base`` (:data:`DEFS`) and ``defs``."""
    return RuleSet.from_text(f"{base}{defs} def_end rule_start {rules} rule_end")


def prioritised(rules: RuleSet, *pairs: str, semantics: str = "cancel", lead: float = 0.0) -> Priorities:
    """The priorities ``pairs`` (``"R1 > R2"``) between ``rules``' rules."""
    return Priorities.build((r.name for r in rules.rules), pairs, semantics, lead)


@dataclass
class Parts:
    """A core and the pieces a step of the Manager drives on it."""

    core: Core
    clock: VirtualClock
    answers: Answers
    gate: Gate
    enforcer: Enforcer
    heard: list[RuntimeEvent]

    def kinds(self) -> list[str]:
        """The kinds of the records heard so far, in order."""
        return [str(ev.kind) for ev in self.heard]

    def of(self, kind: Kind) -> list[dict[str, Any]]:
        """The data of the records of ``kind`` heard so far."""
        return [ev.data for ev in self.heard if ev.kind == kind]

    def update(self, **values: object) -> None:
        """Apply ``values`` in a step of their own (what ``Manager.update`` does, without its checks)."""
        core = self.core
        with core.steps.step() as step:
            core.apply(core.context.validate(values), step)

    def trigger(self, event: str, step: Step) -> list[Job]:
        """(In ``step``.) ``event`` occurs: what it meets, then its rules decide and their
        decisions are put in force. Returns the jobs of the decisions that run something (an
        undetermined one runs nothing), then the ``otherwise`` fallbacks started."""
        core, now = self.core, step.now
        seq = core.steps.count("seq")
        followups = self.enforcer.occur(event, now, seq, step)
        _, jobs, more = self.enforcer.trigger(event, now, seq, step)
        return jobs + followups + more

    def fire(self, event: str) -> list[Job]:
        """:meth:`trigger` in a step of its own."""
        with self.core.steps.step() as step:
            return self.trigger(event, step)


def parts(
    rules: str,
    defs: str = "",
    *,
    priorities: tuple[str, ...] = (),
    semantics: str = "cancel",
    lead: float = 0.0,
    listen: bool = True,
    max_age: dict[str, float] | None = None,
    base: str = DEFS,
    **build: Any,
) -> Parts:
    """A core for ``rules`` (see :func:`ruleset`) on a VirtualClock at 0, with its answers, gate
    and enforcer; ``listen`` subscribes a list to its records (so that its steps record);
    ``max_age`` ages measures (put in force as a reload puts a new context)."""
    rs = ruleset(rules, defs, base)
    clock = VirtualClock()
    core = Core.build(
        rs, clock=clock, priorities=prioritised(rs, *priorities, semantics=semantics, lead=lead), **build
    )
    if max_age is not None:
        core.max_age = dict(max_age)
        core.install(rs, Context(rs.measures, max_age), core.layers, core.priorities, core.implementations)
    answers = Answers(core)
    gate = Gate(core, answers)
    heard: list[RuntimeEvent] = []
    if listen:
        core.steps.subscribe(heard.append)
    return Parts(core, clock, answers, gate, Enforcer(core), heard)


def journaled(p: Parts, path: Path) -> Journal:
    """Give ``p``'s core the journal at ``path``, wired and restored as the Manager does it."""
    journal = Journal(path)
    steps = p.core.steps
    steps.journal = journal
    steps.meta, steps.before_commit = p.core.meta, p.gate.before_commit
    open_journal(p.core, p.gate, p.enforcer, reset=False)
    return journal

"""What is in force while the reference semantics walks a trace, indexed for its questions.

:mod:`cosleec.semantics.reference` asks, at every step, which obligations and prohibitions
an occurrence of an event can settle, which windows have closed, and -- for conflicts and
priorities -- which items of an event, of an instance or of a rule are in force. Scanning
every item in force to answer them made a trace that leaves obligations pending (an
untimed response the robot never gives) take time quadratic in its length: minutes for a
1M-line trace (issue 28). :class:`InForce` answers each from an index instead: by event
(obligations, prohibitions, and ``else`` alternatives by the events they wait for), by
instance and rule, and by deadline (a heap). An item settles by its verdict's status
changing, wherever that happens; each index drops settled items when it is next read, so
a step costs what it touches, and every answer lists items in creation order, as a scan
of them all would. Imports only the AST and the verdict records.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable
from dataclasses import dataclass, field

from cosleec.lang import ast as A
from cosleec.semantics.verdicts import PENDING, Verdict


@dataclass(eq=False)
class Item:
    """An obligation or prohibition in force: its verdict plus what the judge needs."""

    v: Verdict
    created: int  # causal position: occurrences after it count
    otherwise: A.Response | None
    branches: list[list[tuple[str, float, float | None]]] = field(default_factory=list)
    met: list[set[int]] = field(default_factory=list)

    @property
    def deadline(self) -> float | None:
        """When the item is judged if nothing settles it first (None: never)."""
        his: list[float | None] = [self.v.window[1]]
        for b in self.branches:
            his += [hi for _, _, hi in b]
        return None if any(h is None for h in his) else max(h for h in his if h is not None)

    @property
    def pending(self) -> bool:
        """Still in force."""
        return self.v.status == PENDING


class InForce:
    """The items in force (see the module docstring); :meth:`add` each once its verdict has
    its id, instance and rule."""

    def __init__(self) -> None:
        self.owed: dict[str, list[Item]] = {}  # obligations, by event
        self.banned: dict[str, list[Item]] = {}  # prohibitions, by event
        self.waiting: dict[str, list[Item]] = {}  # obligations with an `else`, by the events it names
        self.instances: dict[int, list[Item]] = {}
        self.rules: dict[str, dict[int, None]] = {}  # rule -> its instances with items (maybe settled)
        self.deadlines: list[tuple[float, int, Item]] = []  # a heap

    def add(self, item: Item) -> None:
        """Put ``item`` in force."""
        v = item.v
        (self.banned if v.negated else self.owed).setdefault(v.event, []).append(item)
        if item.branches:
            for event in dict.fromkeys(ev for b in item.branches for ev, _, _ in b):
                self.waiting.setdefault(event, []).append(item)
        self.instances.setdefault(v.instance, []).append(item)
        self.rules.setdefault(v.rule, {})[v.instance] = None
        d = item.deadline
        if d is not None:
            heapq.heappush(self.deadlines, (d, v.id, item))

    def of_event(self, event: str, negated: bool) -> list[Item]:
        """The prohibitions (``negated``) or obligations of ``event`` in force."""
        return _pending((self.banned if negated else self.owed).get(event))

    def touched_by(self, event: str) -> list[Item]:
        """The items an occurrence of ``event`` can settle: its obligations and prohibitions,
        and the obligations whose ``else`` waits for it."""
        found = {i.v.id: i for i in (*self.of_event(event, False), *self.of_event(event, True))}
        found.update((i.v.id, i) for i in _pending(self.waiting.get(event)))
        return [found[k] for k in sorted(found)]

    def of_instance(self, instance: int) -> list[Item]:
        """The items of one firing (its ``otherwise`` chain included) in force."""
        items = _pending(self.instances.get(instance))
        if not items:
            self.instances.pop(instance, None)
        return items

    def active(self, rules: Iterable[str]) -> list[int]:
        """The instances of ``rules`` with an item in force, in order."""
        out = []
        for rule in rules:
            known = self.rules.get(rule, {})
            for instance in list(known):
                if self.of_instance(instance):
                    out.append(instance)
                else:
                    del known[instance]
        return sorted(out)

    def events(self) -> list[str]:
        """The events some obligation and some prohibition in force both name."""
        return [
            e for e in self.owed if e in self.banned and self.of_event(e, True) and self.of_event(e, False)
        ]

    def next_deadline(self, before: float) -> float | None:
        """The earliest deadline of an item in force, if it is earlier than ``before``."""
        heap = self.deadlines
        while heap and not heap[0][2].pending:
            heapq.heappop(heap)
        return heap[0][0] if heap and heap[0][0] < before else None

    def due(self, d: float) -> list[Item]:
        """The items in force whose deadline is ``d`` (the earliest), taken off the heap."""
        heap, out = self.deadlines, []
        while heap and heap[0][0] == d:
            item = heapq.heappop(heap)[2]
            if item.pending:
                out.append(item)
        return out


def _pending(items: list[Item] | None) -> list[Item]:
    """The items of ``items`` still in force (the settled ones are dropped from it)."""
    if not items:
        return []
    items[:] = [i for i in items if i.pending]
    return list(items)

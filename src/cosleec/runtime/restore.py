"""Restore: a runtime started on a journal takes back what was committed, or refuses.

:func:`open_journal` proves the journal first (:func:`~cosleec.runtime.journal.verify`,
against the audit log): one that lost commits is refused -- or, with ``reset_journal``,
emptied, and what was lost recorded (``journal-reset``). Then :class:`Restore` takes back,
in one step: the counters (ids are never reused), the audit log's uncommitted tail (set
aside, an ``uncommitted`` record), the clock (virtual time goes on; a monotonic clock that
started again shifts saved times, each reading the stricter one), the context, the
obligations and prohibitions in force (relinked to the rules now, or ``dropped``), and the
outbox: held decisions are held again, a decision perhaps never run is recorded
``task-interrupted`` and not run again, one perhaps never published is published again.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

from cosleec.lang import CANCEL
from cosleec.records import Kind
from cosleec.runtime.clock import VirtualClock, boot
from cosleec.runtime.core import Core
from cosleec.runtime.enforcer import Enforcer
from cosleec.runtime.errors import ConfigurationError, ContextError
from cosleec.runtime.gate import Gate
from cosleec.runtime.journal import JournalError, Saved, lost, verify
from cosleec.runtime.obligations import PENDING, Tracked
from cosleec.runtime.reload import item_of
from cosleec.runtime.steps import Step


def open_journal(core: Core, gate: Gate, enforcer: Enforcer, *, reset: bool) -> None:
    """Restore what ``core``'s journal holds, once it is known to be all that was committed: a
    journal that lost commits is refused -- or, with ``reset``, emptied, and what was lost
    recorded (``journal-reset``) before this runtime starts a lineage of its own."""
    steps = core.steps
    journal, audit = steps.journal, steps.audit
    assert journal is not None
    try:
        saved = journal.load()
        doubt = verify(journal, saved, audit)
    except JournalError as e:  # damaged: nothing can be restored
        saved, doubt = None, e.reason or str(e)
    if doubt is None and reset:
        raise ConfigurationError(
            "reset_journal=True, but the journal holds all that was committed: there is nothing to reset",
            hint="start without reset_journal (it is for a journal the Manager refused, once)",
        )
    if doubt is not None and not reset:
        raise journal.refusal(doubt, audit)
    held = None if doubt is None else lost(journal.reset(), audit, doubt)
    journal.start()
    if saved is None or held is not None:
        with steps.step() as step:
            if held is not None:
                step.emit(Kind.JOURNAL_RESET, held)
            step.emit(Kind.RESTORED, {"from": None, "lineage": steps.lineage, "rules_changed": False})
        return
    steps.lineage = saved.lineage or saved.run
    with steps.step() as step:
        Restore(core, gate, enforcer, saved, step).run()


class Restore:
    """Takes back what ``saved`` holds, in ``step`` (see the module docstring)."""

    def __init__(self, core: Core, gate: Gate, enforcer: Enforcer, saved: Saved, step: Step) -> None:
        self.core = core
        self.gate = gate
        self.enforcer = enforcer
        self.saved = saved
        self.step = step
        self.dropped: list[str] = []
        self.shift = 0.0  # saved obligation times -> this clock's (a reboot)
        self.hold = 0.0  # saved prohibition times -> this clock's
        self.kept = 0  # obligations and prohibitions restored pending

    def run(self) -> None:
        """Restore everything, in order, each with its record."""
        uncommitted = self._counters()
        self._clock()
        values = self._context()
        restored = self._obligations()
        for rec in self.saved.outbox:
            self._outbox(rec)
        self._records(uncommitted, values)
        if self.core.journal:  # what was dropped leaves the journal in this same step
            self._forget(values, restored)
        prio = self.core.priorities
        if prio.above and prio.semantics == CANCEL:
            # priorities declared since (or changed): activations restored together meet now
            self.enforcer.meet(restored, self.core.steps.clock.now(), self.step)

    def _counters(self) -> list[dict[str, Any]]:
        """Ids go on; the audit log's records past the committed end are set aside (returned)."""
        steps, saved, step = self.core.steps, self.saved, self.step
        c = saved.counters
        for name in ("decision", "seq", "record"):
            steps.counters[name] = max(steps.counters[name], c.get(name, 1))
        audit = steps.audit
        if audit is None or saved.audit is None:
            return []
        steps.counters["record"] = c.get("record", 1)  # the journal's count: seq goes on without a gap
        if audit.size > saved.audit:  # written for a step whose commit never happened
            try:
                return audit.cut(saved.audit)
            except ValueError as e:  # not where the journal says: edited by hand, or another log
                step.emit(Kind.AUDIT_MISMATCH, {"reason": f"{e}; nothing was set aside"})
        elif audit.size < saved.audit:
            step.emit(
                Kind.AUDIT_MISMATCH,
                {
                    "reason": f"the audit log is {saved.audit - audit.size} bytes shorter than "
                    "the journal committed: it was changed outside cosleec"
                },
            )
        return []

    def _clock(self) -> None:
        """Refuse another kind of clock; go on from virtual time; shift after a reboot."""
        steps, saved = self.core.steps, self.saved
        clock = steps.clock
        kind = type(clock).__name__
        if saved.clock_kind and saved.clock_kind != kind:
            raise JournalError(
                f"the journal was written on a {saved.clock_kind} and this Manager runs on a {kind}: "
                "every saved window would be misread",
                where=str(steps.journal.path) if steps.journal is not None else "",
                hint="restart with the same kind of clock, or give a new journal",
            )
        now = clock.now()
        if isinstance(clock, VirtualClock) and now < saved.clock:
            clock.set(saved.clock)  # virtual (simulated) time goes on from where it stopped
            now = self.step.now = saved.clock
        # a monotonic clock that started again (a reboot): shift saved clock times. How long
        # the Manager was down is known only from the wall clock, which may be wrong: each
        # reading is the stricter one -- obligations as if all that time passed (deadlines
        # due sooner), prohibitions as if none did (still in force)
        down = max(0.0, time.time() - saved.wall)
        restarted = not isinstance(clock, VirtualClock) and (
            now < saved.clock or (bool(saved.boot) and saved.boot != boot())
        )
        self.shift = now - down - saved.clock if restarted else 0.0
        self.hold = now - saved.clock if restarted else 0.0

    def _context(self) -> dict[str, Any]:
        """The saved values the rules still declare and accept (the others dropped)."""
        core, saved = self.core, self.saved
        context = core.context
        values: dict[str, Any] = {}
        for name, (value, stamp) in saved.context.items():
            if name not in context.measures:
                self.dropped.append(f"measure {name}: the rules no longer declare it")
                continue
            try:
                values[name] = context.validate({name: value})[name]
            except ContextError as e:
                self.dropped.append(f"measure {name}: {e}")
                continue
            context.stamps[name] = stamp + self.shift
        context.values.update(values)
        c = saved.counters
        context.version = max(c.get("version", 0), 1 if values else 0)
        core.layers.version = max(core.layers.version, c.get("layers", 0))
        core.layers.update(set(values), context.values)
        return values

    def _obligations(self) -> list[Tracked]:
        """The saved obligations the rules still have, relinked and shifted; resumed or missed."""
        tracker, c = self.core.tracker, self.saved.counters
        restored: list[Tracked] = []
        for rec in self.saved.obligations:
            t = Tracked.from_json(rec)
            item = item_of(t, self.core.ruleset)
            if item is None:
                self.dropped.append(
                    f"obligation {t.id} ({t.rule}: {t.obligation.describe()}): the rules no longer have it"
                )
                continue
            t.obligation = dataclasses.replace(t.obligation, otherwise=item.otherwise, item=item.key)
            d = self.hold if t.prohibition else self.shift
            if d:  # the whole window into this boot's clock
                t.shift(d)
                # and kept so in the journal, with this step's new clock and boot: a restart in
                # this boot (no shift then) must find the windows this boot's clock reads
                self.step.change.obligations[t.id] = t.to_json()
            restored.append(t)
            if t.status == PENDING:
                tracker.resume(t, c.get("obligation", 1))
                self.kept += 1
            else:  # missed: its late event is still reported, once
                tracker.missed(t)
        # obligation ids go on even when nothing was pending (resume sees only what it restores)
        tracker.resume_ids(c.get("obligation", 1))
        for gone in tracker.forgotten:
            self.step.change.obligations[gone] = None
        tracker.forgotten.clear()
        return restored

    def _outbox(self, rec: dict[str, Any]) -> None:
        """One outbox entry: held again, published again, or recorded ``task-interrupted``."""
        gate, step = self.gate, self.step
        local = self.core.dispatch
        held = bool(rec.get("held")) and gate.rehold(rec)
        if held and not rec.get("running"):
            return  # still waiting to be allowed: it runs (once) when it is
        if not local and rec.get("running") and isinstance(rec.get("record"), dict):
            gate.republish(rec, held, step)  # a part perhaps never published: published again
            return
        if not held and not local and isinstance(rec.get("record"), dict):
            gate.undelivered.append(rec["record"])  # the Manager node publishes it again
            return
        # decided (a part of it handed on), but perhaps never run: recorded, not run again
        step.emit(
            Kind.TASK_INTERRUPTED,
            {
                **{k: rec[k] for k in ("decision", "rule", "event") if k in rec},
                "reason": "the Manager stopped before it was known to have run",
            },
        )
        if held:  # the rest still waits to be allowed; what was handed on is not run again
            gate.keep_held(gate.held[int(rec["decision"])], step)
        else:
            step.change.outbox[int(rec["decision"])] = None

    def _records(self, uncommitted: list[dict[str, Any]], values: dict[str, Any]) -> None:
        """The ``uncommitted``, ``dropped`` and ``restored`` records."""
        step, saved, audit = self.step, self.saved, self.core.steps.audit
        if uncommitted:
            step.emit(
                Kind.UNCOMMITTED,
                {
                    "records": len(uncommitted),
                    "first": uncommitted[0].get("seq"),
                    "last": uncommitted[-1].get("seq"),
                    "to": f"{audit.path.name}.uncommitted" if audit is not None else None,
                },
            )
        for what in self.dropped:
            step.emit(Kind.DROPPED, {"what": what})
        step.emit(
            Kind.RESTORED,
            {
                "from": saved.run,
                "lineage": self.core.steps.lineage,
                "rules_changed": saved.rules != self.core.ruleset.digest,
                "context": sorted(values),
                "obligations": self.kept,
                "dropped": len(self.dropped),
                "interrupted": len(saved.outbox),
                "shift": self.shift,
            },
        )

    def _forget(self, values: dict[str, Any], restored: list[Tracked]) -> None:
        """What was not restored leaves the journal."""
        change = self.step.change
        for name in self.saved.context:
            if name not in values:
                change.context[name] = None
        kept_ids = {t.id for t in restored}
        for rec in self.saved.obligations:
            if int(rec["id"]) not in kept_ids:
                change.obligations[int(rec["id"])] = None

"""The enforcer: obligations and prohibitions begin, meet events, fall due, and meet each other.

It follows the reference semantics' order within a step: a decision's items begin (windows
that close before they open are judged at once); a cancellation-based priority settles a
new activation against those in force; a new prohibition meets the obligations in force,
and a new obligation the prohibitions (a *conflict*, resolved by priority or won by the
prohibition: :mod:`cosleec.runtime.priorities`). As time passes, deadlines fall due one at
a time -- each ``otherwise`` is in force before a later deadline is judged -- and a
conflict-aware priority cancels the lower rule at the deadline that forces it.

Every change is recorded in the step it is given (``obligation``, ``conflict``,
``cancelled`` records); the ``otherwise`` decisions it starts are returned as jobs for the
dispatch (:mod:`cosleec.runtime.gate`).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable

from cosleec.lang import CANCEL, CONFLICT_AWARE
from cosleec.records import Kind
from cosleec.runtime.core import Core
from cosleec.runtime.decision import Decision
from cosleec.runtime.jobs import Job
from cosleec.runtime.model import Obligation
from cosleec.runtime.obligations import BLOCKED, CANCELLED, PENDING, Outcome, Tracked
from cosleec.runtime.plain import duration
from cosleec.runtime.priorities import covers, forced
from cosleec.runtime.steps import Step

log = logging.getLogger("cosleec.runtime")


class Enforcer:
    """Puts decisions in force and judges what they meet, on ``core`` (see the module docstring)."""

    def __init__(self, core: Core) -> None:
        self.core = core
        self._cut: tuple[int, tuple[float, Tracked, str] | None] | None = None  # (tracker version, forced())

    def reset(self) -> None:
        """Forget what conflict-aware priorities force (a reload: found again for the new priorities)."""
        self._cut = None

    def occur(self, name: str, now: float, seq: int, step: Step) -> list[Job]:
        """Event ``name`` occurred at ``now``: what it fulfils or violates; the fallbacks it starts."""
        return self.settle(self.core.tracker.occur(name, now, seq), now, seq, step)

    def trigger(
        self, name: str, now: float, seq: int, step: Step
    ) -> tuple[list[Decision], list[Job], list[Job]]:
        """The rules ``name`` triggers decide (a rule whose condition is false does not), each
        decision is recorded and put in force. Returns the decisions, the jobs of those that run
        something (an undetermined one runs nothing), and the ``otherwise`` fallbacks started."""
        core = self.core
        decisions: list[Decision] = []
        jobs: list[Job] = []
        followups: list[Job] = []
        for rule in core.ruleset.by_trigger.get(name, ()):
            d = core.decider.decide(rule, name, now)
            if d is None:
                continue
            # the rule's composition at this trigger: the dispatch runs under it, whatever the
            # context does in the meantime
            composition = core.layers.composition_of(rule) if d.clause is not None else None
            decisions.append(d)
            rec = core.record(d, step, queue=composition is not None)
            job = Job(rule, d, composition, [], rec, core.implementations)
            followups += self.begin(job, d.obligations, now, seq, 0, d.id, step)
            if composition is not None:
                jobs.append(job)
        return decisions, jobs, followups

    def advance(self, now: float, step: Step, limit: int | None = None) -> list[Job]:
        """Every deadline due up to ``now``, in time order: conflict-aware cancellations (at
        times <= now) and closing windows (deadlines < now), one deadline at a time so that
        each ``otherwise`` is in force before a later deadline is judged. With ``limit``, at
        most that many judged (``step.more`` says whether more are due)."""
        core = self.core
        tracker = core.tracker
        followups: list[Job] = []
        judged = 0
        aware = core.aware
        while True:
            cut = self.forced() if aware else None
            if cut is not None and cut[0] <= now:
                nd = tracker.next_deadline()
                if nd is None or not nd < now or cut[0] <= nd:
                    at, victim, by = cut
                    if not self.cancel(victim.instance, at, by, step, "conflict-aware"):
                        log.error("conflict-aware cancellation of %s found nothing in force", victim.rule)
                        break  # a bug must not hang the Manager: judge the rest at the next step
                    continue
            out = tracker.due(now, None if limit is None else limit - judged)
            if not out.changed:
                break
            judged += len(out.changed)
            followups += self.settle(out, now, core.steps.count("seq"), step)
            if limit is not None and judged >= limit:
                step.more = True
                break
        return followups

    def settle(self, out: Outcome, now: float, seq: int, step: Step) -> list[Job]:
        """Record what ``out`` changed and start the ``otherwise`` of each miss, in order."""
        core = self.core
        followups: list[Job] = []
        for t in out.progressed:  # (an `else` item met: still pending, what it met recorded)
            core.track(t, step)
        for t in out.changed:
            if t.status == "violated" and not t.late:
                core.stats.violations += 1
            core.track(t, step)
        for t, start in out.fallbacks:
            rule = core.ruleset.rule(t.rule)
            d, determined = core.decider.fallback(rule, t, start)
            rec = core.record(d, step, queue=determined)
            job = Job(rule, d, None, [], rec, core.implementations)
            more = self.begin(job, d.obligations, start, seq, t.depth + 1, t.instance, step)
            if determined:
                followups.append(job)
            followups += more
        return followups

    def begin(
        self,
        job: Job,
        obligations: tuple[Obligation, ...],
        now: float,
        seq: int,
        depth: int,
        instance: int,
        step: Step,
    ) -> list[Job]:
        """Put a decision's obligations in force at ``now``, then settle what they meet, in the
        reference semantics' order: windows that close before they open, priorities (a new
        instance), conflicts. Returns the ``otherwise`` fallbacks this started."""
        core = self.core
        tracker = core.tracker
        d = job.decision
        started = [tracker.start(d.id, d.clause, ob, now, seq, depth, instance) for ob in obligations]
        job.items = started
        followups: list[Job] = []
        for t in started:
            core.track(t, step)
        for t in started:
            if t.status == PENDING and tracker.closed_at_start(t):
                followups += self.settle(tracker.expire(t, now), now, seq, step)
        prio = core.priorities
        if depth == 0 and d.clause is not None and prio.above and prio.semantics == CANCEL:
            self.prioritise(instance, d.rule, now, step)
        for t in started:
            if t.status != PENDING or not tracker.bans:
                continue
            if t.prohibition:  # a new prohibition against the obligations in force, oldest first
                for o in tracker.obliging(t.event):
                    if t.status == PENDING and o.status == PENDING:
                        followups += self.clash(o, t, now, seq, step)
            else:  # a new obligation against the prohibitions in force
                for p in tracker.banning(t.event):
                    if t.status == PENDING and p.status == PENDING:
                        followups += self.clash(t, p, now, seq, step)
        return followups

    # ------------------------------------------------------------------ priorities
    def prioritise(self, instance: int, rule: str, now: float, step: Step) -> None:
        """Cancellation-based priority: a new instance against every active one."""
        tracker, prio = self.core.tracker, self.core.priorities
        if not tracker.of_instance(instance):
            return  # it imposes nothing: it is not active
        others = {i: r for r in prio.related(rule) for i in tracker.instances_of(r)}
        for other in sorted(others.keys() - {instance}):
            higher = prio.between(rule, others[other])
            if higher == rule:
                self._conflicts_cancelled(instance, other, now, rule, step)
                self.cancel(other, now, rule, step, CANCEL)
            elif higher is not None:
                self._conflicts_cancelled(instance, other, now, higher, step)
                self.cancel(instance, now, higher, step, CANCEL)
                return

    def meet(self, items: Iterable[Tracked], now: float, step: Step) -> None:
        """Cancellation-based priorities between activations that were in force together before
        the priorities between them were (a journal restored, a reload): in the order they began."""
        tracker = self.core.tracker
        for t in sorted(items, key=lambda t: t.instance):
            if t.status == PENDING and t.clause is not None and tracker.of_instance(t.instance):
                self.prioritise(t.instance, t.rule, now, step)

    def _conflicts_cancelled(self, a: int, b: int, now: float, winner: str, step: Step) -> None:
        """Record the conflicts a cancellation settles: each obligation of one activation whose
        window a prohibition of the other forbids."""
        tracker = self.core.tracker
        both = sorted([*tracker.of_instance(a), *tracker.of_instance(b)], key=lambda t: t.id)
        for o in both:
            for p in both:
                if (
                    not o.prohibition
                    and p.prohibition
                    and o.event == p.event
                    and o.instance != p.instance
                    and covers(o, p, now)
                ):
                    how = f"{winner} has priority (cancel): the other is cancelled"
                    self.conflict(o, p, now, CANCEL, winner, how, step)

    def cancel(self, instance: int, at: float, by: str, step: Step, how: str) -> bool:
        """Cancel everything activation ``instance`` has in force: priority ``by`` outranks it.

        Returns whether there was anything to cancel.
        """
        core = self.core
        items = core.tracker.of_instance(instance)
        for t in items:
            core.tracker.finish(t, CANCELLED, at, by)
            core.track(t, step)
        if items:
            core.stats.cancelled += 1
            step.emit(
                Kind.CANCELLED,
                {
                    "instance": instance,
                    "rule": items[0].rule,
                    "by": by,
                    "at": at,
                    "priority": how,
                    "obligations": [t.id for t in items],
                },
            )
        return bool(items)

    def forced(self) -> tuple[float, Tracked, str] | None:
        """The next conflict-aware cancellation (:func:`forced`), kept while nothing in force ends
        (what starts meanwhile is weighed against the kept answer, not everything again)."""
        tr, prio = self.core.tracker, self.core.priorities
        if self._cut is not None and self._cut[0] == tr.ended:
            if not tr.started:
                return self._cut[1]
            found = forced(tr, prio, tr.started)
            kept = self._cut[1]
            if kept is None or (found is not None and (found[0], found[1].id) < (kept[0], kept[1].id)):
                kept = found
        else:
            kept = forced(tr, prio)
        tr.started.clear()
        self._cut = (tr.ended, kept)
        return kept

    # ------------------------------------------------------------------ conflicts
    def clash(self, o: Tracked, p: Tracked, now: float, seq: int, step: Step) -> list[Job]:
        """Obligation ``o`` meets prohibition ``p``: a conflict when ``p`` forbids all ``o`` has left."""
        if not covers(o, p, now):
            return []
        core = self.core
        higher = core.priorities.between(o.rule, p.rule)
        if higher is not None and core.priorities.semantics == CONFLICT_AWARE:
            how = f"{higher} has priority ({CONFLICT_AWARE}): the other is kept as long as possible"
            self.conflict(o, p, now, CONFLICT_AWARE, higher, how, step)
            return []  # settled later, at the deadline that forces it (forced())
        how = "the prohibition forbids the whole window and wins: the obligation is blocked"
        self.conflict(o, p, now, "prohibition-wins", p.rule, how, step)
        core.tracker.finish(o, BLOCKED, now, p.rule)
        core.stats.violations += 1
        core.track(o, step)
        if o.obligation.otherwise is None:
            return []
        return self.settle(Outcome(fallbacks=[(o, now)]), now, seq, step)

    def conflict(
        self, o: Tracked, p: Tracked, now: float, resolution: str, winner: str, how: str, step: Step
    ) -> None:
        """Record that obligation ``o`` and prohibition ``p`` conflict, and how it is resolved."""
        self.core.stats.conflicts += 1
        until = (
            "with no end" if p.hi is None else f"for another {duration(p.hi - now)}"
        )  # never a clock reading
        step.emit(
            Kind.CONFLICT,
            {
                "event": o.event,
                "at": now,
                "obligation": o.id,
                "prohibition": p.id,
                "between": [o.rule, p.rule],  # the obligation's rule, the prohibition's
                "clauses": [o.clause, p.clause],
                "resolution": resolution,
                "winner": winner,
                "explanation": f"{o.rule} requires {o.obligation.describe()} and {p.rule} forbids {o.event} "
                f"{until}: {how}",
            },
        )

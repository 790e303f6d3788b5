"""Tracker: the hot path's plain start and quiet check against the general ones.

``Tracker.start_plain`` is ``Tracker.start`` for a plain obligation (one required event, a
window from now) whose deadline its caller made once (``untimed`` applied); ``quiet_for``
is the three checks the hot path asks (nothing forbidden, nothing due, nothing waiting for
the event). On generated obligations, times and indexes (priorities' or not), each must
leave the tracker as the general one does and answer as the three do.
"""

from __future__ import annotations

import dataclasses

from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.runtime.model import Obligation
from cosleec.runtime.obligations import Tracked, Tracker

EVENTS = ("A", "B", "C")


def plain(event: str, within: float | None, eventually: bool) -> Obligation:
    return Obligation(event=event, within_s=within, eventually=eventually and within is None, rule="R1")


def window(tracker: Tracker, ob: Obligation) -> float | None:
    """What the plans make once: the deadline's length, ``untimed`` applied."""
    if ob.within_s is not None or ob.eventually:
        return ob.within_s
    if tracker.untimed == "immediate":
        return tracker.tolerance
    if isinstance(tracker.untimed, float):
        return tracker.untimed
    return None


def typed(t: Tracked) -> list[tuple[type, object]]:
    return [(type(x), x) for x in dataclasses.astuple(t)]


def state(t: Tracker) -> tuple[object, ...]:
    items = {i: dataclasses.astuple(x) for i, x in t._active.items()}
    by_event = {e: sorted(b) for e, b in t._by_event.items()}
    return items, by_event, sorted(t._heap), t.next_id, [x.id for x in t.started], t._instances.keys()


STARTS = st.lists(
    st.tuples(
        st.sampled_from(EVENTS),
        st.one_of(st.none(), st.floats(0, 10)),
        st.booleans(),
        st.one_of(st.floats(0, 100), st.integers(0, 100)),  # (a clock may count in whole seconds)
        st.integers(1, 5),
    ),
    max_size=8,
)


@settings(max_examples=300, deadline=None)
@given(STARTS, st.sampled_from(["none", "immediate", 2.5]), st.booleans())
def test_a_plain_start_leaves_what_start_leaves(
    starts: list[tuple[str, float | None, bool, float, int]], untimed: str | float, priorities: bool
) -> None:
    general, hot = Tracker(untimed), Tracker(untimed)
    for t in (general, hot):
        t.reindex(priorities, priorities)
    for i, (event, within, eventually, now, clause) in enumerate(starts):
        ob = plain(event, within, eventually)
        a = general.start(i + 1, clause, ob, now, seq=i)
        off = window(hot, ob)
        b = hot.start_plain(i + 1, clause, "R1", ob, now, None if off is None else now + off, i)
        assert typed(a) == typed(b) and type(b) is Tracked  # (3 and 3.0 differ in a record)
        assert state(general) == state(hot)


@settings(max_examples=200, deadline=None)
@given(STARTS, st.sampled_from(EVENTS), st.floats(0, 120), st.booleans())
def test_quiet_for_is_the_three_checks(
    starts: list[tuple[str, float | None, bool, float, int]], event: str, now: float, ban: bool
) -> None:
    t = Tracker()
    for i, (ev, within, eventually, at, clause) in enumerate(starts):
        t.start(i + 1, clause, plain(ev, within, eventually), at, seq=i)
    if ban:
        t.start(99, 0, Obligation(event="C", negated=True, within_s=5.0, rule="R2"), 0.0, seq=99)
    t.due(now / 2)  # some windows closed (and missed: a late event is awaited)
    assert t.quiet_for(event, now) == (not t.bans and not t.backlog(now) and not t.waits_for(event))


@given(
    within=st.none() | st.floats(0.0, 10.0),
    negated=st.booleans(),
    alternatives=st.booleans(),
    changes=st.lists(
        st.sampled_from(["status", "late", "refused", "met", "obligation", "shift", "by"]), max_size=6
    ),
)
def test_a_deferred_obligation_record_is_the_one_made_then(
    within: float | None, negated: bool, alternatives: bool, changes: list[str]
) -> None:
    """``Tracked.record_of`` (the hot path's record, made when read) reads later as
    ``to_json`` read at once, whatever changes the obligation meets in between (every field
    that changes while it is in force: outcome, late events, refusals, `else` items met, a
    restore's shift, a reload's new ``otherwise``)."""
    ob = Obligation(
        event="A",
        negated=negated,
        within_s=within,
        rule="R1",
        alternatives=((("B", 0.0, 5.0), ("C", 1.0, None)),) if alternatives else (),
    )
    t = Tracker().start(3, 1, ob, 10.0, 7)
    now, later = t.to_json(), t.record_of()
    for change in changes:
        if change == "status":
            t.status, t.outcome_at = "fulfilled", 12.0
        elif change == "by":
            t.by = "A"
        elif change == "late":
            t.late.append(13.0)
        elif change == "refused":
            t.refused += 1
        elif change == "met" and t.met:
            t.met[0].append(1)
        elif change == "obligation":
            t.obligation = dataclasses.replace(t.obligation, item="R1.0.0", event="A")
        elif change == "shift":  # (what a restore after a reboot does)
            t.shift(5)
    assert later() == now
    assert t.record_of()() == t.to_json()

"""The publisher cache both ROS transports use (:class:`cosleec.ros.publishers.Publishers`),
alone: one publisher per key, made once even when threads race for it, a cosleec topic
latched as the call that makes it says, and nothing kept of a publisher that failed."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from cosleec.ros.publishers import Publishers


class Maker:
    """A middleware stand-in: each call makes a new publisher (a tuple that says how it was made)."""

    def __init__(self, delay: float = 0.0) -> None:
        self.made: list[tuple[Any, ...]] = []
        self.delay = delay

    def __call__(self, *how: Any) -> tuple[Any, ...]:
        time.sleep(self.delay)  # a slow middleware widens the window of a race
        made = (len(self.made), *how)
        self.made.append(made)
        return made


def test_a_key_gets_one_publisher_made_on_first_use() -> None:
    pubs, make = Publishers(), Maker()
    assert pubs.get("/t#std_msgs/Bool") is None and "/t#std_msgs/Bool" not in pubs
    first = pubs.make("/t#std_msgs/Bool", make)
    assert pubs.make("/t#std_msgs/Bool", make) is first and make.made == [first]
    assert pubs.get("/t#std_msgs/Bool") is first and pubs["/t#std_msgs/Bool"] is first
    assert "/t#std_msgs/Bool" in pubs


def test_each_key_has_its_own_publisher() -> None:
    pubs, make = Publishers(), Maker()
    typed = pubs.make("/t#std_msgs/Bool", make)
    raw = pubs.make("/t#std_msgs/Bool#raw", make)
    assert typed != raw and len(make.made) == 2
    assert pubs.all() == [typed, raw]


def test_an_unknown_key_is_a_key_error_by_index_and_none_by_get() -> None:
    pubs = Publishers()
    assert pubs.get("/nope") is None
    with pytest.raises(KeyError):
        pubs["/nope"]


def test_threads_racing_for_one_key_get_the_one_publisher_made_once() -> None:
    pubs, make = Publishers(), Maker(delay=0.05)
    start = threading.Barrier(8)
    got: list[Any] = []

    def ask() -> None:
        start.wait()
        got.append(pubs.make("/diagnostics#", make))

    threads = [threading.Thread(target=ask) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(5)
    assert len(make.made) == 1 and got == [make.made[0]] * 8


def test_a_topic_is_latched_as_the_call_that_makes_its_publisher_says() -> None:
    pubs, make = Publishers(), Maker()
    pubs.advertise("/cosleec/layers", True, make)
    pubs.advertise("/cosleec/layers", False, make)  # too late to change it: no second publisher
    pubs.advertise("/cosleec/events", False, make)
    pubs.advertise("/cosleec/events", True, make)  # nor the other way round
    assert make.made == [(0, True), (1, False)]
    assert pubs["/cosleec/layers"] == (0, True) and pubs["/cosleec/events"] == (1, False)


def test_a_latched_advertise_whose_publisher_failed_is_remembered_for_the_next_one() -> None:
    pubs, make = Publishers(), Maker()

    def broken(latched: bool) -> Any:
        raise RuntimeError("the middleware refused")

    with pytest.raises(RuntimeError):
        pubs.advertise("/cosleec/layers", True, broken)
    assert "/cosleec/layers" not in pubs
    pubs.advertise("/cosleec/layers", False, make)  # latched was asked for first: it stays latched
    assert make.made == [(0, True)]


def test_a_publisher_that_failed_is_not_kept_and_the_next_use_makes_it() -> None:
    pubs, make = Publishers(), Maker()
    calls = []

    def once_broken() -> Any:
        calls.append(1)
        if len(calls) == 1:
            raise OSError("not yet")
        return make()

    with pytest.raises(OSError):
        pubs.make("/t#std_msgs/Bool", once_broken)
    assert pubs.get("/t#std_msgs/Bool") is None
    assert pubs.make("/t#std_msgs/Bool", once_broken) == (0,) and len(calls) == 2


def test_advertise_and_make_share_the_keys() -> None:
    # a topic advertised is found by get (publish, subscribers); make does not make it again
    pubs, make = Publishers(), Maker()
    pubs.advertise("/cosleec/status", False, make)
    assert pubs.make("/cosleec/status", make) == (0, False) and len(make.made) == 1

"""The publishers of one ROS transport: each made once, on first use, and found again by its key.

Both transports (:mod:`cosleec.ros.ros2`, :mod:`cosleec.ros.ros1`) keep one publisher per
thing they publish, under one key:

- a cosleec topic: the topic (``/cosleec/events``), made by :meth:`Publishers.advertise`;
- a typed message a simulator or a test sends: ``topic#type`` (``/lux#std_msgs/Float64``);
- a message the guard forwards as it came: ``topic#type#raw``;
- the ``/diagnostics`` array: ``/diagnostics#``.

How a publisher is made is the middleware's (``create_publisher``, ``rospy.Publisher``):
the transport gives a function that makes it, and the cache calls it at most once per key,
under a lock, as node threads and middleware callbacks may publish at the same time.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


class Publishers:
    """One transport's publishers by key (the topic, or ``topic#type`` and ``topic#type#raw``).

    A cosleec topic is latched or not as the first :meth:`advertise` of it says; the
    other publishers are made by :meth:`make`. Thread-safe: two threads asking for the
    same key at once get the same publisher, made once.
    """

    def __init__(self) -> None:
        self._made: dict[str, Any] = {}
        self._latched: set[str] = set()
        self._lock = threading.Lock()

    def advertise(self, topic: str, latched: bool, create: Callable[[bool], Any]) -> None:
        """Make the publisher of the cosleec ``topic`` with ``create(latched)``, unless it exists.

        A ``latched`` call is remembered even when it makes nothing, but only the call that
        makes the publisher decides: a topic advertised plain and then latched stays plain.
        """
        with self._lock:
            if latched:
                self._latched.add(topic)
            if topic not in self._made:
                self._made[topic] = create(topic in self._latched)

    def make(self, key: str, create: Callable[[], Any]) -> Any:
        """The publisher of ``key``, made with ``create()`` the first time it is asked for."""
        made = self._made.get(key)
        if made is None:
            with self._lock:
                made = self._made.get(key)
                if made is None:
                    made = self._made[key] = create()
        return made

    def get(self, key: str) -> Any | None:
        """The publisher of ``key``, or None if none was made."""
        return self._made.get(key)

    def __getitem__(self, key: str) -> Any:
        """The publisher of ``key``; KeyError if none was made."""
        return self._made[key]

    def __contains__(self, key: object) -> bool:
        """Was the publisher of ``key`` made?"""
        return key in self._made

    def all(self) -> list[Any]:
        """Every publisher made so far (to unregister them when the transport closes)."""
        with self._lock:
            return list(self._made.values())

"""Task modules for the failure tests: a task node that hangs, and one that crashes."""

from __future__ import annotations

import threading
from typing import Any

from cosleec.demo.assistive_care import tasks

_forever = threading.Event()


def install_hanging(node: Any) -> None:
    """Every capability blocks forever (a stuck driver, a dead actuator)."""
    robot = tasks.install(node)

    def hang(ob: Any, decision: Any) -> None:
        _forever.wait()

    for event in list(node.implementations.capabilities):
        node.capability(event)(hang)
    del robot


def install_crashing(node: Any) -> None:
    tasks.install(node)

    def crash(ob: Any, decision: Any) -> None:
        raise RuntimeError(f"actuator fault while doing {ob.event}")

    for event in list(node.implementations.capabilities):
        node.capability(event)(crash)


class Hanging:
    install = staticmethod(install_hanging)


class Crashing:
    install = staticmethod(install_crashing)

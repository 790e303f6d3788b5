"""Tasks for the ROS 2 kill campaign: every capability notes that it ran, and reports nothing.

Each call appends one JSON line ``{"k": "cap", "phase": "start", "decision", "event"}`` to
the file ``$COSLEEC_KILL_RAN`` (one ``write(2)``). The script itself reports the robot's
actions (``tests.kill_campaign.flatten``), so what the Manager decides does not depend on
when a task ran; what the test checks here is that no decision ran twice.
"""

from __future__ import annotations

import json
import os
from typing import Any


def install(node: Any) -> None:
    fd = os.open(os.environ["COSLEEC_KILL_RAN"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    for event in sorted(node.ruleset.responds):

        def perform(ob: Any, d: Any, event: str = event) -> None:
            line = {"k": "cap", "phase": "start", "decision": d.id, "event": event}
            os.write(fd, (json.dumps(line) + "\n").encode())

        node.capability(event)(perform)

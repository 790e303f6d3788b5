"""Node health on ``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``), as ROS tools expect it.

``rqt_robot_monitor``, ``diagnostic_aggregator`` and fleet dashboards read node health
from ``/diagnostics``; cosleec's own ``status`` topic says more but only cosleec reads it.
Each status record a node publishes is summarised here: at most once a second, and at
once when the level changes, so a burst of rejected messages shows without flooding.

Levels: ERROR while the executor is not alive (the node is deaf), while the Manager does
not answer a guard or task node (``manager_answering`` false: it blocks or refuses
everything, and the message says why), or when a handler failed on a bug of ours
(``errors`` grew); WARN when messages were rejected, violations occurred or
a QoS-incompatible peer appeared since the last report; OK otherwise. The values are the
counters that matter (received, rejected, decisions, violations, executor alive, ...).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

OK, WARN, ERROR = 0, 1, 2
#: seconds between two reports at the same level
PERIOD = 1.0


class Diagnostics:
    """Turns a node's status records into diagnostic statuses and hands them to ``send``.

    ``send`` gets ``{"name", "level", "message", "values": [(key, text), ...]}``; the
    transport makes the ``DiagnosticArray``. Thread-safe.
    """

    def __init__(
        self, name: str, send: Callable[[dict[str, Any]], None], clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.name = name
        self.send = send
        self.clock = clock
        self._last: tuple[float, int] | None = None  # (when, level) of the last report
        self._seen: dict[str, int] = {}  # counters at the last report
        self._lock = threading.Lock()

    def report(self, status: dict[str, Any]) -> bool:
        """Summarise ``status`` (a node's status record); True if a diagnostic went out."""
        counters = dict(status.get("counters") or {})
        if isinstance(status.get("qos_incompatible"), int):  # a count like the others: growth warns
            counters["qos_incompatible"] = status["qos_incompatible"]
        stats = dict(status.get("stats") or {})
        with self._lock:
            level, why = self._level(status, counters, stats)
            now = self.clock()
            if self._last is not None and self._last[1] == level and now - self._last[0] < PERIOD:
                return False
            self._last = (now, level)
            self._seen = {**counters, **{f"stats.{k}": v for k, v in stats.items()}}
        values = [("executor_alive", str(bool(status.get("executor_alive", True))).lower())]
        values += [(k, str(v)) for k, v in sorted(counters.items())]
        values += [
            (k, str(v))
            for k, v in sorted(stats.items())
            if k in ("decisions", "violations", "refused", "conflicts")
        ]
        for k in ("transport_errors", "transport_lost", "lifecycle", "manager_answering"):
            if k in status:
                v = status[k]
                values.append((k, str(v).lower() if isinstance(v, bool) else str(v)))
        self.send(
            {
                "name": f"cosleec: {status.get('node', self.name)} ({self.name})",
                "level": level,
                "message": why,
                "values": values,
            }
        )
        return True

    def _level(
        self, status: dict[str, Any], counters: dict[str, Any], stats: dict[str, Any]
    ) -> tuple[int, str]:
        if status.get("executor_alive") is False:
            return ERROR, "the executor has stopped: the node hears nothing"
        if status.get("manager_answering") is False:
            return ERROR, str(status.get("manager_problem") or "the Manager does not answer")
        grew = {
            k: int(v) - int(self._seen.get(k, 0))
            for k, v in [*counters.items(), *((f"stats.{k}", v) for k, v in stats.items())]
            if isinstance(v, int) and int(v) > int(self._seen.get(k, 0))
        }
        if grew.get("errors"):
            return ERROR, f"{grew['errors']} message(s) hit a bug in the node (see its log)"
        warn = []
        if grew.get("rejected"):
            warn.append(f"{grew['rejected']} message(s) rejected")
        if grew.get("stats.violations"):
            warn.append(f"{grew['stats.violations']} violation(s)")
        if grew.get("qos_incompatible"):
            warn.append(f"{grew['qos_incompatible']} peer(s) with incompatible QoS appeared (not connected)")
        if warn:
            return WARN, "; ".join(warn)
        return OK, "ok"

"""Node health on ``/diagnostics``: the level of each status record (OK, WARN, ERROR), the rate
limit (one report per PERIOD at one level, at once on a change of level), what "grew since
the last report" means, and the values a report carries. Time is a fake clock."""

from __future__ import annotations

import json
import threading
from typing import Any

import pytest

from cosleec.nodes import LocalBus, Node
from cosleec.ros import diagnostics as diag
from cosleec.ros.diagnostics import ERROR, OK, PERIOD, WARN, Diagnostics


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class Harness:
    def __init__(self, name: str = "cosleec_manager") -> None:
        self.clock = Clock()
        self.sent: list[dict[str, Any]] = []
        self.d = Diagnostics(name, self.sent.append, clock=self.clock)

    def at(self, t: float, **status: Any) -> bool:
        """Report ``status`` at ``t`` seconds after the start."""
        self.clock.t = 100.0 + t
        status.setdefault("node", "manager")
        return self.d.report(status)

    @property
    def last(self) -> dict[str, Any]:
        return self.sent[-1]

    def levels(self) -> list[int]:
        return [s["level"] for s in self.sent]


def counters(**kw: int) -> dict[str, int]:
    return {"received": 0, "processed": 0, "rejected": 0, "published": 0, "errors": 0, **kw}


def test_levels_and_period_constants() -> None:
    assert (OK, WARN, ERROR) == (0, 1, 2)  # diagnostic_msgs/DiagnosticStatus levels
    assert PERIOD == 1.0


def test_the_first_report_goes_out_ok() -> None:
    h = Harness()
    assert h.at(0, counters=counters(received=5, processed=5)) is True
    assert h.sent == [
        {
            "name": "cosleec: manager (cosleec_manager)",
            "level": OK,
            "message": "ok",
            "values": [
                ("executor_alive", "true"),
                ("errors", "0"),
                ("processed", "5"),
                ("published", "0"),
                ("received", "5"),
                ("rejected", "0"),
            ],
        }
    ]


def test_the_name_falls_back_to_the_transports_node_name() -> None:
    h = Harness("robot1_guard")
    h.d.report({"counters": {}})
    assert h.last["name"] == "cosleec: robot1_guard (robot1_guard)"


def test_an_empty_status_is_ok() -> None:
    h = Harness()
    assert h.d.report({}) is True
    assert h.last["level"] == OK and h.last["values"] == [("executor_alive", "true")]


# ----------------------------------------------------------------------------- levels


def test_a_dead_executor_is_an_error() -> None:
    h = Harness()
    h.at(0, counters=counters(), executor_alive=False)
    assert h.last["level"] == ERROR
    assert h.last["message"] == "the executor has stopped: the node hears nothing"
    assert ("executor_alive", "false") in h.last["values"]


@pytest.mark.parametrize("alive", [True, None])
def test_an_alive_or_unknown_executor_is_no_error(alive: Any) -> None:
    h = Harness()
    status: dict[str, Any] = {"counters": counters()}
    if alive is not None:
        status["executor_alive"] = alive
    h.at(0, **status)
    assert h.last["level"] == OK
    assert h.last["values"][0] == ("executor_alive", "true")


def test_a_dead_executor_outranks_errors_and_rejections() -> None:
    h = Harness()
    h.at(0, counters=counters(errors=2, rejected=3), executor_alive=False)
    assert h.last["level"] == ERROR and "executor has stopped" in h.last["message"]


def test_errors_that_grew_are_an_error_naming_how_many() -> None:
    h = Harness()
    h.at(0, counters=counters())
    h.at(0.1, counters=counters(errors=2, rejected=2))
    assert h.last["level"] == ERROR
    assert h.last["message"] == "2 message(s) hit a bug in the node (see its log)"


def test_rejections_that_grew_are_a_warning() -> None:
    h = Harness()
    h.at(0, counters=counters(rejected=1))
    assert h.last["level"] == WARN and h.last["message"] == "1 message(s) rejected"
    h.at(0.1, counters=counters(rejected=1))
    assert h.last["level"] == OK  # the same count: nothing new, back to OK at once
    h.at(0.2, counters=counters(rejected=4))
    assert h.last["level"] == WARN and h.last["message"] == "3 message(s) rejected"


def test_violations_that_grew_are_a_warning() -> None:
    h = Harness()
    h.at(0, counters=counters(), stats={"violations": 0, "decisions": 3})
    assert h.last["level"] == OK
    h.at(0.1, counters=counters(), stats={"violations": 2, "decisions": 5})
    assert h.last["level"] == WARN and h.last["message"] == "2 violation(s)"


def test_a_counter_named_violations_is_not_the_managers_violations() -> None:
    h = Harness()
    h.at(0, counters=counters(violations=3))
    assert h.last["level"] == OK


def test_decisions_growing_is_no_warning() -> None:
    h = Harness()
    h.at(0, counters=counters(received=9, processed=9, published=9), stats={"decisions": 9, "refused": 2})
    assert h.last["level"] == OK


def test_rejections_and_violations_together() -> None:
    h = Harness()
    h.at(0, counters=counters(rejected=2), stats={"violations": 1})
    assert h.last["level"] == WARN
    assert h.last["message"] == "2 message(s) rejected; 1 violation(s)"


def test_a_qos_incompatible_peer_is_a_warning() -> None:
    h = Harness()
    h.at(0, counters=counters(), qos_incompatible=1)
    assert h.last["level"] == WARN
    assert h.last["message"] == "1 peer(s) with incompatible QoS appeared (not connected)"
    h2 = Harness()
    h2.at(0, counters=counters(rejected=1), qos_incompatible=2)
    assert (
        h2.last["message"]
        == "1 message(s) rejected; 2 peer(s) with incompatible QoS appeared (not connected)"
    )


@pytest.mark.parametrize("value", [0, None])
def test_no_qos_incompatible_peer_is_no_warning(value: Any) -> None:
    h = Harness()
    h.at(0, counters=counters(), qos_incompatible=value)
    assert h.last["level"] == OK


def test_counters_that_went_down_are_no_growth() -> None:
    h = Harness()
    h.at(0, counters=counters(rejected=5, errors=5))
    assert h.last["level"] == ERROR
    h.at(0.1, counters=counters(rejected=1, errors=1))  # a restarted node counts from 0 again
    assert h.last["level"] == OK


def test_a_non_integer_counter_is_ignored() -> None:
    h = Harness()
    h.at(0, counters={"rejected": "many", "errors": 1.5}, stats={"violations": None})
    assert h.last["level"] == OK


# ----------------------------------------------------------------------------- rate limit


def test_at_most_one_report_per_period_at_one_level() -> None:
    h = Harness()
    assert h.at(0, counters=counters()) is True
    assert h.at(0.5, counters=counters()) is False
    assert h.at(PERIOD - 1e-6, counters=counters()) is False
    assert h.at(PERIOD, counters=counters()) is True  # a whole period later: again
    assert h.at(PERIOD + 0.5, counters=counters()) is False
    assert h.at(2 * PERIOD, counters=counters()) is True
    assert h.levels() == [OK, OK, OK]


def test_the_period_counts_from_the_last_report_sent_not_the_last_attempt() -> None:
    h = Harness()
    h.at(0, counters=counters())
    h.at(0.6, counters=counters())  # held back
    assert h.at(1.0, counters=counters()) is True


def test_a_change_of_level_goes_out_at_once() -> None:
    h = Harness()
    assert h.at(0, counters=counters()) is True
    assert h.at(0.01, counters=counters(rejected=1)) is True  # OK -> WARN
    assert h.at(0.02, counters=counters(rejected=1, errors=1)) is True  # WARN -> ERROR
    assert h.at(0.03, counters=counters(rejected=1, errors=1)) is True  # ERROR -> OK
    assert h.levels() == [OK, WARN, ERROR, OK]


def test_a_change_of_level_starts_a_new_period() -> None:
    h = Harness()
    h.at(0, counters=counters())
    h.at(0.5, counters=counters(rejected=1))  # WARN at 0.5
    assert h.at(1.2, counters=counters(rejected=2)) is False  # WARN again, 0.7 s later
    assert h.at(1.5, counters=counters(rejected=3)) is True  # WARN again, 1.0 s later


def test_growth_is_measured_since_the_last_report_sent() -> None:
    h = Harness()
    h.at(0, counters=counters())
    h.at(0.1, counters=counters(rejected=1))  # WARN, sent: seen rejected=1
    assert h.at(0.2, counters=counters(rejected=3)) is False  # WARN, held back: seen stays 1
    assert h.at(1.1, counters=counters(rejected=3)) is True
    assert h.last["level"] == WARN and h.last["message"] == "2 message(s) rejected"
    # and now 3 is what was last reported: no growth, OK at once
    assert h.at(1.2, counters=counters(rejected=3)) is True
    assert h.last["level"] == OK


def test_a_burst_of_rejections_shows_without_flooding() -> None:
    h = Harness()
    h.at(0, counters=counters())
    for i in range(1, 200):  # 199 statuses in 0.995 s, each with one more rejection
        h.at(i * 0.005, counters=counters(rejected=i))
    assert h.levels() == [OK, WARN]


def test_concurrent_reports_at_one_level_send_one() -> None:
    h = Harness()
    barrier = threading.Barrier(8)
    results: list[bool] = []

    def go() -> None:
        barrier.wait()
        results.append(h.d.report({"node": "manager", "counters": counters()}))

    threads = [threading.Thread(target=go) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(5)
    assert results.count(True) == 1 and len(h.sent) == 1


def test_the_default_clock_is_monotonic() -> None:
    import time

    d = Diagnostics("n", lambda _s: None)
    assert d.clock is time.monotonic


# ----------------------------------------------------------------------------- values


def test_the_values_carry_counters_sorted_the_managers_stats_and_transport_health() -> None:
    h = Harness()
    h.at(
        0,
        counters={"rejected": 1, "errors": 0, "received": 7, "lost": 2},
        stats={
            "violations": 1,
            "decisions": 4,
            "refused": 3,
            "conflicts": 0,
            "updates": 9,  # not one that matters here
            "events": 5,
        },
        executor_alive=True,
        transport_errors=3,
        transport_lost=4,
        qos_incompatible=0,
        lifecycle="inactive",
        context_version=12,  # not a value of the report
        time=3.5,
    )
    assert h.last["values"] == [
        ("executor_alive", "true"),
        ("errors", "0"),
        ("lost", "2"),
        ("qos_incompatible", "0"),
        ("received", "7"),
        ("rejected", "1"),
        ("conflicts", "0"),
        ("decisions", "4"),
        ("refused", "3"),
        ("violations", "1"),
        ("transport_errors", "3"),
        ("transport_lost", "4"),
        ("lifecycle", "inactive"),
    ]
    assert all(isinstance(k, str) and isinstance(v, str) for k, v in h.last["values"])


def test_a_held_back_report_sends_nothing() -> None:
    h = Harness()
    h.at(0, counters=counters())
    h.at(0.1, counters=counters(received=1))
    assert len(h.sent) == 1


def test_diagnostics_module_imports_no_middleware() -> None:
    assert "rclpy" not in vars(diag) and "rospy" not in vars(diag)


# ----------------------------------------------------------------------------- bugs


def test_a_qos_incompatible_count_that_stays_the_same_goes_back_to_ok() -> None:
    h = Harness()
    h.at(0, counters=counters(), qos_incompatible=1)
    assert h.last["level"] == WARN
    h.at(PERIOD, counters=counters(), qos_incompatible=1)
    assert h.last["level"] == OK


def test_a_transports_incompatible_peers_reach_the_diagnostics(bus: LocalBus) -> None:
    class Transport:
        def __init__(self) -> None:
            self.local = bus.transport()
            self.incompatible = 2  # as Ros2Transport counts them
            self.sent: list[dict[str, Any]] = []

        def publish(self, topic: str, message: Any) -> None:
            self.sent.append(message if isinstance(message, dict) else json.loads(message))

        def subscribe(self, topic: str, handler: Any) -> None:
            self.local.subscribe(topic, handler)

        def subscribe_typed(self, *a: Any, **k: Any) -> None:
            raise AssertionError("unused")

        def advertise(self, topic: str, latched: bool = False) -> None:
            pass

        def close(self) -> None:
            pass

    t = Transport()
    node = Node(t)
    node.status()
    status = t.sent[-1]
    h = Harness()
    h.d.report(status)
    assert h.last["level"] == WARN and "incompatible QoS" in h.last["message"]


# ----------------------------------------------------------------------------- a Manager that does not answer


PROBLEM = (
    "the Manager (/cosleec_manager/request) did not answer within 0.5 s: every guarded message is blocked"
)


def test_a_manager_that_does_not_answer_is_an_error_saying_why() -> None:
    h = Harness("cosleec_guard")
    h.at(0, node="guard", counters=counters(), manager_answering=True)
    assert h.last["level"] == OK and ("manager_answering", "true") in h.last["values"]
    h.at(0.1, node="guard", counters=counters(), manager_answering=False, manager_problem=PROBLEM)
    assert (h.last["level"], h.last["message"]) == (ERROR, PROBLEM)  # at once: the level changed
    assert ("manager_answering", "false") in h.last["values"]
    h.at(0.2, node="guard", counters=counters(), manager_answering=True)
    assert (h.last["level"], h.last["message"]) == (OK, "ok")  # and back, at once


def test_a_manager_not_asked_yet_is_no_error_and_no_value() -> None:
    h = Harness("cosleec_guard")
    h.at(0, node="guard", counters=counters())
    assert h.last["level"] == OK and all(k != "manager_answering" for k, _ in h.last["values"])


def test_a_manager_that_does_not_answer_outranks_warnings_but_not_a_dead_executor() -> None:
    h = Harness()
    h.at(0, counters=counters(rejected=2), manager_answering=False, manager_problem=PROBLEM)
    assert (h.last["level"], h.last["message"]) == (ERROR, PROBLEM)
    h.at(5, counters=counters(rejected=2), manager_answering=False, executor_alive=False)
    assert "executor has stopped" in h.last["message"]


def test_a_task_node_whose_manager_does_not_answer_reports_an_error_until_it_answers(bus: LocalBus) -> None:
    from cosleec.nodes import ManagerNode, TaskNode
    from cosleec.runtime import RuleSet

    from .support import collect
    from .test_manager_services import RULES

    rules = RuleSet.from_file(RULES)
    status = collect(bus, "/cosleec/status")
    task = TaskNode(bus.transport(), rules, request_timeout=0.05)
    h = Harness("cosleec_task")
    assert task.request("MoveNearUser") is False  # nobody answers: refused (fail closed)
    bus.wait_idle()
    mine = [s for s in status if s["node"] == "task"]
    assert mine[-1]["manager_answering"] is False  # said at once, not at the next heartbeat
    h.d.report(mine[-1])
    assert h.last["level"] == ERROR
    assert h.last["message"] == (
        "the Manager did not answer a request within 0.05 s: the tasks' requests are refused until it answers"
    )
    manager = ManagerNode(bus.transport(), rules, sim_time=True)
    assert task.request("MoveNearUser") is True
    bus.wait_idle()
    mine = [s for s in status if s["node"] == "task"]
    h.clock.t += PERIOD
    h.d.report(mine[-1])
    assert (mine[-1]["manager_answering"], h.last["level"]) == (True, OK)
    manager.close()
    task.close()

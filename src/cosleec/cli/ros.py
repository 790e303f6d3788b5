"""``cosleec ros2 ...`` and ``cosleec ros1 ...``: the CO-SLEEC nodes on real middleware."""

from __future__ import annotations

import argparse
import os
import re
import sys
from typing import Any

from cosleec import ros
from cosleec.cli.common import add_clause_options, add_priority_options
from cosleec.nodes import LayersNode, ListenerNode, ManagerNode, Mapping, TaskNode
from cosleec.runtime import RuleSet, Unknowns


def add_parser(sub: argparse._SubParsersAction, backend: str) -> None:  # type: ignore[type-arg]
    """Register ``cosleec <backend>`` (``ros2`` or ``ros1``) and its sub-commands.

    One per node kind (manager, layers, listener, task), plus ``launch`` and ``demo``.
    """
    p = sub.add_parser(
        backend, help=f"run CO-SLEEC nodes on {'ROS 2 (rclpy)' if backend == 'ros2' else 'ROS 1 (rospy)'}"
    )
    nodes = p.add_subparsers(dest="node", metavar="NODE")
    nodes.required = True

    def common(q: argparse.ArgumentParser) -> None:
        q.add_argument("--namespace", default="/cosleec")
        q.set_defaults(run=run, backend=backend)

    m = nodes.add_parser("manager", help="rules, context, decisions, obligations")
    m.add_argument("rules")
    add_clause_options(m)
    m.add_argument("--sim-time", action="store_true", help="take time from the clock topic")
    m.add_argument("--audit", metavar="FILE", help="append-only JSON Lines audit trail")
    m.add_argument(
        "--journal",
        metavar="FILE",
        help="keep the Manager's state in this SQLite journal: a restarted Manager restores it",
    )
    add_priority_options(m, lead=True)
    m.add_argument("--record", metavar="FILE.mcap", help="record the decision stream (Foxglove opens it)")
    m.add_argument(
        "--status-each", action="store_true", help="publish status after every message (harnesses)"
    )
    common(m)
    la = nodes.add_parser("layers", help="the COP Layer Manager: publishes active layers (latched)")
    la.add_argument("rules")
    add_clause_options(la)  # as the manager's, or the two choose different layers
    common(la)
    li = nodes.add_parser("listener", help="the Context Listener: robot topics -> measures and events")
    li.add_argument("mapping")
    li.add_argument("--rules", help="check the mapping against these rules")
    common(li)
    t = nodes.add_parser("task", help="a task node: layered implementations of rules")
    t.add_argument("rules")
    t.add_argument("--module", required=True, help="a module with install(node) binding tasks/capabilities")
    t.add_argument("--name", default="task")
    t.add_argument("--only", help="comma-separated rule names this node serves")
    t.add_argument(
        "--status-each", action="store_true", help="publish status after every obligation (harnesses)"
    )
    t.add_argument(
        "--when-manager-down",
        choices=("refuse", "raise"),
        default="refuse",
        help="when the Manager does not answer a task's request in time: refuse the action (default), "
        "or raise ManagerUnavailable into the task",
    )
    t.add_argument(
        "--request-timeout",
        type=float,
        default=2.0,
        metavar="SECONDS",
        help="how long a task's request waits for the Manager's answer (default 2)",
    )
    common(t)
    lp = nodes.add_parser("launch", help="start the nodes of a launch file; stop them on SIGINT/SIGTERM")
    lp.add_argument("file")
    lp.set_defaults(run=run, backend=backend)
    d = nodes.add_parser(
        "demo", help="the assistive-care scenario over real middleware, in separate processes"
    )
    d.add_argument("--json", action="store_true")
    common(d)


def node_name(namespace: str, kind: str) -> str:
    """The middleware name of a ``kind`` node under ``namespace``: ``/robot1`` gives ``robot1_manager``.

    ROS 1 lets one node hold a name: two Managers both named ``cosleec_manager`` would
    evict each other, so the name carries the namespace (``/cosleec`` still gives
    ``cosleec_manager``; ``/fleet/robot1`` gives ``fleet_robot1_manager``). What a ROS
    name cannot hold becomes ``_``, and a name that would start with a digit starts with
    ``n``, so the result is valid on ROS 1 and ROS 2.
    """
    name = "_".join(p for p in re.split(r"[^A-Za-z0-9]+", f"{namespace}/{kind}") if p) or kind
    return name if name[0].isalpha() else f"n{name}"


def run(args: argparse.Namespace) -> int:
    """Run the chosen node until SIGINT/SIGTERM, or launch a file, or play the demo.

    Rules and mapping are loaded and checked before the middleware starts, so a mistake
    in them is reported at once, with exit 1.
    """
    backend, node = args.backend, args.node
    if node == "launch":
        return ros.launch(args.file)
    if node == "demo":
        return ros.run_demo(backend, args.namespace, args.json)

    # rules and mapping are read before the middleware starts: a mistake is reported at once
    path = args.rules if node != "listener" else args.rules or None
    rules = RuleSet.from_file(path) if path else None
    mapping = (
        Mapping.load(args.mapping, dict(rules.measures) if rules else None, rules.events if rules else None)
        if node == "listener"
        else None
    )
    namespace = mapping.namespace if mapping is not None and mapping.namespace else args.namespace
    name = node_name(namespace, node if node != "task" else args.name)

    def make(t: Any) -> Any:
        if node == "manager":
            assert rules is not None
            return ManagerNode(
                t,
                rules,
                namespace=args.namespace,
                semantics=args.semantics,
                sim_time=args.sim_time,
                audit=args.audit,
                record=args.record,
                status_each=args.status_each,
                unknown=args.unknown,
                journal=args.journal,
                priorities=args.priority,
                priority_semantics=args.priority_semantics,
                priority_lead=args.priority_lead,
            )
        if node == "layers":
            assert rules is not None
            return LayersNode(
                t, rules, namespace=args.namespace, semantics=args.semantics, unknowns=Unknowns(args.unknown)
            )
        if node == "listener":
            assert mapping is not None
            return ListenerNode(t, mapping, namespace=args.namespace)
        assert rules is not None
        tn = TaskNode(
            t,
            rules,
            namespace=args.namespace,
            name=args.name,
            status_each=args.status_each,
            when_manager_down=args.when_manager_down,
            request_timeout=args.request_timeout,
        )
        ros.load_module(args.module).install(tn)
        only = args.only.split(",") if args.only else None
        return tn.start(only)

    if backend == "ros2" and not os.environ.get("ROS_DOMAIN_ID"):
        print("cosleec: note: ROS_DOMAIN_ID is not set (domain 0)", file=sys.stderr)
    return ros.serve(backend, node, make, name)

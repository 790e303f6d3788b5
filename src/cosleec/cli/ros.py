"""``cosleec ros2 ...`` and ``cosleec ros1 ...``: the CO-SLEEC nodes on real middleware."""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any


def add_parser(sub: argparse._SubParsersAction, backend: str) -> None:  # type: ignore[type-arg]
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
    m.add_argument("--semantics", choices=["last-wins", "nested"], default="last-wins")
    m.add_argument("--sim-time", action="store_true", help="take time from the clock topic")
    m.add_argument("--audit", metavar="FILE", help="append-only JSON Lines audit trail")
    m.add_argument("--record", metavar="FILE.mcap", help="record the decision stream (Foxglove opens it)")
    m.add_argument(
        "--status-each", action="store_true", help="publish status after every message (harnesses)"
    )
    common(m)
    la = nodes.add_parser("layers", help="the COP Layer Manager: publishes active layers (latched)")
    la.add_argument("rules")
    la.add_argument("--semantics", choices=["last-wins", "nested"], default="last-wins")
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
    common(t)
    lp = nodes.add_parser("launch", help="start the nodes of a launch file; stop them on SIGINT/SIGTERM")
    lp.add_argument("file")
    lp.set_defaults(run=run, backend=backend)
    d = nodes.add_parser(
        "demo", help="the assistive-care scenario over real middleware, in separate processes"
    )
    d.add_argument("--json", action="store_true")
    common(d)


def run(args: argparse.Namespace) -> int:
    backend, node = args.backend, args.node
    if node == "launch":
        from cosleec.ros.launch import launch

        return launch(args.file)
    if node == "demo":
        from cosleec.ros.demo import main

        return main(backend, args.namespace, args.json)
    from cosleec.ros.run import load_module, serve

    name = f"cosleec_{node}" if node != "task" else f"cosleec_{args.name}"

    def make(t: Any) -> Any:
        if node == "manager":
            from cosleec.nodes import ManagerNode

            return ManagerNode(
                t,
                args.rules,
                namespace=args.namespace,
                semantics=args.semantics,
                sim_time=args.sim_time,
                audit=args.audit,
                record=args.record,
                status_each=args.status_each,
            )
        if node == "layers":
            from cosleec.nodes import LayersNode

            return LayersNode(t, args.rules, namespace=args.namespace, semantics=args.semantics)
        if node == "listener":
            from cosleec.nodes import ListenerNode, Mapping, MappingError

            measures = events = None
            if args.rules:
                from cosleec.runtime.manager import load_rules
                from cosleec.runtime.model import compile_rules

                spec, symbols = load_rules(args.rules)
                rs = compile_rules(spec, symbols)
                measures, events = rs.measures, rs.events
            try:
                mapping = Mapping.load(args.mapping, measures, events)
            except (MappingError, OSError) as e:
                print(f"cosleec listener: {e}", file=sys.stderr)
                raise SystemExit(1) from None
            return ListenerNode(t, mapping, namespace=args.namespace)
        from cosleec.nodes import TaskNode

        tn = TaskNode(t, args.rules, namespace=args.namespace, name=args.name, status_each=args.status_each)
        load_module(args.module).install(tn)
        only = args.only.split(",") if args.only else None
        return tn.start(only)

    if backend == "ros2" and not os.environ.get("ROS_DOMAIN_ID"):
        print("cosleec: note: ROS_DOMAIN_ID is not set (domain 0)", file=sys.stderr)
    return serve(backend, node, make, name)

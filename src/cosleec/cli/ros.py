"""``cosleec ros2 ...`` and ``cosleec ros1 ...``: the CO-SLEEC nodes on real middleware.

Every node option is also a ROS parameter of the same name (``--status-each`` is
``status_each``): ``cosleec ros2 manager --ros-args -p rules:=home.sleec -p
semantics:=nested`` or ``--params-file params.yaml`` on ROS 2, ``_semantics:=nested`` (a
private parameter) on ROS 1. A parameter given wins over the option. Simulated time is
the standard ``use_sim_time`` (``--sim-time`` sets it), read from ``/clock``.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import re
import sys
from collections.abc import Callable
from typing import Any

from cosleec import ros
from cosleec.cli import ros_setup
from cosleec.cli.common import add_clause_options, add_priority_options, input_file, output_file, port
from cosleec.errors import UserError
from cosleec.nodes import (
    DECIDE,
    DEFAULT_DECIDE,
    GuardNode,
    LayersNode,
    ListenerNode,
    ManagerNode,
    Mapping,
    McapRecorder,
    Route,
    TaskNode,
    load_routes,
    route,
)
from cosleec.runtime import Manager, RuleSet, Unknowns
from cosleec.views import AttachedView

#: the options of each node kind that are also ROS parameters (argparse dests). Not the
#: namespace: it names the node, which exists before its parameters can be read (ROS 2 has
#: its own `-r __ns:=/robot1`); nor the Manager's --web: it opens a port, which is asked for
#: where the node is started, not by a parameter file shared between robots; nor
#: --reload-dir and --decide, which say what anyone on the domain may make the Manager do:
#: a ROS 1 node reads parameters it was not given from the parameter server, which anyone
#: on the graph can write, so these come from the command line (or launch file) alone
PARAMETERS = {
    "manager": (
        "rules",
        "semantics",
        "unknown",
        "audit",
        "journal",
        "priority",
        "priority_semantics",
        "priority_lead",
        "record",
        "status_each",
        "autostart",
    ),
    "layers": ("rules", "semantics", "unknown"),
    "listener": ("mapping", "rules"),
    "task": (
        "rules",
        "module",
        "path",
        "name",
        "only",
        "status_each",
        "when_manager_down",
        "request_timeout",
    ),
    "guard": ("mapping", "rules", "manager", "timeout"),
}


def seconds(text: str) -> float:
    """An argparse type: a positive, finite number of seconds (``nan``, ``inf`` and ``-1`` are not)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r}: give a positive, finite number of seconds")
    return value


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """``argv`` without its ROS arguments, and those arguments.

    ROS 2: everything from ``--ros-args`` up to a lone ``--`` (or the end). ROS 1:
    ``name:=value`` remappings and ``_param:=value`` private parameters, anywhere.
    """
    rest: list[str] = []
    ros_args: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--ros-args":
            j = argv.index("--", i + 1) if "--" in argv[i + 1 :] else len(argv)
            ros_args += argv[i:j]
            i = j + 1
            continue
        if ":=" in a and not a.startswith("-"):
            ros_args.append(a)
        else:
            rest.append(a)
        i += 1
    return rest, ros_args


def add_parser(sub: argparse._SubParsersAction, backend: str) -> None:  # type: ignore[type-arg]
    """Register ``cosleec <backend>`` (``ros2`` or ``ros1``) and its sub-commands.

    One per node kind (manager, layers, listener, task, guard), plus ``launch`` and ``demo``;
    on ROS 2 also ``setup``, which builds cosleec's messages into this environment.
    """
    p = sub.add_parser(
        backend, help=f"run CO-SLEEC nodes on {'ROS 2 (rclpy)' if backend == 'ros2' else 'ROS 1 (rospy)'}"
    )
    nodes = p.add_subparsers(dest="node", metavar="NODE")
    nodes.required = True
    for add in (_add_manager, _add_layers, _add_listener, _add_task, _add_guard):
        _add_common(add(nodes), backend)
    lp = nodes.add_parser("launch", help="start the nodes of a launch file; stop them on SIGINT/SIGTERM")
    lp.add_argument("file", metavar="FILE", help="the launch file (YAML: backend, namespace, nodes)")
    lp.set_defaults(run=run, backend=backend)
    d = nodes.add_parser(
        "demo", help="the assistive-care scenario over real middleware, in separate processes"
    )
    d.add_argument("--json", action="store_true", help="print runtime events as JSON lines")
    _add_common(d, backend)
    if backend == "ros2":
        ros_setup.add_parser(nodes)


def _add_common(q: argparse.ArgumentParser, backend: str) -> None:
    """The options every node (and the demo) takes, after its own: the namespace and the wire."""
    q.add_argument("--namespace", default="/cosleec", help="the topics' namespace (default /cosleec)")
    q.add_argument(
        "--wire",
        choices=("typed", "json"),
        default="typed",
        help="typed: cosleec_interfaces messages (default); json: JSON text in std_msgs/String, "
        "for tools without the types (every node of a system must use the same)",
    )
    q.set_defaults(run=run, backend=backend)


def _add_manager(nodes: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """``manager``: the rules, where the Manager writes, and what it lets others make it do."""
    m = nodes.add_parser("manager", help="rules, context, decisions, obligations")
    m.add_argument("rules", nargs="?", help="the rule file (or the `rules` parameter)")
    add_clause_options(m)
    m.add_argument("--sim-time", action="store_true", help="take time from /clock (use_sim_time)")
    m.add_argument("--audit", metavar="FILE", help="append-only JSON Lines audit trail")
    m.add_argument(
        "--explanations",
        metavar="FILE",
        help="what the robot says to people, rule by rule (YAML): each decision's for_people",
    )
    m.add_argument(
        "--journal",
        metavar="FILE",
        help="keep the Manager's state in this SQLite journal: a restarted Manager restores it",
    )
    m.add_argument(
        "--reset-journal",
        action="store_true",
        help="with --journal: start afresh from a journal the Manager refused (a lost or damaged -wal, an "
        "old copy), once; the reset and what was lost are recorded in the audit log",
    )
    add_priority_options(m, lead=True)
    m.add_argument(
        "--record",
        metavar="FILE.mcap",
        help="record the decision stream: a rosbag2 MCAP (ros2 bag, rosbags, Foxglove, cosleec timeline open it)",
    )
    m.add_argument(
        "--record-format",
        choices=McapRecorder.FORMATS,
        default=McapRecorder.FORMATS[0],
        help="with --record: ros2 (default: CDR messages of cosleec_interfaces types, profile ros2) or "
        "json (the JSON copy: one JSON object per message, for tools without the ROS types)",
    )
    m.add_argument(
        "--status-each", action="store_true", help="publish status after every message (harnesses)"
    )
    m.add_argument(
        "--web",
        type=port,
        metavar="PORT",
        help="serve the live web view on 127.0.0.1:PORT (0: a free port; its address is printed on stderr)",
    )
    m.add_argument(
        "--reload-dir",
        metavar="DIR",
        help="~/reload may also read rule files under DIR (symlinks and .. resolved first); "
        "default: only the rule file the Manager runs. Give a directory only the operator can write to",
    )
    m.add_argument(
        "--decide",
        choices=DECIDE,
        default=DEFAULT_DECIDE,
        help="what the ~/decide service takes: off (the default: the context comes from the Context "
        "Listener), events-only (an event, no measure values) or all (values and an event; simulation, tests)",
    )
    m.add_argument(
        "--no-autostart",
        dest="autostart",
        action="store_false",
        help="ROS 2: stay unconfigured until a lifecycle manager configures and activates the node "
        "(default: configure and activate at once)",
    )
    return m


def _add_layers(nodes: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """``layers``: the COP Layer Manager, from the same rules and clause options as the Manager."""
    la = nodes.add_parser("layers", help="the COP Layer Manager: publishes active layers (latched)")
    la.add_argument("rules", nargs="?", help="the rule file (or the `rules` parameter)")
    add_clause_options(la)  # as the manager's, or the two choose different layers
    return la


def _add_listener(nodes: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """``listener``: the Context Listener, from a mapping file."""
    li = nodes.add_parser("listener", help="the Context Listener: robot topics -> measures and events")
    li.add_argument("mapping", nargs="?", help="the mapping file (or the `mapping` parameter)")
    li.add_argument("--rules", help="check the mapping against these rules")
    return li


def _add_task(nodes: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """``task``: a task node, its module of tasks, and what it does when the Manager is away."""
    t = nodes.add_parser("task", help="a task node: layered implementations of rules")
    t.add_argument("rules", nargs="?", help="the rule file (or the `rules` parameter)")
    t.add_argument(
        "--module",
        help="a module (or a .py file) with install(node) binding tasks/capabilities; "
        "found in the current directory and on --path",
    )
    t.add_argument(
        "--path", action="append", default=[], metavar="DIR", help="also look for --module here (repeatable)"
    )
    t.add_argument("--name", default="task", help="the task node's name (default task)")
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
        type=seconds,
        default=2.0,
        metavar="SECONDS",
        help="how long a task's request waits for the Manager's answer (default 2)",
    )
    return t


def _add_guard(nodes: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """``guard``: the topics it guards (a mapping's ``guards``, or one route given here)."""
    g = nodes.add_parser(
        "guard",
        help="forward a topic's messages (any type) only while the event they stand for is permitted",
    )
    g.add_argument("mapping", nargs="?", help="a mapping file with a `guards` section")
    g.add_argument("--rules", help="check the guarded events against these rules")
    g.add_argument("--from", dest="source", metavar="TOPIC", help="guard one topic without a mapping file...")
    g.add_argument("--to", dest="target", metavar="TOPIC", help="...forwarding to this topic...")
    g.add_argument(
        "--type",
        dest="msg_type",
        metavar="TYPE",
        help="...messages of this type (geometry_msgs/msg/Twist)...",
    )
    g.add_argument("--event", metavar="EVENT", help="...only while this event is permitted")
    g.add_argument(
        "--manager",
        help="the Manager node's name, whose ~/request service is asked (default: from --namespace)",
    )
    g.add_argument(
        "--timeout",
        type=seconds,
        default=0.5,
        metavar="SECONDS",
        help="how long a message waits for the Manager's answer before it is dropped (default 0.5)",
    )
    return g


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


def options(t: Any, args: argparse.Namespace, node: str) -> argparse.Namespace:
    """``args`` with the node's ROS parameters applied (a parameter given wins over the option)."""
    params = getattr(t, "parameters", None)
    if params is None:
        return args
    names = PARAMETERS[node]
    values = params({n: getattr(args, n, None) for n in names})
    return argparse.Namespace(**{**vars(args), **values})


def _required(value: Any, what: str, node: str) -> Any:
    if not value:
        raise UserError(
            f"the {node} node needs {what}",
            hint=f"give it as the first argument, or as the `{what.split()[-1]}` parameter",
        )
    return value


def run(args: argparse.Namespace) -> int:
    """Run the chosen node until SIGINT/SIGTERM, or launch a file, or play the demo.

    Given on the command line, rules and mapping are loaded and checked before the
    middleware starts, so a mistake in them is reported at once, with exit 1; given as
    parameters, as soon as the node has read its parameters.
    """
    backend, node = args.backend, args.node
    if node == "launch":
        path = input_file(args.file, "the launch file", text=True)
        ros_setup.require_launch_middleware(path)  # once, not once per node
        return ros.launch(path)
    if node == "demo":
        ros_setup.require_middleware(backend, args.wire)
        return ros.run_demo(backend, args.namespace, args.json, wire=args.wire)
    ros_args = list(getattr(args, "ros_args", []) or [])
    _refuse_on_ros1(args, backend, node, ros_args)
    _check_files(args, node)
    _check_types(backend, _robot_types(args, node))
    if node == "task" and args.module:  # imported now: a module without install(node) is said at once
        ros.load_module(args.module, args.path)
    ros_setup.require_middleware(backend, args.wire)  # after the files: their mistakes are said first
    name = node_name(args.namespace, node if node != "task" else args.name)
    lifecycle = backend == "ros2" and node == "manager"
    make = _maker(args, node, lifecycle)
    if backend == "ros2" and not os.environ.get("ROS_DOMAIN_ID"):
        print("cosleec: note: ROS_DOMAIN_ID is not set (domain 0)", file=sys.stderr)
    return ros.serve(backend, node, make, name, wire=args.wire, ros_args=ros_args, lifecycle=lifecycle)


def _refuse_on_ros1(args: argparse.Namespace, backend: str, node: str, ros_args: list[str]) -> None:
    """What ROS 1 has not: ROS 2's ``--ros-args`` (parameters are ``_name:=value``), lifecycle nodes."""
    if backend == "ros1" and (
        "--ros-args" in ros_args or any(a in ("-p", "--params-file") for a in ros_args)
    ):
        raise UserError(
            "ROS 1 takes no --ros-args",
            hint="give a node's private parameters as _name:=value (e.g. _semantics:=nested)",
        )
    if backend == "ros1" and node == "manager" and not args.autostart:
        raise UserError(
            "--no-autostart: ROS 1 has no lifecycle nodes", hint="the ROS 1 Manager enforces from its start"
        )


def _check_files(args: argparse.Namespace, node: str) -> None:
    """The rule file read, and the Manager's files and directories checked, before the middleware
    starts: a mistake is reported at once."""
    if (node in ("layers", "task") and args.rules) or (node == "manager" and args.rules and args.autostart):
        RuleSet.from_file(args.rules)  # (a managed Manager reads its rules when configured)
    if node != "manager":
        return
    for option, what, path in (  # written by the node: the directory must exist (none is created)
        ("--audit", "the audit log", args.audit),
        ("--journal", "the journal", args.journal),
        ("--record", "the recording", args.record),
    ):
        if path:
            output_file(path, what, option)
    if args.reset_journal and not args.journal:
        raise UserError("--reset-journal needs --journal", hint="give the journal to start afresh from")
    if args.reload_dir and not os.path.isdir(args.reload_dir):
        raise UserError(
            f"--reload-dir {args.reload_dir!r} is not a directory",
            hint="give an existing directory of rule files that only the operator can write to",
        )


def _robot_types(args: argparse.Namespace, node: str) -> list[tuple[str, str, str]]:
    """(where, what, message type) of the robot's topics a listener or guard reads, from the
    mapping (checked against the rules, if given) or the command line; read and checked now."""
    early = RuleSet.from_file(args.rules) if node in ("listener", "guard") and args.rules else None
    typed: list[tuple[str, str, str]] = []
    if node == "listener" and args.mapping:
        mapping = Mapping.load(
            input_file(args.mapping, "the mapping", text=True),
            dict(early.measures) if early else None,
            early.events if early else None,
        )
        typed += [(e.where or args.mapping, e.label, e.type) for e in mapping.entries]
    if node == "guard" and args.mapping:
        routes = load_routes(
            input_file(args.mapping, "the mapping", text=True), early.events if early else None
        )
        typed += [(args.mapping, f"guards.{r.source}", r.type) for r in routes]
    if node == "guard" and _one_route(args):
        r = _command_line_route(args, early.events if early else None)
        typed.append(("--type", f"the guard of {r.source}", r.type))
    return typed


def _one_route(args: argparse.Namespace) -> bool:
    """Does the command line give the guard its one route (``--from``, ``--to``, ``--type``, ``--event``)?"""
    return bool(args.source or args.target or args.msg_type or args.event)


def _command_line_route(args: argparse.Namespace, events: frozenset[str] | None) -> Route:
    """The guard's one route, from ``--from``, ``--to``, ``--type`` and ``--event``."""
    spec = {"to": args.target, "type": args.msg_type, "event": args.event}
    return route(str(args.source or ""), spec, "--from/--to/--type/--event", events)


def _maker(args: argparse.Namespace, node: str, lifecycle: bool) -> Callable[[Any], Any]:
    """``make(transport)``, which builds the node once the middleware is up, as :func:`cosleec.ros.serve`
    wants it: the node's ROS parameters win over the options, and the files they name are read then."""

    def make(t: Any) -> Any:
        o = options(t, args, node)
        if node == "manager":
            return _manager(t, o, args, lifecycle)
        rules = (
            RuleSet.from_file(_required(o.rules, "a rule file: rules", node))
            if node in ("layers", "task") or o.rules
            else None
        )
        if node == "layers":
            assert rules is not None
            return LayersNode(
                t, rules, namespace=o.namespace, semantics=o.semantics, unknown=Unknowns(o.unknown)
            )
        if node == "listener":
            mapping = Mapping.load(
                _required(o.mapping, "a mapping file: mapping", node),
                dict(rules.measures) if rules else None,
                rules.events if rules else None,
            )
            return ListenerNode(t, mapping, namespace=o.namespace)
        if node == "guard":
            return _guard(t, o, args, rules)
        assert rules is not None
        return _task(t, o, rules)

    return make


def _manager(t: Any, o: argparse.Namespace, args: argparse.Namespace, lifecycle: bool) -> Any:
    """The Manager node; on ROS 2 a lifecycle node (:class:`cosleec.ros.ManagedManager`) that
    builds it when configured. The live web view's address, if any, is printed on stderr."""
    path = _required(o.rules, "a rule file: rules", "manager")
    sim = bool(o.sim_time) or bool(getattr(t, "use_sim_time", lambda: False)())
    # a reset is for the first Manager of this process only: a lifecycle node configured
    # again restores the journal the first one wrote
    reset = [bool(args.reset_journal)]
    # --web: the view is found now (a missing extra is said at once); the node attaches it to
    # each Manager it builds, before it starts, and closes it before that Manager closes
    web = AttachedView(args.web) if args.web is not None else None

    def attach_web(manager: Manager) -> Callable[[], None] | None:
        if web is None:
            return None
        web.attach(manager)
        return web.close

    def build(active: bool) -> ManagerNode:
        node = ManagerNode(
            t,
            RuleSet.from_file(path),  # a lifecycle node reads it when configured
            namespace=o.namespace,
            semantics=o.semantics,
            sim_time=sim,
            audit=o.audit,
            record=o.record,
            record_format=args.record_format,
            status_each=o.status_each,
            unknown=o.unknown,
            journal=o.journal,
            priorities=o.priority,
            priority_semantics=o.priority_semantics,
            priority_lead=o.priority_lead,
            explanations=args.explanations,
            rules_path=o.rules,
            active=active,
            on_manager=attach_web,
            reload_dir=args.reload_dir,
            decide=args.decide,
            reset_journal=bool(reset and reset.pop()),
        )
        if web is not None and web.url:
            print(f"cosleec: live web view at {web.url}", file=sys.stderr, flush=True)
        return node

    if not lifecycle:
        return build(True)
    return ros.ManagedManager(t, build, path, autostart=o.autostart)


def _guard(t: Any, o: argparse.Namespace, args: argparse.Namespace, rules: RuleSet | None) -> GuardNode:
    """The guard node: its one route from the command line, else the routes of its mapping."""
    events = rules.events if rules else None
    if _one_route(args):
        routes = [_command_line_route(args, events)]
    else:
        routes = load_routes(_required(o.mapping, "a mapping file: mapping", "guard"), events)
    return GuardNode(
        t,
        routes,
        manager=o.manager or "/" + node_name(o.namespace, "manager"),
        namespace=o.namespace,
        timeout=o.timeout,
    )


def _task(t: Any, o: argparse.Namespace, rules: RuleSet) -> Any:
    """A task node, with the tasks its module installs, serving the rules of ``--only`` (or all)."""
    tn = TaskNode(
        t,
        rules,
        namespace=o.namespace,
        name=o.name,
        status_each=o.status_each,
        when_manager_down=o.when_manager_down,
        request_timeout=o.request_timeout,
    )
    ros.load_module(_required(o.module, "a task module: --module", "task"), o.path).install(tn)
    only = o.only.split(",") if o.only else None
    return tn.start(only)


def _check_types(backend: str, typed: list[tuple[str, str, str]]) -> None:
    """A message type of the robot's topics that this environment lacks is a UserError naming where it is given.

    Checked only when the middleware can be imported here (importing message classes starts
    no middleware); without it, starting the node says that the middleware is missing.
    """
    if not typed or importlib.util.find_spec("rclpy" if backend == "ros2" else "rospy") is None:
        return
    from cosleec.ros import MessageTypeError, message_class

    for where, what, type_name in typed:
        try:
            message_class(type_name)
        except MessageTypeError as e:
            raise MessageTypeError(
                f"{what}: {e.message}",
                where=where,
                hint=e.hint
                or "give the type as package/msg/Type (std_msgs/msg/Bool); "
                f"`{'ros2 interface list' if backend == 'ros2' else 'rosmsg list'}` lists those installed",
            ) from None

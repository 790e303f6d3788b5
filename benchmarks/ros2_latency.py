"""End-to-end latency of CO-SLEEC over ROS 2, against raw rclpy, in separate processes.

Raw: a ping-pong of ``cosleec_interfaces/msg/Event`` (the type the end-to-end path carries)
through an rclpy echo process: benchmark -Ping-> echo -Pong-> benchmark, 2 hops.
End to end: the benchmark sends a context message that switches a layer, then the trigger;
the Manager (own process) decides under the new layer and sends the obligation; the task
node (own process) dispatches the layered implementation, which reports the response event;
the benchmark stops the clock when that report arrives: benchmark -> Manager -> task node ->
benchmark, 3 hops (plus the context message, published just before the trigger). Both are
round trips measured interleaved in the same run, on the same machine; the ratios of their
p50 and p99 are the figures (targets <= 2.0 and <= 1.8, issue 32). With 3 hops against 2, the structural floor of
that ratio is about 1.5 (``hop_ratio``). The cosleec topics carry their ``cosleec_interfaces``
types, as deployed (the default wire).
Third path, interleaved too: the same three hops and four messages through two relays
(``_ros2_relay.py``) made in the shape of the running Manager and task node, read from the
ROS graph -- the same publishers, subscriptions and services with the same types and
QoS-event callbacks -- that forward and do nothing else: the floor of the node design in
rclpy (``relay_ratio_p50``/``_p99`` against the raw round trip; ``ratio_to_relay_*``: ours
against it). The echo, the benchmark and the cosleec nodes spin the
same rclpy executor (the SingleThreadedExecutor).
Runs inside a private network namespace (ros-setup.md §1): it re-executes itself there.
"""

from __future__ import annotations

import json
import os
import random
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from cosleec.testing import percentile

HERE = Path(__file__).resolve().parent
RULES = """def_start event Ping event Pong measure toggle : boolean def_end
rule_start R when Ping then Pong within 5 seconds unless toggle then Pong within 5 seconds rule_end
"""

RAW_HOPS = 2  # benchmark -> echo -> benchmark
E2E_HOPS = 3  # benchmark -> Manager -> task node -> benchmark (the context message rides along)


def isolated() -> bool:
    return [n for _, n in socket.if_nameindex()] == ["lo"]


def reexec_isolated() -> None:
    env = dict(
        os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(random.randint(1, 100))
    )
    cmd = [
        "unshare",
        "--net",
        "--",
        "bash",
        "-c",
        'ip link set lo up && exec "$@"',
        "x",
        sys.executable,
        *sys.argv,
    ]
    os.execvpe("unshare", cmd, env)


def start_relays(node: Any, ns: str, tmp: Path, env: dict[str, str], procs: list[Any], qos: Any) -> Any:
    """Start the two relays (``_ros2_relay.py``) of the running Manager's and task node's shape,
    read from the ROS graph; return the function that times one round trip through them."""
    from cosleec_interfaces.msg import ContextUpdate, Event, MeasureValue

    def mirrored(entities: list[tuple[str, list[str]]]) -> list[tuple[str, str]]:
        # what rclpy makes for every node by itself (parameters, type descriptions, /rosout) is
        # made by the relay's rclpy too
        auto = ("rcl_interfaces/", "type_description_interfaces/")
        return [
            (name, types[0])
            for name, types in entities
            if not types[0].startswith(auto) and name not in ("/rosout", "/parameter_events")
        ]

    shape = {}
    for role in ("manager", "task"):  # the nodes are named after the namespace and their role
        name, space = f"{ns.strip('/')}_{role}", "/"
        shape[role] = {
            "publishers": mirrored(node.get_publisher_names_and_types_by_node(name, space)),
            "subscriptions": mirrored(node.get_subscriber_names_and_types_by_node(name, space)),
            "services": mirrored(node.get_service_names_and_types_by_node(name, space)),
        }
    (tmp / "shape.json").write_text(json.dumps(shape))
    for role in ("manager", "task"):
        procs.append(
            subprocess.Popen(
                [sys.executable, str(HERE / "_ros2_relay.py"), role, str(tmp / "shape.json")],
                env=env,
                stdout=subprocess.DEVNULL,
            )
        )
    ctx = node.create_publisher(ContextUpdate, "/bench_relay/context", qos)
    ev = node.create_publisher(Event, "/bench_relay/events", qos)
    got = threading.Event()
    arrivals: list[float] = []

    def answered(m: Event) -> None:
        if m.event == "Pong":
            arrivals.append(time.perf_counter())
            got.set()

    node.create_subscription(Event, "/bench_relay/events", answered, qos)
    toggle = [False]

    def relay_once(wait: float = 5.0) -> float:
        got.clear()
        toggle[0] = not toggle[0]
        t0 = time.perf_counter()
        value = MeasureValue(name="toggle", kind=MeasureValue.BOOLEAN, boolean=toggle[0])
        ctx.publish(ContextUpdate(values=[value]))
        ev.publish(Event(event="Ping"))
        if not got.wait(wait):
            raise TimeoutError("no answer through the relays")
        return arrivals[-1] - t0

    deadline = time.monotonic() + 60
    while True:  # until every link of the relays' path is matched
        try:
            relay_once(0.5)
            return relay_once
        except TimeoutError:
            if time.monotonic() > deadline:
                raise


def main() -> int:
    sys.path.insert(0, str(HERE))
    from _common import args, report

    a = args(__doc__ or "")
    if not isolated():
        reexec_isolated()
    import rclpy
    from cosleec_interfaces.msg import ContextUpdate, Event, MeasureValue, Status
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from cosleec.ros import env as rosenv
    from cosleec.ros.launch import node_command, start, stop

    n = 1000 if a.quick else 5000  # a p99 of fewer samples swings with one disturbance
    env = rosenv.ros2_env()
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), env.get("PYTHONPATH", "")])
    os.environ.update(env)
    tmp = Path(tempfile.mkdtemp(prefix="cosleec-bench-"))
    rules = tmp / "bench.sleec"
    rules.write_text(RULES)
    ns = "/bench_cosleec"
    procs = [
        subprocess.Popen([sys.executable, str(HERE / "_ros2_pong.py")], env=env, stdout=subprocess.DEVNULL),
        start(node_command("ros2", ["manager", str(rules)], ns), env=env, stdout=subprocess.DEVNULL),
        start(
            node_command("ros2", ["task", str(rules), "--module", "_ros2_bench_tasks"], ns),
            env=env,
            stdout=subprocess.DEVNULL,
        ),
    ]
    rclpy.init()
    node = rclpy.create_node("bench_driver")
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    got = threading.Event()
    arrivals: list[float] = []

    def arrived(_m: object) -> None:
        arrivals.append(time.perf_counter())
        got.set()

    ping = node.create_publisher(Event, "/bench/ping", qos)
    node.create_subscription(Event, "/bench/pong", arrived, qos)
    ctx = node.create_publisher(ContextUpdate, f"{ns}/context", qos)
    ev = node.create_publisher(Event, f"{ns}/events", qos)
    reports: list[float] = []
    rep = threading.Event()

    def reported(m: Event) -> None:
        if m.event == "Pong":
            reports.append(time.perf_counter())
            rep.set()

    node.create_subscription(Event, f"{ns}/events", reported, qos)
    status: dict[str, dict[str, int]] = {}

    def on_status(m: Status) -> None:
        s = json.loads(m.record)
        status[s["node"]] = s.get("subscribers", {})

    node.create_subscription(Status, f"{ns}/status", on_status, qos)
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        deadline = time.monotonic() + 60

        def connected() -> bool:  # every link of both paths, as the nodes themselves report it
            m, t = status.get("manager", {}), status.get("task", {})
            return (
                ping.get_subscription_count() >= 1
                and ctx.get_subscription_count() >= 1
                and ev.get_subscription_count() >= 1
                and node.count_publishers("/bench/pong") >= 1
                and m.get("obligations", 0) >= 1
                and t.get("events", 0) >= 2
            )

        while not connected():
            if time.monotonic() > deadline:
                raise TimeoutError(f"the benchmark graph did not connect: {status}")
            time.sleep(0.05)

        seq = [0]

        def raw_once() -> float:
            got.clear()
            seq[0] += 1
            t0 = time.perf_counter()
            ping.publish(Event(event="Ping", sender="bench_driver", seq=seq[0]))
            if not got.wait(5):
                raise TimeoutError("no pong")
            return arrivals[-1] - t0

        toggle = [False]

        def e2e_once() -> float:
            rep.clear()
            toggle[0] = not toggle[0]
            t0 = time.perf_counter()
            value = MeasureValue(name="toggle", kind=MeasureValue.BOOLEAN, boolean=toggle[0])
            ctx.publish(ContextUpdate(values=[value]))  # switches R's layer
            ev.publish(Event(event="Ping"))
            if not rep.wait(5):
                raise TimeoutError("no report from the task node")
            return reports[-1] - t0

        relay_once = start_relays(node, ns, tmp, env, procs, qos)
        for _ in range(50):  # warm up the paths (discovery, first dispatch)
            raw_once()
            e2e_once()
            relay_once()
        raw, e2e, relay = [], [], []
        for _ in range(n):  # interleaved, so that machine noise hits them alike
            raw.append(raw_once() * 1e6)
            e2e.append(e2e_once() * 1e6)
            relay.append(relay_once() * 1e6)
    finally:
        executor.shutdown()
        spinner.join(5)
        node.destroy_node()
        rclpy.shutdown()
        for p in procs:
            stop(p)
    result = {
        "benchmark": "ros2_latency",
        "samples": n,
        "raw_p50_us": round(statistics.median(raw), 1),
        "raw_p99_us": round(percentile(raw, 99), 1),
        "e2e_p50_us": round(statistics.median(e2e), 1),
        "e2e_p99_us": round(percentile(e2e, 99), 1),
        "ratio_p50": round(statistics.median(e2e) / statistics.median(raw), 2),
        "ratio_p99": round(percentile(e2e, 99) / percentile(raw, 99), 2),
        "target_ratio_p50": 2.0,
        "target_ratio_p99": 1.8,
        "relay_p50_us": round(statistics.median(relay), 1),
        "relay_p99_us": round(percentile(relay, 99), 1),
        "relay_ratio_p50": round(statistics.median(relay) / statistics.median(raw), 2),
        "relay_ratio_p99": round(percentile(relay, 99) / percentile(raw, 99), 2),
        "ratio_to_relay_p50": round(statistics.median(e2e) / statistics.median(relay), 2),
        "ratio_to_relay_p99": round(percentile(e2e, 99) / percentile(relay, 99), 2),
        "raw_message_type": "cosleec_interfaces/msg/Event",
        "raw_hops": RAW_HOPS,
        "e2e_hops": E2E_HOPS,
        "e2e_messages": E2E_HOPS + 1,
        "hop_ratio": round(E2E_HOPS / RAW_HOPS, 2),
        "sleec_at_runtime_mean_ms": 76,
        "quick": a.quick,
    }
    rows = [
        (
            f"raw rclpy ping-pong (Event, {RAW_HOPS} hops)",
            f"p50 {result['raw_p50_us']} us",
            f"p99 {result['raw_p99_us']} us",
        ),
        (
            f"CO-SLEEC end to end ({E2E_HOPS} hops + context)",
            f"p50 {result['e2e_p50_us']} us",
            f"p99 {result['e2e_p99_us']} us",
        ),
        (
            "ratio (e2e / raw)",
            f"p50 {result['ratio_p50']}x",
            f"p99 {result['ratio_p99']}x (targets <= 2.0, <= 1.8)",
        ),
        ("hop ratio (structural floor)", f"{result['hop_ratio']}x", "3 hops against 2"),
        (
            "relays of the nodes' shape (same hops)",
            f"p50 {result['relay_ratio_p50']}x raw",
            f"p99 {result['relay_ratio_p99']}x raw; e2e / relays {result['ratio_to_relay_p50']}x, "
            f"{result['ratio_to_relay_p99']}x",
        ),
    ]
    report("ros2_latency", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())

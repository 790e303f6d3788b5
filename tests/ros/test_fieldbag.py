"""A field bag of a real rclpy publisher, judged: ``cosleec conforms RULES BAG --mapping M``.

A robot process (rclpy, its own process) publishes std_msgs and sensor_msgs on its topics; a
subscriber here records what it receives, serialized as it came off the wire, with rosbags'
rosbag2 MCAP writer and the receive time -- what ``ros2 bag record`` does (the project's own
recorder writes cosleec's streams, not arbitrary robot topics). The bag is then judged
through the mapping. ROS 2 only, inside the test's network namespace (conftest)."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rosbags")

from cosleec.cli.main import main
from tests.bagwriter import write_raw_bag

RULES = """\
def_start
    event UserFallen
    event CallSupport
    event RecordVideo
    measure userConsent : boolean
    measure batteryLevel : numeric
def_end
rule_start
    R1 when UserFallen then CallSupport within 30 seconds
    R2 when UserFallen then not RecordVideo within 60 seconds unless userConsent
rule_end
"""

TOPICS = {  # topic -> (type, what the mapping makes of it)
    "/consent": ("std_msgs/msg/Bool", "measures", "userConsent: {topic: NS/consent, type: std_msgs/Bool}"),
    "/battery": (
        "sensor_msgs/msg/BatteryState",
        "measures",
        "batteryLevel: {topic: NS/battery, type: sensor_msgs/msg/BatteryState, field: percentage}",
    ),
    "/fall": (
        "std_msgs/msg/Bool",
        "events",
        "UserFallen: {topic: NS/fall, type: std_msgs/Bool, equals: true}",
    ),
    "/support": (
        "std_msgs/msg/String",
        "events",
        "CallSupport: {topic: NS/support, type: std_msgs/String, equals: calling}",
    ),
    "/camera/recording": (
        "std_msgs/msg/Bool",
        "events",
        "RecordVideo: {topic: NS/camera/recording, type: std_msgs/Bool, equals: true}",
    ),
}

ROBOT = r"""
import sys, time
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState
from std_msgs.msg import Bool, String

ns = sys.argv[1]
rclpy.init()
node = rclpy.create_node("field_robot")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
types = {"/consent": Bool, "/battery": BatteryState, "/fall": Bool, "/support": String, "/camera/recording": Bool}
pubs = {name: node.create_publisher(t, ns + name, qos) for name, t in types.items()}
deadline = time.monotonic() + 30
while any(p.get_subscription_count() == 0 for p in pubs.values()):
    if time.monotonic() > deadline:
        sys.exit("field_robot: nobody subscribed")
    time.sleep(0.05)
time.sleep(0.5)
for name, msg in [("/consent", Bool(data=False)), ("/battery", BatteryState(percentage=0.8)),
                  ("/fall", Bool(data=False)), ("/fall", Bool(data=True)), ("/fall", Bool(data=True)),
                  ("/support", String(data="calling")), ("/camera/recording", Bool(data=True))]:
    pubs[name].publish(msg)
    time.sleep(0.15)
time.sleep(0.5)
node.destroy_node()
rclpy.shutdown()
"""


def test_a_bag_of_a_real_publisher_is_judged_through_the_mapping(
    backend: str,
    namespace: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    request: pytest.FixtureRequest,
) -> None:
    if backend != "ros2":  # before the transport: no ROS 1 master started for a skip
        pytest.skip("rosbag2 of a live ROS 2 publisher: ROS 2 only")
    transport = request.getfixturevalue("transport")
    received: list[tuple[int, str, str, bytes]] = []
    lock = threading.Lock()

    def recorder(name: str, msgtype: str) -> Any:
        def got(data: Any) -> None:
            with lock:
                received.append((time.time_ns(), namespace + name, msgtype, bytes(data)))

        return got

    for name, (msgtype, _, _) in TOPICS.items():
        transport.subscribe_raw(namespace + name, msgtype, recorder(name, msgtype))
    robot = subprocess.Popen([sys.executable, "-c", ROBOT, namespace], env=dict(os.environ))
    try:
        assert robot.wait(timeout=60) == 0
    finally:
        if robot.poll() is None:
            robot.kill()
            robot.wait()
    deadline = time.monotonic() + 5
    while len(received) < 7 and time.monotonic() < deadline:
        time.sleep(0.05)
    with lock:
        assert len(received) == 7, [r[1] for r in received]
        bag = write_raw_bag(tmp_path / "field", list(received))
        camera = next(stamp for stamp, topic, _, _ in received if topic.endswith("/camera/recording"))
    (tmp_path / "rules.sleec").write_text(RULES)
    lines = {"measures": [], "events": []}
    for _, section, entry in TOPICS.values():
        lines[section].append("  " + entry.replace("NS", namespace))
    (tmp_path / "mapping.yaml").write_text("".join(f"{k}:\n" + "\n".join(v) + "\n" for k, v in lines.items()))

    rc = main(
        ["conforms", str(tmp_path / "rules.sleec"), str(bag), "--mapping", str(tmp_path / "mapping.yaml")]
    )
    out = " ".join(capsys.readouterr().out.split())
    assert rc == 1, out
    assert "7 messages on 5 mapped topics" in out and "gap" not in out
    assert "violated R2 (default)" in out and "violated R1" not in out  # support was called in time
    bag_time = f"{camera // 10**9}.{camera % 10**9:09d}"
    assert f"RecordVideo: {namespace}/camera/recording at " in out and f"(bag time {bag_time})" in out
    assert f"from trigger UserFallen: {namespace}/fall at " in out
    assert "1 violation, 0 pending" in out  # (none blocked: no "(N blocked)")

"""The Manager node with an explanations file (issue 33, item 1): its published decisions
carry the sentence for people; `cosleec ros2 manager --explanations FILE` takes the file."""

from __future__ import annotations

import json
from pathlib import Path

from cosleec.cli.main import build_parser
from cosleec.nodes import LocalBus, LocalTransport, ManagerNode
from cosleec.runtime import RuleSet

from .support import collect

RULES = """def_start event CameraOn event RecordVideo measure patientConsented : boolean def_end
rule_start
R2 when CameraOn then not RecordVideo within 10 minutes unless patientConsented
rule_end"""


def test_the_node_publishes_what_the_robot_says(tmp_path: Path) -> None:
    said = tmp_path / "r.explanations.yaml"
    said.write_text("R2: I won't record video in your room without your consent.\n")
    bus = LocalBus()
    decisions = collect(bus, "/cosleec/decisions")
    t = LocalTransport(bus)
    node = ManagerNode(t, RuleSet.from_text(RULES), sim_time=True, explanations=str(said))
    try:
        t.publish("/cosleec/events", json.dumps({"event": "CameraOn"}))
        assert bus.wait_idle()
        (d,) = [r for r in decisions if r.get("rule") == "R2"]
        assert d["for_people"] == "I won't record video in your room without your consent."
    finally:
        node.close()


def test_the_manager_command_takes_an_explanations_file() -> None:
    args = build_parser().parse_args(["ros2", "manager", "rules.sleec", "--explanations", "x.yaml"])
    assert args.explanations == "x.yaml"

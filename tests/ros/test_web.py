"""The Manager node's live web view (``cosleec ros2 manager ... --web PORT``) over real middleware.

The page itself is tested in a browser in tests/unit/views/test_web.py; here the node serves
it on 127.0.0.1 (inside the test's private network namespace), its state follows what the
robot's topics told the Manager, and its stream sends a message.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from cosleec.ros import env as rosenv
from cosleec.ros.demo import System
from cosleec.ros.driver import Driver


def test_the_manager_node_serves_the_live_web_view(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    pytest.importorskip("sse_starlette", reason="the web extra is not installed here (scripts/setup-ros)")
    port = rosenv.free_port()
    url = f"http://127.0.0.1:{port}/"
    with System(backend, namespace, env=graph, manager_args=["--web", str(port)]) as system:
        driver = Driver(transport, namespace)
        driver.ready()
        driver.set({"userUndressed": True, "userDistressed": "low"})
        driver.event("CurtainOpenRequest")
        driver.quiet()
        deadline = time.monotonic() + 20
        while True:  # the node answers once it is up; the decision is in its state at once
            try:
                s = httpx.get(url + "state", timeout=2).json()
                if s["decisions"]:
                    break
            except httpx.HTTPError:
                pass
            assert time.monotonic() < deadline, "the Manager node's web view did not answer"
            time.sleep(0.1)
        [d] = s["decisions"]
        assert (d["rule"], d["layer"]) == ("R1", "R1.1") and "because userUndressed was true" in d[
            "explanation"
        ]
        context = {c["name"]: c["value"] for c in s["context"]}
        assert context["userUndressed"] is True and context["userDistressed"] == "low"
        assert {r["name"]: r["layer"] for r in s["rules"]}["R1"] == "R1.1"
        assert s["clock"] == "virtual"  # --sim-time: the node's clock follows /clock
        with httpx.stream("GET", url + "events", timeout=5) as r:
            assert r.headers["content-type"].startswith("text/event-stream")
            lines = r.iter_lines()
            assert next(lines) == "event: state"
            first = json.loads(next(lines).removeprefix("data: "))
        assert first["decisions"][0]["id"] == d["id"]
        assert httpx.post(url + "control/event", json={"event": "CurtainOpenRequest"}).status_code == 403
        assert system.codes() == [None, None, None]

"""examples/bt/curtains_and_camera.py plays its scenario and draws its tree with py_trees' dot export."""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "examples" / "bt" / "curtains_and_camera.py"


def load() -> object:
    spec = importlib.util.spec_from_file_location("bt_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["bt_example"] = module
    spec.loader.exec_module(module)
    return module


def test_the_example_runs_each_layer_and_r6_stops_the_camera(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    example = load()
    render = tmp_path / "img" if shutil.which("dot") else None
    assert example.main(["--render", str(render)] if render else []) == 0  # type: ignore[attr-defined]
    out = capsys.readouterr().out
    runs = [line.split(": ")[1].split(",")[0] for line in out.splitlines() if " on " in line and ": " in line]
    assert runs == ["SUCCESS"] * 4 + ["FAILURE"]
    layers = [line.split(", ", 1)[1].split(":")[0] for line in out.splitlines() if " on " in line]
    assert layers == ["default", "R1.1", "R1.2", "R10.1", "R10.1"]
    assert "refused: RecordVideo is forbidden by R6" in out
    assert out.count("does OpenCurtains") == 2 and "does RecordVideo" in out.split("-- UserFallen")[0]
    assert "does RecordVideo" not in out.split("-- UserFallen")[1]
    assert "owed: 1 owed, next CallSupport by 60 s (R4)" in out
    if render:
        svg = (render / "bt-curtains-camera.svg").read_text(encoding="utf-8")
        assert "R1 on CurtainOpenRequest" in svg and "Guard RecordVideo" in svg

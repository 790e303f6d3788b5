"""``cosleec timeline BAG --mapping M --rules R``: a field bag drawn as the run the rules made
of it -- the same replay ``conforms`` judges, decided by an embedded Manager in bag time."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("rosbags")

from cosleec.cli.bag_timeline import bag_records
from cosleec.cli.main import main
from tests.bagwriter import write_bag
from tests.unit.test_conforms_bags import COMPLIANT, MAPPING, RULES, VIOLATING


def files(tmp_path: Path) -> tuple[str, str]:
    (tmp_path / "rules.sleec").write_text(RULES)
    (tmp_path / "mapping.yaml").write_text(MAPPING)
    return str(tmp_path / "rules.sleec"), str(tmp_path / "mapping.yaml")


def test_the_rules_decide_over_the_bag_in_bag_time(tmp_path: Path) -> None:
    rules, mapping = files(tmp_path)
    bag = write_bag(tmp_path / "run", "mcap", VIOLATING)
    records = bag_records(str(bag), mapping, rules)
    decisions = [(r["rule"], r["time"]) for r in records if r["kind"] == "decision"]
    assert ("R1", 10.0) in decisions and ("R2", 10.0) in decisions  # the fall, at 10 s of bag time
    events = [(r["event"], r["time"]) for r in records if r["kind"] == "event"]
    assert ("RecordVideo", 40.25) in events
    broken = [
        (r["rule"], r["time"]) for r in records if r["kind"] == "obligation" and r["status"] == "violated"
    ]
    assert broken == [("R2", 40.25)]  # the camera, recording while the fall's ban holds


def test_a_compliant_bag_has_no_violation(tmp_path: Path) -> None:
    rules, mapping = files(tmp_path)
    bag = write_bag(tmp_path / "run", "sqlite3", COMPLIANT)
    records = bag_records(str(bag), mapping, rules)
    assert not [r for r in records if r["kind"] == "obligation" and r["status"] == "violated"]
    assert ("R3", "fulfilled") in {(r["rule"], r["status"]) for r in records if r["kind"] == "obligation"}
    assert any(r["kind"] == "decision" for r in records)


def test_the_command_draws_it_and_asks_for_both_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, mapping = files(tmp_path)
    bag = write_bag(tmp_path / "run", "mcap", VIOLATING)
    out = tmp_path / "t.html"
    assert main(["timeline", str(bag), "--mapping", mapping, "--rules", rules, "-o", str(out)]) == 0
    assert out.read_text().startswith("<") and "R2" in out.read_text()
    assert main(["timeline", str(bag), "--mapping", mapping, "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "--mapping draws a field bag, which also needs --rules" in err and "Traceback" not in err

"""A mapping is type-checked wherever it is read: `cosleec analyse --mapping`, `conforms
--mapping`, `timeline --mapping` and the listener node (`cosleec ros2 listener`) all refuse
`not_equals: null` before doing anything else, at its file:line:col, naming the fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
RULES = str(ROOT / "src/cosleec/demo/assistive_care/rules.sleec")
MAPPING = ROOT / "examples/analysis/partial-mapping.yaml"


@pytest.mark.parametrize(
    "command",
    [
        ["analyse", RULES, "--check", "unproduced-input", "--mapping", "MAPPING"],
        ["conforms", RULES, "BAG", "--mapping", "MAPPING"],
        ["timeline", "BAG", "--rules", RULES, "--mapping", "MAPPING"],
        ["ros2", "listener", "MAPPING", "--rules", RULES],
    ],
    ids=lambda c: " ".join(c[:2]),
)
def test_a_null_comparison_is_refused_at_load_by_every_command_that_reads_a_mapping(
    command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = MAPPING.read_text(encoding="utf-8")
    assert "equals: open_curtains}" in text
    bad = tmp_path / "mapping.yaml"
    bad.write_text(text.replace("equals: open_curtains}", "not_equals: null}"), encoding="utf-8")
    given = {"BAG": str(tmp_path / "run"), "MAPPING": str(bad)}  # no bag: the mapping is read first
    rc = main([given.get(a, a) for a in command])
    err = capsys.readouterr().err
    assert rc != 0
    line = next(n for n, row in enumerate(text.splitlines(), 1) if "open_curtains" in row)
    assert f"{bad}:{line}:" in err and "`not_equals: null` compares with nothing" in err, err
    assert (
        "hint: to fire on every message of the topic, leave out the comparison and write `every_message: true`"
        in err
    )

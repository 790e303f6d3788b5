"""A rule file's ``semantics_start`` block is how the runtime reads its clauses, as ``check``
and ``analyse`` do: the option may say the same or nothing, never the opposite."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cosleec.errors import ConfigurationError
from cosleec.lang import HedgeSemantics
from cosleec.nodes import LayersNode, LocalBus
from cosleec.runtime import Manager, ReloadError, RuleSet, VirtualClock
from cosleec.semantics import conformance
from cosleec.semantics.trace import Recording

RULES = """def_start
  event E
  event A
  event B
  event C
  measure p: boolean
  measure q: boolean
def_end
rule_start
  R1 when E then A
    unless p then B
    unless q then C
rule_end
"""
NESTED = RULES + "semantics_start\n  unless nested\nsemantics_end\n"
LAST_WINS = RULES + "semantics_start\n  unless last-wins\nsemantics_end\n"


def clause(text: str, **options: object) -> int | None:
    """The clause R1 chooses when p is false and q true: 2 under last-wins, 0 under nested."""
    m = Manager.from_text(text, clock=VirtualClock(), dispatch=False, **options)
    m.start(check=False)
    m.update(p=False, q=True)
    (d,) = m.event("E")
    m.close()
    return d.clause


def test_the_file_s_block_chooses_the_clause() -> None:
    assert clause(RULES) == 2  # no block: SLEEC's last-wins
    assert clause(NESTED) == 0
    assert clause(LAST_WINS) == 2
    assert Manager.from_text(NESTED).semantics == HedgeSemantics.NESTED


def test_an_option_that_agrees_is_taken_and_one_that_contradicts_is_refused() -> None:
    assert clause(NESTED, semantics="nested") == 0
    assert clause(RULES, semantics="nested") == 0  # a file that declares nothing takes the option
    with pytest.raises(ConfigurationError) as e:
        Manager.from_text(NESTED, semantics="last-wins")
    assert "contradicts" in e.value.message and "nested" in e.value.message
    assert e.value.where.endswith(":15:3")  # the block's `unless nested`


def test_the_options_record_states_the_semantics_used(tmp_path: Path) -> None:
    audit = tmp_path / "audit.jsonl"
    m = Manager.from_text(NESTED, clock=VirtualClock(), dispatch=False, audit=str(audit))
    m.start(check=False)
    m.close()
    (options,) = [r for r in map(json.loads, audit.read_text().splitlines()) if r["kind"] == "options"]
    assert options["semantics"] == "nested"


def test_a_reload_cannot_change_the_semantics() -> None:
    m = Manager.from_text(RULES, clock=VirtualClock(), dispatch=False)
    m.start(check=False)
    with pytest.raises(ReloadError) as e:
        m.reload(RuleSet.from_text(NESTED))
    assert "restart" in e.value.hint
    m.reload(RuleSet.from_text(LAST_WINS))  # the same semantics, said out loud: taken
    assert m.semantics == HedgeSemantics.LAST_WINS
    m.close()
    pinned = Manager.from_text(RULES, clock=VirtualClock(), dispatch=False, semantics="nested")
    pinned.start(check=False)
    pinned.reload(RuleSet.from_text(NESTED))  # the option and the new file agree
    with pytest.raises(ReloadError):
        pinned.reload(RuleSet.from_text(LAST_WINS))
    pinned.close()


def test_conforms_judges_by_the_file_s_block_unless_the_log_says_otherwise() -> None:
    spec = RuleSet.from_text(NESTED).spec
    bare = Recording(steps=[], source="trace.json")
    choice = conformance.choose_reading(spec, bare, conformance.Given())
    assert choice.reading.semantics == HedgeSemantics.NESTED
    with pytest.raises(ConfigurationError):
        conformance.choose_reading(spec, bare, conformance.Given(semantics=HedgeSemantics.LAST_WINS))


def test_the_layers_node_reads_the_file_s_block() -> None:
    bus = LocalBus()
    try:
        assert LayersNode(bus.transport(), RuleSet.from_text(NESTED)).layer_manager.semantics == "nested"
        assert LayersNode(bus.transport(), RuleSet.from_text(RULES)).layer_manager.semantics == "last-wins"
    finally:
        bus.close()


def test_decide_on_the_command_line_follows_the_file(tmp_path: Path) -> None:
    path = tmp_path / "rules.sleec"
    path.write_text(NESTED)
    cosleec = str(Path(sys.executable).parent / "cosleec")
    argv = [cosleec, "decide", str(path), "--set", "p=false", "--set", "q=true", "--event", "E", "--json"]
    out = subprocess.run(argv, capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    assert [d["clause"] for d in json.loads(out.stdout)["decisions"]] == [0]
    wrong = subprocess.run([*argv, "--semantics", "last-wins"], capture_output=True, text=True, check=False)
    assert wrong.returncode == 1 and "contradicts" in wrong.stderr and "Traceback" not in wrong.stderr

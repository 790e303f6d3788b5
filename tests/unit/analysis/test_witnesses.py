"""Witness traces: judged by the reference semantics, readable back, accepted by ``conforms``."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cosleec.analysis import Finding
from cosleec.cli.main import main
from cosleec.lang import HedgeSemantics, Reading, load
from cosleec.semantics import judge, read_trace

from .support import analyse, sleec

ROOT = Path(__file__).resolve().parents[3]
CURTAINS = ROOT / "examples" / "analysis" / "curtains.sleec"

SOURCES = {
    "concern": sleec(
        "R1 when A then B within 5 seconds\nR2 when C then not B within 10 seconds",
        "concern_start\nc1 when A and {m} then C\nc2 when A then B within 3 seconds\nconcern_end",
    ),
    "runtime": sleec("R1 when A then B within 5 seconds\nR2 when C then not B within 3 seconds"),
    "clauses": sleec(
        "R1 when A then B within 5 seconds unless x then C within 5 seconds unless (t > 35)\n"
        "R2 when B then D within 2 seconds unless (d > 1) then E within d seconds unless y"
    ),
    "otherwise": sleec(
        "R1 when A then B within 5 seconds otherwise C within 2 seconds\nR2 when C then not D within 10 seconds",
        "concern_start\nc1 when A and {x} then C within 7 seconds\nconcern_end",
    ),
    "situation": sleec(
        "R1 when A then B within [6 seconds, 7 seconds]\nR2 when A then not B within 5 seconds"
    ),
}


def _findings(tmp_path: Path, name: str) -> tuple[Path, list[Finding]]:
    if name == "curtains":
        path = tmp_path / "curtains.sleec"
        shutil.copy(CURTAINS, path)
    else:
        path = tmp_path / f"{name}.sleec"
        path.write_text(SOURCES[name], encoding="utf-8")
    return path, analyse(path).findings


@pytest.mark.parametrize("name", [*sorted(SOURCES), "curtains"])
def test_every_witness_is_confirmed_and_reads_back_as_a_trace(tmp_path: Path, name: str) -> None:
    _, findings = _findings(tmp_path, name)
    witnessed = [f for f in findings if f.witness is not None]
    assert witnessed
    for n, f in enumerate(witnessed):
        w = f.witness
        assert w is not None
        assert w.confirmed, (f.code, f.subject, w.timeline)
        assert w.timeline and w.steps
        trace = tmp_path / f"w{n}.jsonl"
        trace.write_text(w.jsonl(), encoding="utf-8")
        back = read_trace(trace)
        assert [(s.t, s.event, dict(s.values)) for s in back] == [
            (s.t, s.event, dict(s.values)) for s in w.steps
        ]
        times = [s.t for s in back]
        assert times == sorted(times)
        assert back[-1].event is None  # a last step past every deadline
    codes = {f.code for f in witnessed}
    assert codes <= {"concern-raised", "runtime-conflict", "semantics-differ", "situational-conflict"}


def test_a_concern_witness_is_a_trace_the_rules_accept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, findings = _findings(tmp_path, "concern")
    concerns = {f.subject: f for f in findings if f.code == "concern-raised"}
    assert set(concerns) == {"c1", "c2"}
    for f in concerns.values():
        assert f.witness is not None
        trace = tmp_path / f"{f.subject}.jsonl"
        trace.write_text(f.witness.jsonl(), encoding="utf-8")
        assert main(["conforms", str(path), str(trace)]) == 0, f.witness.timeline
        events = [s.event for s in f.witness.steps]
        assert "A" in events
    c1 = concerns["c1"].witness
    assert c1 is not None
    # c1's situation: an A with m, and a C at its instant, after it
    steps = list(c1.steps)
    a = next(i for i, s in enumerate(steps) if s.event == "A" and s.values.get("m") is True)
    assert any(s.event == "C" and s.t == steps[a].t for s in steps[a + 1 :])
    capsys.readouterr()


def test_a_runtime_conflict_witness_shows_overlapping_windows(tmp_path: Path) -> None:
    """Judged again here, independently of the analysis' own confirmation: R1 owes B and R2
    forbids B, in windows that share an instant."""
    path, findings = _findings(tmp_path, "runtime")
    (f,) = [f for f in findings if f.code == "runtime-conflict"]
    assert f.witness is not None
    j = judge(load(path), list(f.witness.steps), Reading())
    owes = [v for v in j.verdicts if v.rule == "R1" and not v.negated and v.event == "B"]
    bans = [v for v in j.verdicts if v.rule == "R2" and v.negated and v.event == "B"]
    inf = float("inf")
    assert any(
        o.window[0] <= (inf if p.window[1] is None else p.window[1])
        and p.window[0] <= (inf if o.window[1] is None else o.window[1])
        for o in owes
        for p in bans
    ), f.witness.timeline


def test_a_semantics_differ_witness_fires_different_clauses_under_each_semantics(tmp_path: Path) -> None:
    path, findings = _findings(tmp_path, "clauses")
    spec = load(path)
    differ = [f for f in findings if f.code == "semantics-differ"]
    assert {f.subject for f in differ} == {"R1", "R2"}
    for f in differ:
        assert f.witness is not None
        picked = {}
        for sem in HedgeSemantics:
            j = judge(spec, list(f.witness.steps), Reading(semantics=sem))
            (fired,) = [x for x in j.firings if x.rule == f.subject and x.fired]
            picked[sem] = fired.clause
        assert picked[HedgeSemantics.LAST_WINS] != picked[HedgeSemantics.NESTED], f.situation
        name = {0: f"the default response of {f.subject}"}
        lw, ne = (picked[HedgeSemantics.LAST_WINS], picked[HedgeSemantics.NESTED])
        assert (
            f"last-wins selects {name.get(lw, f'{f.subject}.{lw}')} and nested selects "
            f"{name.get(ne, f'{f.subject}.{ne}')}" in f.message
        )


def test_witnesses_dir_holds_the_witnesses_of_one_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, findings = _findings(tmp_path, "concern")
    out = tmp_path / "w"
    assert main(["analyse", "--witnesses", str(out), str(path)]) == 1
    capsys.readouterr()
    written = sorted(out.iterdir())
    assert len(written) == sum(f.witness is not None for f in findings)
    for trace in written:
        assert trace.suffix == ".jsonl" and trace.name.startswith("concern--")
        assert read_trace(trace)


def test_witnesses_dir_keeps_every_witness_of_the_curtain_example(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, findings = _findings(tmp_path, "curtains")
    out = tmp_path / "w"
    assert main(["analyse", "--witnesses", str(out), str(path)]) == 1
    capsys.readouterr()
    assert len(list(out.iterdir())) == sum(f.witness is not None for f in findings)


def test_a_concern_witness_through_a_refused_obligation_is_confirmed(tmp_path: Path) -> None:
    path = tmp_path / "refused.sleec"
    path.write_text(
        sleec(
            "R1 when A then B within 5 seconds otherwise C within 2 seconds\n"
            "R2 when A and {x} then not B within 10 seconds",
            "concern_start\nc1 when A and {x} then C within 7 seconds\nconcern_end",
        ),
        encoding="utf-8",
    )
    (f,) = [f for f in analyse(path, ["concern-raised"]).findings]
    assert f.witness is not None and f.witness.confirmed

"""Explanations for people (issue 33, item 1): the explanations file, checked at load with
``file:line:col``; ``Decision.for_people`` and ``Permission.for_people`` from the author's
sentences or in plain words; durations, never clock readings; the audit record carries it."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.runtime import (
    Decision,
    DecisionOrigin,
    Explanations,
    ExplanationsError,
    Manager,
    RuleSet,
    VirtualClock,
)
from cosleec.runtime.decision import said_in
from cosleec.runtime.plain import duration, spoken, words

HOSPITAL = """def_start
event MedicationInfoRequest event ShareInformation event Refuse event ExplainWhy
event RecordVideo event CameraOn event FallDetected event CallNurse event RaiseAlarm
measure requesterIsPatient : boolean measure patientConsented : boolean
measure requesterAge : numeric measure urgency : scale(low, high)
def_end
rule_start
R1 when MedicationInfoRequest then ShareInformation unless not requesterIsPatient then {Refuse and ExplainWhy}
R2 when CameraOn then not RecordVideo within 10 minutes unless patientConsented
R3 when FallDetected then CallNurse within 2 minutes otherwise RaiseAlarm
rule_end
"""

FILE = """# what the robot says
R1:
  default: Here is your medication information.
  1: "I can't share this: only the patient may hear it (you are {requesterAge}, urgency {urgency})."
R2: I won't record video in your room without your consent.
R3:
  otherwise: I could not reach a nurse in time, so I am raising the alarm.
"""


@pytest.fixture
def rules() -> RuleSet:
    return RuleSet.from_text(HOSPITAL)


def manager(rules: RuleSet, **options: Any) -> tuple[Manager, VirtualClock]:
    clock = VirtualClock()
    m = Manager(rules, clock=clock, dispatch=False, **options)
    m.start()
    return m, clock


def test_the_authors_sentence_is_said_with_the_values_the_decision_read(
    rules: RuleSet, tmp_path: Path
) -> None:
    path = tmp_path / "hospital.explanations.yaml"
    path.write_text(FILE)
    log = tmp_path / "audit.jsonl"
    m, clock = manager(rules, explanations=str(path), audit=str(log))
    m.update(requesterIsPatient=False, requesterAge=14, urgency="high")
    (d,) = m.event("MedicationInfoRequest")
    # a measure the rule does not read ({requesterAge}) is kept for the sentence
    assert d.for_people == "I can't share this: only the patient may hear it (you are 14, urgency high)."
    assert d.explanation.startswith("R1: Refuse and ExplainWhy [clause 1")  # the developers' text stays
    m.update(requesterIsPatient=True)
    assert m.event("MedicationInfoRequest")[0].for_people == "Here is your medication information."
    (r2,) = m.event("CameraOn")  # a sentence alone: every case of the rule
    assert r2.for_people == "I won't record video in your room without your consent."
    clock.advance(20)
    p = m.request("RecordVideo")
    assert p.for_people == (
        "I can't record video for another 10 minutes: I won't record video in your room without your consent."
    )
    assert "for another 9 min 40 s" in p.reason and "until" not in p.reason
    m.event("FallDetected")
    clock.advance(121)  # CallNurse missed: the otherwise
    m.tick()
    fallback = m.decisions[-1]
    assert fallback.origin == DecisionOrigin.OTHERWISE and fallback.fallback
    assert fallback.for_people == "I could not reach a nurse in time, so I am raising the alarm."
    m.close()
    said = [json.loads(line) for line in log.read_text().splitlines() if '"kind":"decision"' in line]
    # a record keeps the author's sentence; one in plain words is made when it is read
    assert [said_in(r) for r in said] == [d.for_people for d in m.decisions]
    assert ["for_people" in r for r in said] == [True, True, True, False, True]
    assert [r["origin"] for r in said] == ["trigger"] * 3 + ["trigger", "otherwise"]


def test_without_a_file_the_sentence_is_in_plain_words_not_the_rules_notation(rules: RuleSet) -> None:
    m, clock = manager(rules)
    m.update(requesterIsPatient=False, patientConsented=False)
    (d,) = m.event("MedicationInfoRequest")
    assert d.for_people == "I will refuse and explain why, because requester is patient is no."
    (r2,) = m.event("CameraOn")
    assert r2.for_people == "I will not record video for 10 minutes, because patient consented is no."
    clock.advance(61)
    p = m.request("RecordVideo")
    assert p.for_people == ("I can't record video for another 9 minutes, because patient consented is no.")
    assert p.reason.startswith("RecordVideo is forbidden by R2 for another 8 min 59 s (")
    m.event("FallDetected")
    clock.advance(121)
    fallback = m.decisions[-1]
    assert fallback.for_people == "I did not call nurse in time, so I will raise alarm."
    m2, _ = manager(rules)
    (undetermined,) = m2.event("MedicationInfoRequest")
    assert undetermined.for_people == "I can't decide yet: I don't know requester is patient."
    for said in (d.for_people, r2.for_people, p.for_people, fallback.for_people):
        assert not any(c in said for c in "[]=_") and "R1" not in said and " s " not in said


def test_a_record_keeps_only_the_authors_sentence_and_readers_make_the_rest(rules: RuleSet) -> None:
    m, _ = manager(rules)
    m.update(requesterIsPatient=False, patientConsented=False)
    (d,) = m.event("MedicationInfoRequest")
    record = json.loads(json.dumps(d.to_json()))
    assert "for_people" not in record  # made on every decision, it doubled a decision's cost
    assert d._for_people == []  # and to_json did not make it either
    assert said_in(record) == d.for_people == Decision.from_json(record).for_people
    kept = {**record, "for_people": "Something said then."}  # what was said then stays said
    assert said_in(kept) == "Something said then." == Decision.from_json(kept).to_json()["for_people"]
    assert said_in({"kind": "decision", "rule": "R1"}) == ""  # no id: too malformed to read
    assert said_in({**record, "clause": "two"}) == ""


def test_a_decision_round_trips_with_its_origin_and_what_was_said(rules: RuleSet) -> None:
    m, clock = manager(rules, explanations=Explanations.parse(FILE))
    m.event("FallDetected")
    clock.advance(200)
    m.tick()
    trigger, fallback = m.decisions
    for d in (trigger, fallback):
        back = Decision.from_json(json.loads(json.dumps(d.to_json())))
        assert back == d and back.for_people == d.for_people and back.origin == d.origin
    assert (fallback.clause, fallback.layer, fallback.origin) == (0, None, "otherwise")  # not the default
    assert trigger.origin == "trigger" and not trigger.fallback and trigger.missed is None
    old = {k: v for k, v in fallback.to_json().items() if k not in ("origin", "for_people", "missed")}
    assert Decision.from_json(old).fallback  # an older record: its `violated` says it
    assert (
        Decision.from_json(old).for_people
        == "Something I had to do was not done in time, so I will raise alarm."
    )


@pytest.mark.parametrize(
    ("text", "where", "says", "hint"),
    [
        ("R11: Hello.", ":1:1", "'R11' is not a rule", "did you mean R1?"),
        ("Zz: Hello.", ":1:1", "'Zz' is not a rule", "the rules are R1, R2, R3"),
        ("R1:\n  3: Hello.", ":2:3", "R1 has no clause 3: it has one clause (1)", "i-th `unless`"),
        ("R2:\n  otherwise: Hello.", ":2:3", "R2 has no `otherwise`", "give the rule an `otherwise`"),
        ("R1:\n  defualt: Hello.", ":2:3", "'defualt' is not a case", "did you mean default?"),
        (
            "R1: Hello {requesterAg}.",
            ":1:5",
            "{requesterAg} is not a measure",
            "did you mean {requesterAge}?",
        ),
        ("R1:\n  default: 42", ":2:12", "a sentence must be text, not 42", "quotes"),
        ("R1: yes", ":1:5", "a sentence must be text, not True", "quotes"),
        ("R1: [a, b]", ":1:5", "not a list or mapping", "quotes"),
        ("R1: a\nR1: b", ":2:1", "R1 is given twice", "keep one"),
        ("R1: I can't: no.", ":1:12", "not valid YAML", "quote a sentence"),
        ("- R1", ":1:1", "maps rule names to sentences", "R1: I will"),
    ],
)
def test_a_file_the_rules_do_not_fit_is_refused_at_load_with_where_and_the_fix(
    rules: RuleSet, tmp_path: Path, text: str, where: str, says: str, hint: str
) -> None:
    path = tmp_path / "x.yaml"
    path.write_text(text)
    with pytest.raises(ExplanationsError) as e:
        Manager(rules, explanations=path)
    assert e.value.message.startswith(f"{path}{where}: "), e.value.message
    assert says in e.value.message and hint in e.value.hint


def test_a_missing_file_and_a_wrong_option_are_clear_errors(rules: RuleSet, tmp_path: Path) -> None:
    with pytest.raises(ExplanationsError, match="cannot read the explanations file"):
        Manager(rules, explanations=tmp_path / "nope.yaml")
    with pytest.raises(ValueError, match="explanations must be the path"):
        Manager(rules, explanations=42)


def test_the_hot_path_makes_no_sentence_until_one_is_read(rules: RuleSet) -> None:
    m, _ = manager(rules)
    (d,) = m.event("FallDetected")
    assert d._for_people == []  # lazy, like the explanation
    assert d.for_people and d._for_people == [d.for_people]


# ---------------------------------------------------------------------- plain words


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("ExplainWhy", "explain why"),
        ("requesterIsPatient", "requester is patient"),
        ("sendSMSAlert", "send SMS alert"),
        ("battery_low2", "battery low 2"),
        ("x", "x"),
    ],
)
def test_names_are_said_as_words(name: str, said: str) -> None:
    assert words(name) == said


@pytest.mark.parametrize(
    ("seconds", "developers", "people"),
    [
        (0.25, "0.25 s", "a moment"),
        (40, "40 s", "40 seconds"),
        (60, "1 min", "1 minute"),
        (560, "9 min 20 s", "9 minutes"),
        (590, "9 min 50 s", "10 minutes"),
        (3900, "1 h 5 min", "1 hour 5 minutes"),
        (90000, "1 d 1 h", "1 day 1 hour"),
        (-3, "0 s", "a moment"),
        (math.inf, "no end", "ever"),
    ],
)
def test_durations_for_developers_and_for_people(seconds: float, developers: str, people: str) -> None:
    assert (duration(seconds), spoken(seconds)) == (developers, people)


@given(st.floats(min_value=60, max_value=1e7, allow_nan=False))
def test_a_duration_for_developers_drops_less_than_its_last_unit(seconds: float) -> None:
    size = {"d": 86400, "h": 3600, "min": 60, "s": 1}
    parts = duration(seconds).split()
    shown = [(int(n), size[u]) for n, u in zip(parts[::2], parts[1::2])]
    assert len(shown) <= 2 and [u for _, u in shown] == sorted((u for _, u in shown), reverse=True)
    total = sum(n * u for n, u in shown)
    assert 0 <= round(seconds) - total < shown[-1][1]


@given(st.floats(min_value=1, max_value=1e7, allow_nan=False))
def test_a_duration_for_people_is_never_off_by_more_than_half_its_last_unit(seconds: float) -> None:
    size = {"second": 1, "minute": 60, "hour": 3600, "day": 86400}
    parts = spoken(seconds).split()
    units = [size[u.rstrip("s")] for u in parts[1::2]]
    total = sum(int(n) * u for n, u in zip(parts[::2], units))
    assert abs(total - seconds) <= max(units[-1] / 2, 1)


def test_decide_says_each_decisions_sentence_with_explanations(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from cosleec.cli.main import main

    (tmp_path / "h.sleec").write_text(HOSPITAL)
    (tmp_path / "h.yaml").write_text(FILE)
    args = ["decide", str(tmp_path / "h.sleec"), "--event", "MedicationInfoRequest"]
    assert main([*args, "--set", "requesterIsPatient=false", "--explanations", str(tmp_path / "h.yaml")]) == 0
    out = capsys.readouterr().out
    assert (
        "  says: I can't share this: only the patient may hear it (you are unknown, urgency unknown)." in out
    )
    assert main([*args, "--set", "requesterIsPatient=true", "--json"]) == 0
    (d,) = json.loads(capsys.readouterr().out)["decisions"]
    assert d["for_people"] == "I will share information, because requester is patient is yes."
    (tmp_path / "bad.yaml").write_text("R1:\n  7: Sorry.")
    assert main([*args, "--explanations", str(tmp_path / "bad.yaml")]) == 1
    assert f"{tmp_path / 'bad.yaml'}:2:3: R1 has no clause 7" in capsys.readouterr().err


def test_an_explain_why_capability_gets_the_sentence_for_people(rules: RuleSet) -> None:
    m = Manager(rules, clock=VirtualClock(), explanations=Explanations.parse(FILE))
    heard: list[str] = []

    @m.capability("ExplainWhy")
    def explain(obligation: object, decision: Decision) -> None:
        heard.append(decision.for_people)

    m.start(check=False)
    m.update(requesterIsPatient=False, requesterAge=9)
    m.event("MedicationInfoRequest")
    assert heard == ["I can't share this: only the patient may hear it (you are 9, urgency unknown)."]


def test_every_sentence_the_rules_do_not_fit_is_named_in_one_error(rules: RuleSet, tmp_path: Path) -> None:
    path = tmp_path / "says.yaml"
    path.write_text(
        "R1:\n"
        "  3: I can't.\n"  # line 2: R1 has one clause
        "  default: Here, {requesterAg}.\n"  # line 3: no such measure
        "R9: Hello.\n"  # line 4: no such rule
        "R2: Not now.\n"  # fits
    )
    with pytest.raises(ExplanationsError) as e:
        Manager(rules, clock=VirtualClock(), dispatch=False, explanations=str(path))
    text = e.value.message
    assert text.startswith(f"3 sentences of {path} do not fit the rules:")
    assert f"{path}:2:3: R1 has no clause 3" in text
    assert f"{path}:3:12: {{requesterAg}} is not a measure" in text and "did you mean {requesterAge}?" in text
    assert f"{path}:4:1: 'R9' is not a rule" in text
    assert text.count("\n  /") == 3 and "Not now" not in text  # the sentence that fits is not named

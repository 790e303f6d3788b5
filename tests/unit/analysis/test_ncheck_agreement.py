"""Agreement with N-Check on its 18 case-study files, read as N-Check reads them.

``tests/data/analysis/ncheck_answers.json`` records what N-Check (NickF0211/LEGOS-SLEEC)
flagged when run on this machine. With LEGOS's reading of untimed responses (``untimed=0``)
and of the files (``legos_compat``), cosleec must flag the same rules, concerns and purposes
-- except for the differences listed here, each with what is known of it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosleec.analysis import Settings, analyse_file
from cosleec.testing import corpus_dir

DATA = Path(__file__).resolve().parents[2] / "data" / "analysis" / "ncheck_answers.json"
CODES = {
    "red": "redundant",
    "c": "vacuous-conflict",
    "sc": "situational-conflict",
    "con": "concern-raised",
    "pur": "purpose-blocked",
}

# Two deliberate differences of the reference semantics explain every disagreement:
ORDER = (
    "causal order within an instant: an obligation or prohibition counts only occurrences after the step "
    "that raised it (the trigger is never its own response); N-Check has no order within an instant"
)
VALUES = (
    "values per occurrence: two occurrences at one instant may read different values (a context update "
    "between them); N-Check has one snapshot per instant"
)

# (file, N-Check check) -> (only N-Check flags, only cosleec flags, why)
KNOWN = {
    ("NickF0211__LEGOS-SLEEC__Autocar__Autocar-corrected.sleec", "red"): (
        {"R17bb", "R27I"},
        set(),
        # R27I `when UserTurnOnSystem and not consent then not RecordPeople` is implied, for N-Check,
        # by R1 (TurnOnSensors at the same instant) and R27II (TurnOnSensors and not consent: not
        # RecordPeople): a RecordPeople before TurnOnSensors, or consent changing in between, escapes
        # R27II here. R17bb likewise through R17b and R19.
        f"{ORDER}; {VALUES}",
    ),
    ("NickF0211__LEGOS-SLEEC__Autocar__Autocar-corrected.sleec", "con"): (
        set(),
        {"c9"},
        # c9 `when ReadyToDrive then not ReadyToDrive eventually`: for N-Check the trigger itself
        # breaks the response, so the concern can never be raised
        ORDER,
    ),
    ("NickF0211__LEGOS-SLEEC__Autocar__Autocar.sleec", "con"): (set(), {"c9"}, ORDER),
    # situational conflicts: each of these needs two occurrences at one instant that read different
    # values (the untimed responses, read at the same instant, leave no other way)
    ("NickF0211__LEGOS-SLEEC__Autocar__Autocar-corrected.sleec", "sc"): (set(), {"R10_1"}, VALUES),
    ("NickF0211__LEGOS-SLEEC__DAISY__Daisy-corrected.sleec", "sc"): (
        set(),
        {"Rule18b", "Rule23", "Rule5_1"},
        VALUES,
    ),
    ("NickF0211__LEGOS-SLEEC__safescade__safescade-corrected.sleec", "sc"): (
        set(),
        {"R10", "R11_1", "R16", "R3", "R4", "R7"},
        VALUES,
    ),
    ("NickF0211__LEGOS-SLEEC__CSI__CSI-corrected.sleec", "con"): (
        set(),
        {"c5"},
        # c5 `when ActionHumanRandom then RobotMoving`: R18 owes AskPermission at that instant and R19
        # forbids RobotMoving at it; a RobotMoving before AskPermission in the instant is not forbidden
        ORDER,
    ),
}


def answers() -> dict[str, dict[str, dict[str, object]]]:
    return dict(json.loads(DATA.read_text(encoding="utf-8"))["files"])


@pytest.mark.parametrize("name", sorted(answers()))
def test_cosleec_flags_what_ncheck_flags(name: str) -> None:
    path = corpus_dir() / name
    if not path.exists():
        pytest.skip(f"corpus file {name} not found")
    report = analyse_file(path, Settings(untimed=0.0), list(CODES.values()), legos_compat=True)
    assert not report.failed
    for check, code in CODES.items():
        theirs = set(answers()[name][check]["flagged"])  # type: ignore[arg-type]
        if check == "sc":  # N-Check names the rule whose trigger cannot be answered
            ours = {t for f in report.findings if f.code == code for t in f.extra["triggers"]}
        else:
            ours = {f.subject for f in report.findings if f.code == code}
        only_theirs, only_ours, _ = KNOWN.get((name, check), (set(), set(), ""))
        assert (theirs - ours, ours - theirs) == (only_theirs, only_ours), (name, check)

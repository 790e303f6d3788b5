"""The tutorial (docs/tutorial.md) says what cosleec does: its rules are real files that
check clean, its Python blocks run, its table of clauses is what the runtime chooses, and
each common mistake gets the message the page shows.

Its ```console blocks are run by ``tests/unit/test_doc_commands.py``; its ```python blocks
are run here (not by ``tests/unit/test_docs.py``), each on its own, from the repository
root, as a reader would run them.

What is still being built elsewhere is ``xfail(strict=True)``: the parser's recovery, which
reports every syntax error of a file (H1). A strict xfail that passes fails: remove its
marker when the part lands.
"""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from cosleec.cli.main import main
from cosleec.runtime import RuleSet
from tests.doc_blocks import ROOT

PAGE = ROOT / "docs" / "tutorial.md"
TEXT = PAGE.read_text(encoding="utf-8")
HOSPITAL = ROOT / "examples" / "hospital"
FENCE = re.compile(r"^```(\w+)\n(.*?)^```$", re.M | re.S)
BLOCKS = [(m.group(1), m.group(2)) for m in FENCE.finditer(TEXT)]
#: a ```sleec or ```yaml block's first line names the file the rest is taken from
NAMED = [(kind, body) for kind, body in BLOCKS if kind in ("sleec", "yaml")]
PYTHON = [body for kind, body in BLOCKS if kind == "python"]


def named_file(body: str) -> tuple[Path, list[str]]:
    """The file a block names on its first line (``// path`` or ``# path (excerpt)``), and
    the block's other lines."""
    first, *rest = body.rstrip("\n").split("\n")
    m = re.fullmatch(r"(?://|#) (examples/hospital/\S+)(?: \(excerpt\))?", first)
    assert m, f"the block does not name its file on its first line: {first!r}"
    return ROOT / m.group(1), rest


def check(path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """``cosleec check PATH`` from the repository root: exit status and output."""
    code = main(["check", str(path.relative_to(ROOT))])
    out = capsys.readouterr()
    return code, out.out + out.err


@pytest.fixture(autouse=True)
def at_root(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Run from the repository root; the blocks' ``sys.path`` insert and the imported
    ``hospital_tasks`` module are undone afterwards."""
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(sys, "path", list(sys.path))
    yield
    sys.modules.pop("hospital_tasks", None)


def test_the_page_is_in_the_site_right_after_getting_started() -> None:
    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))["nav"]
    pages = [next(iter(entry.values())) for entry in nav]
    assert pages[pages.index("getting-started.md") + 1] == "tutorial.md"
    for page in ("getting-started.md", "language.md"):
        assert "(tutorial.md)" in (ROOT / "docs" / page).read_text(encoding="utf-8")


def test_there_are_blocks_of_every_kind() -> None:
    kinds = [kind for kind, _ in BLOCKS]
    assert kinds.count("sleec") >= 9 and kinds.count("python") >= 4 and kinds.count("console") >= 8


@pytest.mark.parametrize(("kind", "body"), NAMED, ids=lambda x: x if x in ("sleec", "yaml") else None)
def test_every_rules_block_is_taken_from_the_file_it_names(kind: str, body: str) -> None:
    path, lines = named_file(body)
    text = path.read_text(encoding="utf-8").split("\n")
    assert lines and any(text[i : i + len(lines)] == lines for i in range(len(text))), (
        f"{path.relative_to(ROOT)} does not contain these lines, in this order:\n" + "\n".join(lines)
    )


@pytest.mark.parametrize(
    "path",
    [HOSPITAL / "hospital.sleec", *sorted((HOSPITAL / "steps").glob("*.sleec"))],
    ids=lambda p: p.name,
)
def test_every_rules_file_of_the_tutorial_checks_clean_and_is_formatted(
    path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out = check(path, capsys)
    assert code == 0 and out.strip().endswith("measures)"), out  # ok, and no warning
    assert main(["fmt", "--check", str(path)]) == 0, capsys.readouterr().out


def test_the_steps_build_the_finished_rules() -> None:
    """What steps 1-7 write is hospital.sleec: every rule of it, and nothing else but R5."""
    final = RuleSet.from_file(HOSPITAL / "hospital.sleec")
    for step in sorted((HOSPITAL / "steps").glob("*.sleec")):
        rules = RuleSet.from_file(step)
        assert rules.events == final.events and set(rules.spec.measures) == set(final.spec.measures)
    last = RuleSet.from_file(HOSPITAL / "steps" / "8-priority.sleec")
    assert sorted(r.name for r in last.spec.rules) == ["R1", "R2", "R3", "R4", "R5"]


#: the table of step 5: the requester of each row, as measure values
REQUESTERS = {
    "the patient": {"requesterIsPatient": True, "requesterIsNurse": False, "patientIsMinor": False},
    "a visitor": {"requesterIsPatient": False, "requesterIsNurse": False, "patientIsMinor": False},
    "a nurse, adult patient": {
        "requesterIsPatient": False,
        "requesterIsNurse": True,
        "patientIsMinor": False,
    },
    "a nurse, minor patient": {"requesterIsPatient": False, "requesterIsNurse": True, "patientIsMinor": True},
}


def table_rows() -> list[list[str]]:
    """The rows of the page's table of R1's clauses (the header and rule lines left out)."""
    rows = [line.strip("|").split("|") for line in TEXT.split("\n") if line.startswith("| ")]
    return [[cell.strip() for cell in row] for row in rows if row[0].strip() in REQUESTERS]


@pytest.mark.parametrize("row", table_rows(), ids=lambda row: row[0])
def test_the_table_of_last_clause_wins_is_what_the_runtime_chooses(
    row: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """Each row: the conditions the page says hold are the ones that hold, the clause it
    names is the last of them (the oracle), and ``cosleec decide`` chooses that clause."""
    who, first, second, robot = row
    v = REQUESTERS[who]
    holds = [not v["requesterIsPatient"], v["patientIsMinor"] and v["requesterIsNurse"]]
    assert [first, second] == ["yes" if h else "no" for h in holds]
    last = max((i + 1 for i, h in enumerate(holds) if h), default=0)
    shown = re.search(r"\(clause (\d)", robot)
    assert (int(shown.group(1)) if shown else 0) == last
    sets = [x for name, value in v.items() for x in ("--set", f"{name}={str(value).lower()}")]
    rules = str((HOSPITAL / "steps" / "4-two-clauses.sleec").relative_to(ROOT))
    assert main(["decide", rules, "--event", "MedicationInfoRequested", *sets, "--json"]) == 0
    (decision,) = json.loads(capsys.readouterr().out)["decisions"]
    assert decision["clause"] == last
    shares = any(ob["event"] == "ShareMedicationInfo" for ob in decision["obligations"])
    assert shares == robot.startswith("shares")


@pytest.mark.parametrize("block", PYTHON, ids=[f"python-{i + 1}" for i in range(len(PYTHON))])
def test_every_python_block_runs_and_the_robot_does_what_its_comments_say(
    block: str, capsys: pytest.CaptureFixture[str]
) -> None:
    exec(compile(block, str(PAGE), "exec"), {"__name__": "tutorial"})
    printed = capsys.readouterr().out
    for claim in re.findall(r"robot: (?:cannot )?[A-Z]\w+", block):
        assert claim in printed, f"the block says `{claim}`, the robot printed:\n{printed}"


#: each common mistake of the page: whether `check` fails (an error, 1) or warns (0), and the
#: phrase its message contains (phrases.md, exact)
MISTAKES = {
    "for-duration": (1, "durations are written `within 10 minutes`"),
    "double-equals": (1, "`=` compares"),
    "colon-after-name": (1, "a rule's name is followed by `when`"),
    "measure-as-trigger": (1, "is a condition, which comes after the event"),
    "otherwise-without-deadline": (0, "`otherwise` needs a deadline"),
    "untimed-fallback": (0, "can never be violated"),
}


def messages(out: str, path: str) -> list[str]:
    """The error and warning lines of ``check``'s output (no source line, caret or hint)."""
    return [
        line for line in out.split("\n") if re.match(re.escape(path) + r":\d+:\d+: (error|warning): ", line)
    ]


def shown(name: str) -> list[str]:
    """The error and warning lines the page shows for mistake ``name`` (a console block of
    `cosleec check` on it, or a ```text block of its messages)."""
    path = f"examples/hospital/mistakes/{name}.sleec"
    for kind, body in BLOCKS:
        if (kind == "console" and body.startswith(f"$ cosleec check {path}\n")) or (
            kind == "text" and body.startswith(path + ":")
        ):
            return messages(body, path)
    raise AssertionError(f"the page shows no message for {path}")


@pytest.mark.parametrize("name", sorted(MISTAKES))
def test_the_page_shows_each_mistake_with_its_phrase(name: str) -> None:
    status, phrase = MISTAKES[name]
    (line,) = shown(name)
    assert phrase in line and (": error: " in line) == (status == 1)


@pytest.mark.parametrize("name", sorted(MISTAKES))
def test_each_mistake_gets_the_message_that_names_the_fix(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """The phrase, at the place the page shows (its console block is compared word for word
    by test_doc_commands)."""
    status, phrase = MISTAKES[name]
    path = HOSPITAL / "mistakes" / f"{name}.sleec"
    code, out = check(path, capsys)
    assert code == status, out
    (line,) = messages(out, str(path.relative_to(ROOT)))
    assert phrase in line and line.split(": ")[0] == shown(name)[0].split(": ")[0], out


def test_every_mistake_of_a_file_is_reported_where_the_page_says(capsys: pytest.CaptureFixture[str]) -> None:
    path = HOSPITAL / "mistakes" / "several-errors.sleec"
    code, out = check(path, capsys)
    page = shown("several-errors")
    assert len(page) == 3
    for line, name in zip(page, ("for-duration", "colon-after-name", "double-equals"), strict=True):
        assert MISTAKES[name][1] in line
    assert code == 1 and messages(out, str(path.relative_to(ROOT))) == page, out


def test_the_sentence_written_without_a_file_is_the_one_the_page_quotes() -> None:
    quoted = re.search(r'for the refusal above: "(.*?)"', " ".join(TEXT.split()))
    assert quoted, "the page quotes the generated sentence of R1's refusal"
    from cosleec import Manager, VirtualClock

    sys.path.insert(0, str(HOSPITAL))
    from hospital_tasks import install

    m = Manager.from_file(HOSPITAL / "hospital.sleec", clock=VirtualClock())
    robot = install(m)
    m.start()
    m.update(requesterIsPatient=False, requesterIsNurse=False, patientIsMinor=False)
    (decision,) = m.event("MedicationInfoRequested")
    assert decision.for_people == quoted.group(1) and robot.said == [quoted.group(1)]
    m.close()


@pytest.mark.parametrize(("step", "violations", "cancelled"), [("7-conflict", 1, 0), ("8-priority", 0, 1)])
def test_the_priority_cancels_the_docking_instead_of_violating_it(
    step: str, violations: int, cancelled: int, capsys: pytest.CaptureFixture[str]
) -> None:
    """Step 10: a fall, then a low battery. Without the priority the prohibition wins and R4
    is violated; with R5 > R4, R4 is cancelled. Either way the robot stays; `analyse`
    finds the conflict only without the priority."""
    from cosleec import Manager, VirtualClock

    sys.path.insert(0, str(HOSPITAL))
    from hospital_tasks import install

    rules = HOSPITAL / "steps" / f"{step}.sleec"
    clock = VirtualClock()
    m = Manager.from_file(rules, clock=clock)
    install(m)
    m.start()
    m.update(batteryPercent=15, deliveringUrgentMedication=False)
    m.event("FallDetected")  # robot: CallNurse; R5 keeps it from its dock for 5 minutes
    m.event("BatteryReading")
    clock.advance(301)
    assert (m.stats.violations, m.stats.cancelled) == (violations, cancelled)
    assert "robot: GoToDock" not in capsys.readouterr().out
    m.close()
    analyse = main(["analyse", str(rules), "--check", "runtime-conflict"])
    assert analyse == violations, capsys.readouterr().out

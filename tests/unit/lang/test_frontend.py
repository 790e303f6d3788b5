"""The front end's shape: a face of imports only, and one straight pass over each file."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import cosleec.lang
from cosleec.lang import analyse, dialect, visit

SRC = Path(cosleec.lang.__file__).resolve().parent.parent

LEGOS = """def_start event E event F measure a : boolean measure x : numeric def_end
rule_start
  R1 when E and ({a} and ({x} > 3)) then F within [1 seconds, 5 seconds] unless (not {a}) then F eventually
rule_end
concern_start c1 when E and {a} then F concern_end
purpose_start p1 exists E while F meanwhile (when F then E) purpose_end
relation_start witness E F measure imply {a} ({x} > 2) when E then {a} for 5 seconds relation_end
"""


def test_the_face_only_imports_and_exports() -> None:
    tree = ast.parse(Path(cosleec.lang.__file__).read_text(encoding="utf-8"))
    for node in tree.body:
        ok = isinstance(node, ast.Import | ast.ImportFrom) or (
            isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)  # the docstring
        )
        ok = ok or (isinstance(node, ast.Assign) and [t.id for t in node.targets] == ["__all__"])  # type: ignore[attr-defined]
        assert ok, ast.dump(node)[:200]
    for name in cosleec.lang.__all__:
        assert getattr(cosleec.lang, name) is not None


def test_the_face_offers_what_other_packages_take_from_lang() -> None:
    """Whatever another package imports from a lang module, the face exports too."""
    pattern = re.compile(r"from cosleec\.lang\.\w+ import ([\w, ]+)")
    taken = {
        name.split(" as ")[0].strip()  # `from cosleec.lang.x import pairs as priority_pairs` takes `pairs`
        for path in SRC.rglob("*.py")
        if "lang" not in path.relative_to(SRC).parts[:2]
        for m in pattern.finditer(path.read_text(encoding="utf-8"))
        for name in m.group(1).split(",")
    }
    assert taken <= set(cosleec.lang.__all__)


@pytest.mark.parametrize("mode", ["auto", "tk", "legos"])
def test_one_walk_for_the_dialect_facts_and_none_through_visit(
    mode: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    walks = []
    real = dialect._Walk.__init__

    def counted(self: dialect._Walk, measures: set[str]) -> None:
        walks.append(1)
        real(self, measures)

    def forbidden(*args: object) -> None:
        raise AssertionError("the front end re-walked the AST through visit.py")

    monkeypatch.setattr(dialect._Walk, "__init__", counted)
    for name in ("responses", "conditions", "all_durations", "all_responses", "triggers"):
        monkeypatch.setattr(visit, name, forbidden)
    result = analyse(LEGOS, dialect=mode)
    assert result.spec is not None and len(walks) == 1
    if mode == "auto":
        assert result.ok, result.render()

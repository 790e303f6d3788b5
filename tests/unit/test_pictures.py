"""The README's pictures are drawn from the demo by scripts/pictures, and kept up to date."""

from __future__ import annotations

import importlib.util
import json
import shutil
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]


def load() -> ModuleType:
    spec = importlib.util.spec_from_file_location("pictures", ROOT / "scripts" / "pictures.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def pictures() -> ModuleType:
    return load()


def test_the_readme_pictures_show_the_demo_as_it_is_now(pictures: ModuleType) -> None:
    assert pictures.stale() == [], "the README's pictures are out of date: run bash scripts/pictures"


def test_the_readme_shows_every_picture() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for name in load().PICTURES:
        assert f"]({name})" in readme, f"README.md does not show {name}"


def copy_pictures(pictures: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    for name in [*pictures.PICTURES, "docs/images/pictures.json"]:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / name, tmp_path / name)
    monkeypatch.setattr(pictures, "ROOT", tmp_path)
    monkeypatch.setattr(pictures, "MANIFEST", tmp_path / "docs/images/pictures.json")
    assert pictures.stale() == []
    return tmp_path


def test_a_changed_rule_makes_the_rules_picture_stale(
    pictures: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    copy_pictures(pictures, tmp_path, monkeypatch)
    rules = tmp_path / "rules.sleec"
    text = pictures.RULES.read_text(encoding="utf-8")
    assert "within 30 seconds" in text
    rules.write_text(text.replace("within 30 seconds", "within 31 seconds", 1), encoding="utf-8")
    monkeypatch.setattr(pictures, "RULES", rules)
    assert pictures.stale() == ["docs/images/rules.svg: what it shows has changed since it was drawn"]


def test_a_changed_run_makes_the_timeline_stale(
    pictures: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    copy_pictures(pictures, tmp_path, monkeypatch)
    real = pictures.timeline_layout
    layout = real()
    bar = layout.bars[0]
    moved = type(bar)(**{**{f: getattr(bar, f) for f in bar.__dataclass_fields__}, "end": bar.end + 1})
    changed = type(layout)(
        **{**{f: getattr(layout, f) for f in layout.__dataclass_fields__}, "bars": (moved, *layout.bars[1:])}
    )
    monkeypatch.setattr(pictures, "timeline_layout", lambda: changed)
    assert pictures.stale() == ["docs/images/timeline.svg: what it shows has changed since it was drawn"]


def test_a_picture_replaced_by_hand_is_caught(
    pictures: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    root = copy_pictures(pictures, tmp_path, monkeypatch)
    svg = root / "docs/images/rules.svg"
    svg.write_bytes(svg.read_bytes().replace(b"R1", b"R9", 1))
    assert pictures.stale() == [
        "docs/images/rules.svg: the file is not the picture drawn (edited or replaced by hand?)"
    ]
    (root / "docs/images/pictures.json").write_text(json.dumps({}), encoding="utf-8")
    assert pictures.stale() == [f"{name}: not drawn" for name in pictures.PICTURES]


def test_the_timeline_source_does_not_depend_on_the_hash_seed(pictures: ModuleType) -> None:
    assert pictures.plain({("a", 1): {"z", "b"}, "k": (1.5, None)}) == [
        ["k", [1.5, None]],
        [["a", 1], ["b", "z"]],
    ]

"""Draw the README's pictures from the demo, and say when they are out of date (see scripts/pictures).

Each picture is drawn from a *source*: the Graphviz DOT text of the demo's rules, and the
laid-out timeline of the demo's run (what `cosleec demo --plot` draws). The manifest
``docs/images/pictures.json`` keeps, for each picture, a digest of its source and a digest
of its bytes. ``tests/unit/test_pictures.py`` recomputes the sources: a change to the demo's
rules, its scenario, or to what the graph or the timeline draws changes a source, and the
test fails until the pictures are drawn again. The digest of the bytes catches a picture
edited or replaced by hand. Renderers' versions do not matter (a newer Graphviz or
matplotlib draws other bytes from the same source; the test compares sources).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import sys
from collections.abc import Callable, Mapping
from enum import Enum
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
IMAGES = ROOT / "docs" / "images"
MANIFEST = IMAGES / "pictures.json"
RULES = ROOT / "src" / "cosleec" / "demo" / "assistive_care" / "rules.sleec"
TITLE = "the assistive-care demo's rules (cosleec graph)"


def graph_source() -> str:
    """The DOT text of the demo's rules, as `cosleec graph` writes it."""
    from cosleec.runtime import RuleSet
    from cosleec.views import build, to_dot

    return to_dot(build(RuleSet.from_file(RULES)), TITLE)


def timeline_layout() -> Any:
    """The demo's run, laid out as `cosleec demo --plot` lays it out."""
    from cosleec.demo import run
    from cosleec.views import Timeline, layout

    records = run().records()
    return layout(Timeline.from_records(records, source="cosleec demo"))


def plain(value: Any) -> Any:
    """``value`` as JSON can hold it, the same whatever the hash seed: mappings become sorted
    ``[key, value]`` pairs (a key may be a tuple), sets sorted lists, enums their value."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return plain({f.name: getattr(value, f.name) for f in dataclasses.fields(value)})
    if isinstance(value, dict | Mapping):
        return sorted(([plain(k), plain(v)] for k, v in value.items()), key=repr)
    if isinstance(value, set | frozenset):
        return sorted((plain(v) for v in value), key=repr)
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, Enum):
        return value.value
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return repr(value)


def timeline_source() -> str:
    """The laid-out timeline as canonical JSON: every lane, bar, band, marker and note drawn."""
    return json.dumps(plain(timeline_layout()))


def draw_graph(_: str) -> bytes:
    """The demo's rules as SVG (Graphviz)."""
    from cosleec.views import render

    return render(graph_source(), "svg")


def draw_timeline(_: str) -> bytes:
    """The demo's run as SVG (matplotlib)."""
    from cosleec.views import timeline_image

    return timeline_image(timeline_layout().timeline, "svg")


#: picture (relative to the repository) -> (how its source is made, how it is drawn)
PICTURES: dict[str, tuple[Callable[[], str], Callable[[str], bytes]]] = {
    "docs/images/rules.svg": (graph_source, draw_graph),
    "docs/images/timeline.svg": (timeline_source, draw_timeline),
}


def digest(data: str | bytes) -> str:
    """sha256 of text (UTF-8) or bytes, in hex."""
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def stale() -> list[str]:
    """What is out of date, one line per picture; empty when every picture is current."""
    try:
        manifest = json.loads(MANIFEST.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        return [f"{MANIFEST.relative_to(ROOT)}: cannot be read ({e})"]
    problems = []
    for name, (source, _) in PICTURES.items():
        entry = manifest.get(name)
        path = ROOT / name
        if entry is None or not path.exists():
            problems.append(f"{name}: not drawn")
        elif digest(path.read_bytes()) != entry["picture"]:
            problems.append(f"{name}: the file is not the picture drawn (edited or replaced by hand?)")
        elif digest(source()) != entry["source"]:
            problems.append(f"{name}: what it shows has changed since it was drawn")
    return problems


def main(argv: list[str]) -> int:
    """Draw every picture and write the manifest; ``--check`` only says what is out of date."""
    if argv[1:] == ["--check"]:
        problems = stale()
        for line in problems:
            print(line, file=sys.stderr)
        if problems:
            print("draw them again: bash scripts/pictures", file=sys.stderr)
        return 1 if problems else 0
    IMAGES.mkdir(parents=True, exist_ok=True)
    manifest = {}
    for name, (source, draw) in PICTURES.items():
        text = source()
        data = draw(text)
        (ROOT / name).write_bytes(data)
        manifest[name] = {"source": digest(text), "picture": digest(data)}
        print(f"{name}: {len(data):,} bytes")
    MANIFEST.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

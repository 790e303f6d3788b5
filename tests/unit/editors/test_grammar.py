"""The editors' side: the TextMate grammar tokenises every SLEEC file of the corpus as
cosleec's own scanner reads it, and the VS Code extension is a valid, buildable package.

The grammar runs in the real ``vscode-textmate`` on the real Oniguruma (``vscode-oniguruma``),
as VS Code runs it (editors/vscode/test/tokenize.js), once for the whole corpus, the
examples and the paper-notation files. Then, token by token against
``Lexicon.tokens``: no scope is ``invalid``; every comment is a comment; every keyword a
keyword (the relation keywords only inside a relation block, the paper notation's in any
case), every name a name (a rule's name before its ``when`` a rule name, an event's after
``event`` an event's), every number a number, every mark an operator or punctuation.

The npm packages come from ``scripts/setup --dev`` (``npm ci`` in editors/vscode where node
is installed); without them the test skips here and fails under CI.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import zipfile
from functools import cache
from pathlib import Path
from typing import Any

import pytest

from cosleec.lang.lexer import BAD_CHAR, Lexicon
from cosleec.lang.parser import PAPER, SLEEC, looks_like_paper
from cosleec.lsp import Settings
from cosleec.testing.corpus import corpus_files

ROOT = Path(__file__).resolve().parents[3]
VSCODE = ROOT / "editors" / "vscode"
GRAMMAR = VSCODE / "syntaxes" / "sleec.tmLanguage.json"


def npm_tools(*packages: str) -> str:
    """The path of node, when it and the packages are installed; else skip (fail under CI)."""
    node = shutil.which("node")
    missing = [p for p in packages if not (VSCODE / "node_modules" / p / "package.json").is_file()]
    if node is None or missing:
        why = "node is not installed" if node is None else f"{', '.join(missing)} not installed"
        if os.environ.get("CI"):
            pytest.fail(f"{why} under CI: scripts/setup --dev runs `npm ci` in editors/vscode")
        pytest.skip(f"{why} (bash scripts/setup --dev, or npm ci in editors/vscode)")
    return node


def sleec_files() -> list[Path]:
    files = [
        *corpus_files(),
        *sorted(ROOT.glob("examples/**/*.sleec")),
        *sorted(ROOT.glob("examples/**/*.txt")),
    ]
    return [f for f in files if f.is_file()]


@cache
def tokenised() -> tuple[list[list[str]], dict[str, list[list[list[int]]]]]:
    node = npm_tools("vscode-textmate", "vscode-oniguruma")
    files = [str(f) for f in sleec_files()]
    run = subprocess.run(
        [node, str(VSCODE / "test" / "tokenize.js"), *files], capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr
    doc: dict[str, Any] = json.loads(run.stdout)
    return doc["scopes"], doc["files"]


def utf16(s: str) -> int:
    return len(s.encode("utf-16-le")) // 2


class Scopes:
    """The scopes the grammar gave each place of one file."""

    def __init__(self, text: str, lines: list[list[list[int]]], scopes: list[list[str]]) -> None:
        self.text = [line.removesuffix("\r") for line in text.split("\n")]
        self.lines = lines
        self.scopes = scopes

    def at(self, line: int, col: int) -> list[str]:
        """The scopes of 1-based ``line``, code-point column ``col``."""
        unit = utf16(self.text[line - 1][: col - 1])
        for start, end, i in self.lines[line - 1]:
            if start <= unit < end:
                return self.scopes[i]
        raise AssertionError(f"no token at {line}:{col}")


def category(scopes: list[str]) -> str:
    return scopes[-1]


def offsets_to_line_col(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


KEYWORD_SCOPES = ("keyword.", "storage.type", "support.type", "constant.language")
NAME_SCOPES = ("variable.", "entity.name.")
MARK_SCOPES = ("keyword.operator", "punctuation.")


def check_file(path: Path, marks: Scopes) -> list[str]:
    """Every disagreement between the grammar and the scanner in one file."""
    text = path.read_text(encoding="utf-8")
    lexicon: Lexicon = (PAPER if looks_like_paper(text) else SLEEC).lexicon
    keywords = {*lexicon.keywords.values(), *lexicon.contextual.values()}
    punct = set(lexicon.punct.values())
    start_mark, end_mark = lexicon.block_marks
    problems: list[str] = []
    where = f"{path.name}"
    tokens = lexicon.tokens(text)
    inside = False  # a relation block
    for i, tok in enumerate(tokens):
        if tok.type == start_mark:
            inside = True
        elif tok.type == end_mark:
            inside = False
        scopes = marks.at(tok.line, tok.column)
        last = category(scopes)
        bad = ""
        if any("comment" in s for s in scopes):
            bad = "in a comment"
        elif tok.type == BAD_CHAR:
            continue
        elif tok.type in keywords and not last.startswith(KEYWORD_SCOPES):
            bad = "a keyword"
        elif tok.type == "NAME":
            following = tokens[i + 1] if i + 1 < len(tokens) else None
            previous = tokens[i - 1] if i else None
            if not last.startswith(NAME_SCOPES):
                bad = "a name"
            elif (
                following is not None
                and following.value == "when"
                and following.line == tok.line
                and not inside
                and lexicon is SLEEC.lexicon
                and not last.startswith("entity.name.function.rule")
            ):
                bad = "a rule's name"
            elif (
                previous is not None
                and previous.value == "event"
                and previous.line == tok.line
                and not last.startswith("entity.name.type.event")
            ):
                bad = "an event's declared name"
        elif tok.type in ("INT", "DECIMAL") and not last.startswith("constant.numeric"):
            bad = "a number"
        elif tok.type in punct and not last.startswith(MARK_SCOPES):
            bad = "a mark"
        if bad:
            problems.append(
                f"{where}:{tok.line}:{tok.column}: `{tok.value}` is {bad}, but the grammar says {scopes}"
            )
    for offset, comment in lexicon.comments(text):
        for k, piece in enumerate(comment.split("\n")):
            if piece.strip():
                line, col = offsets_to_line_col(text, offset + (0 if k == 0 else comment.index(piece)))
                if k:
                    col = 1
                scopes = marks.at(line, col + len(piece) - len(piece.lstrip()))
                if not any(s.startswith("comment.") for s in scopes):
                    problems.append(f"{where}:{line}:{col}: a comment, but the grammar says {scopes}")
    return problems


def test_the_grammar_tokenises_the_corpus_as_the_scanner_reads_it() -> None:
    scopes, files = tokenised()
    paths = sleec_files()
    assert len(paths) == len(files)
    assert len(corpus_files()) == 0 or len(paths) >= 215
    invalid = sorted({" ".join(s) for s in scopes if any("invalid" in x for x in s)})
    assert invalid == []
    problems: list[str] = []
    for path in paths:
        problems += check_file(path, Scopes(path.read_text(encoding="utf-8"), files[str(path)], scopes))
    assert problems == [], "\n".join(problems[:30])


def test_the_grammar_names_the_constructs_of_both_dialects_and_the_paper_notation() -> None:
    scopes, files = tokenised()

    def tokens(path: Path) -> list[tuple[str, str]]:
        text = [line.removesuffix("\r") for line in path.read_text(encoding="utf-8").split("\n")]
        out = []
        for n, line in enumerate(files[str(path)]):
            for start, end, i in line:
                piece = text[n][start:end]
                if piece.strip():
                    out.append((piece, scopes[i][-1]))
        return out

    legos = tokens(ROOT / "examples" / "notation" / "curtains-legos.sleec")
    assert ("{", "punctuation.section.braces.sleec") in legos
    assert ("R1", "entity.name.function.rule.sleec") in legos
    assert ("userUndressed", "variable.other.sleec") in legos
    paper = tokens(ROOT / "examples" / "notation" / "curtains-paper.txt")
    assert {p for p in paper if p[1] == "keyword.control.sleec"} >= {("WHEN", "keyword.control.sleec")}
    assert any(s == "keyword.control.sleec" and re.fullmatch(r"(?i)in\s+which\s+case", p) for p, s in paper)


def test_the_extension_manifest_points_at_files_that_exist() -> None:
    manifest = json.loads((VSCODE / "package.json").read_text(encoding="utf-8"))
    assert (VSCODE / manifest["main"]).is_file()
    [language] = manifest["contributes"]["languages"]
    assert language["id"] == "sleec" and ".sleec" in language["extensions"]
    assert (VSCODE / language["configuration"]).is_file()
    json.loads((VSCODE / language["configuration"]).read_text(encoding="utf-8"))
    [grammar] = manifest["contributes"]["grammars"]
    assert (VSCODE / grammar["path"]).resolve() == GRAMMAR.resolve()
    assert (
        json.loads(GRAMMAR.read_text(encoding="utf-8"))["scopeName"] == grammar["scopeName"] == "source.sleec"
    )
    assert "vscode-languageclient" in manifest["dependencies"]
    lock = json.loads((VSCODE / "package-lock.json").read_text(encoding="utf-8"))
    assert lock["packages"][""]["dependencies"] == manifest["dependencies"]
    assert lock["packages"][""]["devDependencies"] == manifest["devDependencies"]
    # the settings the extension passes are the ones the server reads
    client = (VSCODE / "extension.js").read_text(encoding="utf-8")
    body = client.split("function options(config)", 1)[1].split("\n}\n", 1)[0]
    sent = set(re.findall(r"^\s+(\w+): config\.get\(", body, re.M))
    readable = {"dialect", "lint", "strictPrecedence", "legosCompat", "semantics", "formatWidth", "analysis",
                "analysisTimeout"}  # fmt: skip
    assert sent == readable
    for key in readable:  # each is a key Settings.from_json reads (and type-checks)
        with pytest.raises(ValueError, match=key):
            Settings.from_json({key: object()})
    assert '"lsp"' in client


def test_the_extension_packages_offline_with_vsce(tmp_path: Path) -> None:
    node = npm_tools("@vscode/vsce", "vscode-languageclient")
    vsix = tmp_path / "cosleec.vsix"
    cli = VSCODE / "node_modules" / "@vscode" / "vsce" / "vsce"
    run = subprocess.run(
        [node, str(cli), "package", "--allow-missing-repository", "--skip-license", "-o", str(vsix)],
        cwd=VSCODE,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    names = set(zipfile.ZipFile(vsix).namelist())
    assert {
        "extension/package.json",
        "extension/extension.js",
        "extension/syntaxes/sleec.tmLanguage.json",
    } <= names
    assert any(n.startswith("extension/node_modules/vscode-languageclient/") for n in names)
    assert not any(n.startswith(("extension/test/", "extension/node_modules/@vscode/vsce/")) for n in names)

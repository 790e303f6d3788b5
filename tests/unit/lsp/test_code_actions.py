"""The on-save repairs as quick fixes: ``cosleec lsp`` over stdio, driven by pygls's client.

Save a file with a redundant rule: the finding's diagnostic appears; a code action at it
offers the engine's verified fixes, rank 1 preferred; the edits, applied as LSP says (UTF-16
positions, after characters of one and two UTF-16 units on the same line), give exactly the
engine's patched text (the engine is called directly for the expected answer); after an
edit they are gone, and the next save offers them at their new places. The conversion of
edits is checked on its own against ``Patch.apply`` on any text (hypothesis).
"""

from __future__ import annotations

import itertools
import re
import threading
import time
from collections.abc import Iterator, Sequence

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lsprotocol import types as T

from cosleec.analysis import Settings
from cosleec.lang import Options
from cosleec.lsp import LineIndex
from cosleec.lsp.fixes import text_edits
from cosleec.lsp.onsave import OnSave, Outcome
from cosleec.repair import Edit, Patch, Reading, RepairReport, repair_text
from tests.unit.lsp.test_server import Session, at, utf16

HEAD = """// café ☕ 🙂: characters of one and two UTF-16 units before the rules
def_start
    event Start
    event Go
    measure busy : boolean
    measure level : numeric
def_end
rule_start
    /* é🙂 */ R1 when Start then Go within 5 seconds
"""
REDUNDANT = HEAD + "    /* 🙂é */ R2 when Start and busy then Go within 5 seconds /* ☕ */\nrule_end\n"
CONFLICT = HEAD + "    /* 🙂 */ R3 when Start and level > 3 then not Go within 5 seconds\nrule_end\n"
FIX_ALL = "source.cosleec.fixAll"


def lsp_apply(text: str, edits: Sequence[T.TextEdit]) -> str:
    """Apply LSP edits as the protocol says: positions in UTF-16 units on lines ended by
    ``\\r\\n``, ``\\r`` or ``\\n``, all against the original text; insertions at one place
    appear in the array's order."""
    starts = [0, *(m.end() for m in re.finditer(r"\r\n|\r|\n", text))]

    def offset(p: T.Position) -> int:
        i = starts[p.line]
        units = 0
        while units < p.character:
            units += utf16(text[i])
            i += 1
        assert units == p.character, "a position inside a character"
        return i

    spans = [(offset(e.range.start), offset(e.range.end), e.new_text) for e in edits]
    assert all(a[1] <= b[0] for a, b in itertools.pairwise(spans)), "edits out of order or overlapping"
    for start, end, new in reversed(spans):
        text = text[:start] + new + text[end:]
    return text


def repaired(text: str, path: str) -> RepairReport:
    """The engine's answer, called directly (the expected side)."""
    return repair_text(text, Reading(path, Settings()))


@pytest.fixture(scope="module")
def lsp() -> Iterator[Session]:
    session = Session({"debounce": 0.01, "analysisTimeout": 60})
    yield session
    session.close()


def save(lsp: Session, uri: str, text: str) -> list[T.Diagnostic]:
    """Save ``uri`` and wait for the findings of ``cosleec analyse``."""
    since = lsp.mark()
    lsp.call(lsp.client.text_document_did_save, T.DidSaveTextDocumentParams(lsp.doc(uri), text=text))
    diags = lsp.diagnostics(uri, since, lambda p: any(d.source == "cosleec analyse" for d in p.diagnostics))
    return [d for d in diags if d.source == "cosleec analyse"]


def actions(
    lsp: Session,
    uri: str,
    where: T.Range,
    diagnostics: Sequence[T.Diagnostic] = (),
    only: Sequence[str] | None = None,
    wait: bool = False,
) -> list[T.CodeAction]:
    """The code actions at ``where``; with ``wait``, asked again until there are some (the
    repairs arrive after the findings)."""
    params = T.CodeActionParams(
        text_document=lsp.doc(uri),
        range=where,
        context=T.CodeActionContext(diagnostics=list(diagnostics), only=only),
    )
    deadline = time.monotonic() + 60
    while True:
        got = lsp.run(lsp.client.text_document_code_action_async(params)) or []
        found = [a for a in got if isinstance(a, T.CodeAction)]
        if found or not wait or time.monotonic() > deadline:
            return found
        time.sleep(0.05)


def test_the_server_offers_quick_fixes_and_fix_all(lsp: Session) -> None:
    options = lsp.init.capabilities.code_action_provider
    assert isinstance(options, T.CodeActionOptions)
    assert set(options.code_action_kinds or ()) == {T.CodeActionKind.QuickFix, FIX_ALL}


def test_a_redundant_rule_is_fixed_by_its_verified_patch_then_stale_after_an_edit(lsp: Session) -> None:
    path = "/tmp/cosleec-lsp/fix-redundant.sleec"
    uri = f"file://{path}"
    assert lsp.open(uri, REDUNDANT) == []
    [finding] = save(lsp, uri, REDUNDANT)
    assert finding.code == "redundant"
    assert finding.range.start == at(REDUNDANT, "R2 when")  # after 🙂 (two units) and é (one)
    expected = repaired(REDUNDANT, path)
    [repairs] = expected.repairs
    [fix] = repairs.fixes
    got = actions(lsp, uri, finding.range, [finding], wait=True)
    quick = [a for a in got if a.kind == T.CodeActionKind.QuickFix]
    assert [a.title for a in quick] == [f"Fix (rank 1, remove-rule): {fix.patch.summary}"]
    [action] = quick
    assert action.is_preferred is True and list(action.diagnostics or ()) == [finding]
    assert action.edit is not None and action.edit.changes is not None
    edits = action.edit.changes[uri]
    # the removal starts after the comment: a conversion counting code points would start two units early
    assert edits[0].range.start == at(REDUNDANT, "R2 when")
    assert lsp_apply(REDUNDANT, edits) == fix.text == fix.patch.apply(REDUNDANT)
    assert "R2" not in fix.text
    # the patch set that verifies applied together, as a source action
    [whole] = [a for a in got if a.kind == FIX_ALL]
    assert whole.title == "Fix all (verified together)" and not whole.is_preferred
    assert expected.plan is not None and whole.edit is not None and whole.edit.changes is not None
    assert lsp_apply(REDUNDANT, whole.edit.changes[uri]) == expected.plan.text
    # what a client asks for is what it gets
    only_source = actions(lsp, uri, finding.range, [finding], only=["source"])
    assert [a.kind for a in only_source] == [FIX_ALL]
    assert [a.kind for a in actions(lsp, uri, finding.range, [finding], only=["quickfix"])] == ["quickfix"]
    # without the diagnostic in the request, the findings the range touches (the cursor in R2's name)
    cursor = at(REDUNDANT, "R2 when", 1)
    assert [a.title for a in actions(lsp, uri, T.Range(cursor, cursor)) if a.kind == "quickfix"] == [
        action.title
    ]
    end = finding.range.end  # a cursor at the name's end touches it; one unit further does not
    past = T.Position(end.line, end.character + 1)
    assert [a.kind for a in actions(lsp, uri, T.Range(end, end))] == ["quickfix", FIX_ALL]
    assert [a.kind for a in actions(lsp, uri, T.Range(past, past))] == [FIX_ALL]
    elsewhere = at(REDUNDANT, "R1 when")
    assert [a.kind for a in actions(lsp, uri, T.Range(elsewhere, elsewhere))] == [FIX_ALL]
    # an edit: the offsets would land in the wrong places, so nothing is offered
    top = T.Position(0, 0)
    edited = "// é🙂 moved\n" + REDUNDANT
    lsp.change(uri, 2, [T.TextDocumentContentChangePartial(range=T.Range(top, top), text="// é🙂 moved\n")])
    assert actions(lsp, uri, finding.range, [finding]) == []
    assert actions(lsp, uri, T.Range(top, at(edited, "rule_end"))) == []
    # the next save repairs the new text: the fix lands where the rule now is
    [again] = save(lsp, uri, edited)
    assert again.range.start == at(edited, "R2 when") != finding.range.start
    redone = [a for a in actions(lsp, uri, again.range, [again], wait=True) if a.kind == "quickfix"]
    [fix2] = repaired(edited, path).repairs[0].fixes
    assert redone[0].edit is not None and redone[0].edit.changes is not None
    assert lsp_apply(edited, redone[0].edit.changes[uri]) == fix2.text


def test_every_ranked_fix_is_offered_in_rank_order_and_only_rank_1_is_preferred(lsp: Session) -> None:
    path = "/tmp/cosleec-lsp/fix-conflict.sleec"
    uri = f"file://{path}"
    lsp.open(uri, CONFLICT)
    findings = save(lsp, uri, CONFLICT)
    expected = repaired(CONFLICT, path)
    assert [d.code for d in findings] == [f.code for f in expected.findings]
    several = [r for r in expected.repairs if len(r.fixes) > 1]
    assert several, "the engine offers one fix or none for each finding of this file"
    for repairs in several:
        [shown] = [d for d in findings if d.message.startswith(repairs.finding.diagnostic().message)]
        got = [a for a in actions(lsp, uri, shown.range, [shown], wait=True) if a.kind == "quickfix"]
        assert [a.title for a in got] == [
            f"Fix (rank {f.rank}, {f.patch.operator}): {f.patch.summary}" for f in repairs.fixes
        ]
        assert [a.is_preferred for a in got] == [True] + [None] * (len(got) - 1)
        for a, fix in zip(got, repairs.fixes, strict=True):
            assert a.edit is not None and a.edit.changes is not None and list(a.diagnostics or ()) == [shown]
            assert lsp_apply(CONFLICT, a.edit.changes[uri]) == fix.text


def test_the_on_save_process_sends_the_findings_then_their_repairs() -> None:
    got: list[Outcome] = []
    done = threading.Event()

    def finished(uri: str, outcome: Outcome) -> None:
        got.append(outcome)
        if outcome.of_repairs:
            done.set()

    runner = OnSave(finished)
    try:
        runner.start(
            "file:///r.sleec", REDUNDANT, "r.sleec", options=Options(), dialect="auto", timeout=60,
            legos_compat=False, repair=True,
        )  # fmt: skip
        assert done.wait(60)
    finally:
        runner.close()
    findings, fixes = got
    assert [d.code for d in findings.diagnostics] == ["redundant"] and not findings.of_repairs
    assert fixes.repairs is not None and fixes.repairs.text == REDUNDANT and not fixes.failed
    [(diagnostic, offers)] = fixes.repairs.fixes
    assert diagnostic == findings.diagnostics[0]
    assert [(o.rank, o.operator) for o in offers] == [(1, "remove-rule")]


# ---------------------------------------------------------------- edits, on any text

_CHARS = st.sampled_from(["a", " ", "\n", "\r\n", "\r", "é", "🙂", "𝔘", "R1"])


@st.composite
def texts_and_edits(draw: st.DrawFn) -> tuple[str, list[Edit]]:
    text = "".join(draw(st.lists(_CHARS, max_size=30)))
    # LSP has no position between `\r` and `\n`: an edit never starts or ends there
    places = [i for i in range(len(text) + 1) if not (0 < i < len(text) and text[i - 1 : i + 1] == "\r\n")]
    cuts = sorted(draw(st.lists(st.sampled_from(places), max_size=6)))
    edits = []
    for i in range(0, len(cuts) - 1, 2):  # pairs of cuts: edits that never overlap, some empty
        edits.append(Edit(cuts[i], cuts[i + 1], draw(st.sampled_from(["", "x", "🙂\n", "R9 "]))))
    edits += [
        Edit(c, c, draw(st.sampled_from(["<1>", "<2>"])))
        for c in draw(st.lists(st.sampled_from(places), max_size=2))
    ]
    edits = [e for e in edits if not any(o.start < e.end and e.start < o.end for o in edits if o is not e)]
    return text, draw(st.permutations(edits))


@settings(max_examples=300, deadline=None)
@given(texts_and_edits())
def test_text_edits_give_what_the_patch_gives(case: tuple[str, list[Edit]]) -> None:
    text, edits = case
    patch = Patch("test", "", (), tuple(edits))
    assert lsp_apply(text, text_edits(LineIndex(text), edits)) == patch.apply(text)


def test_two_insertions_at_one_place_keep_the_patch_s_order() -> None:
    text = "rule_start\nrule_end\n"
    end = len(text)
    edits = [Edit(end, end, "first\n"), Edit(end, end, "second\n")]
    got = lsp_apply(text, text_edits(LineIndex(text), edits))
    assert got == Patch("test", "", (), tuple(edits)).apply(text) == text + "second\nfirst\n"

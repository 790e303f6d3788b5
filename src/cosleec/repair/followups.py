"""A repair of the repair: a candidate that removes its finding but makes a new one, with
the new one repaired too.

Adding the rule a concern asks for often makes an existing rule redundant, or clashes with a
rule that forbids what it requires; the candidate alone then fails verification, although
it does what the finding asks. A follow-up repairs each new finding with the two operators
that change nothing else: removing a rule that has become redundant, or declaring which of
two clashing rules takes precedence. The result is one patch of the original file (its edits
found by comparing texts) and is verified like any other.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator

from cosleec.repair.candidates import Candidates
from cosleec.repair.patch import Patch, edits_between
from cosleec.repair.verify import Verdict, key

LOCAL = frozenset({"remove-rule", "declare-priority"})
"""The operators a follow-up uses: each changes nothing but the new finding's cause."""
NEW_AT_MOST = 3
"""New findings a follow-up takes on; a candidate that makes more is not followed up."""
OPTIONS = 2
"""Follow-up patches tried per new finding."""


def follow_ups(first: Patch, verdict: Verdict, source: str, before: frozenset[str]) -> Iterator[Patch]:
    """``first`` with each new finding it made repaired too, when all it did wrong was to
    make at most :data:`NEW_AT_MOST` new findings (its own finding gone). ``before``: the
    original file's rule names. A priority that lets the rules ``first`` wrote or added
    prevail is tried first: they are the repair."""
    if not verdict.new or len(verdict.new) > NEW_AT_MOST or verdict.checked is None:
        return
    if any(not r.startswith("new finding: ") for r in verdict.reasons):
        return
    patched = verdict.checked
    if patched.spec is None:
        return
    text = patched.source
    made = [f for f in verdict.after if key(f) in verdict.new]
    candidates = Candidates(text, patched.spec)
    # (removing the rule the first patch added would undo it: verification says so)
    mine = set(first.rules) | {r.name for r in patched.spec.rules if r.name not in before}
    options = [
        sorted((p for p in candidates.of(f) if p.operator in LOCAL), key=lambda p: _order(p, mine))[:OPTIONS]
        for f in made
    ]
    seen: set[str] = set()
    for combination in itertools.product(*options):
        chosen = list({p.summary: p for p in combination}.values())  # one finding's fix may serve two
        if any(a.overlaps(b) for a, b in itertools.combinations(chosen, 2)):
            continue
        pairs = list(
            dict.fromkeys((p.rules[0], p.rules[1]) for p in chosen if p.operator == "declare-priority")
        )
        if any((low, high) in pairs for high, low in pairs):
            continue  # both ways round: a cycle, which the language refuses
        edits = [e for p in chosen if p.operator != "declare-priority" for e in p.edits]
        if pairs:  # one block for them all
            edits.append(candidates.ops.writer.add_priorities(pairs))
        final = Patch("follow-up", "", (), tuple(edits)).apply(text)
        if final in seen:
            continue
        seen.add(final)
        said = "; ".join(dict.fromkeys(p.summary for p in chosen))
        rules = tuple(dict.fromkeys([*first.rules, *(r for p in chosen for r in p.rules)]))
        yield Patch(first.operator, f"{first.summary}; then {said}", rules, edits_between(source, final))


def _order(p: Patch, mine: set[str]) -> int:
    """Follow-ups in the order to try: a priority for the repair's own rules, then one against
    them, then removals."""
    if p.operator == "declare-priority":
        return 0 if p.rules[0] in mine else 1
    return 2


__all__ = ["follow_ups"]

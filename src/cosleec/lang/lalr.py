"""A tight LALR(1) driver over the tables and callbacks Lark computes from ``sleec.lark``.

Why: Lark's own driver looks every reduction up by ``Rule``/``Token`` objects that are
equal but not identical, so each step pays for several Python-level ``__eq__`` calls.
Re-keying Lark's table once, by plain strings and precomputed ``(size, origin,
callback)`` triples, roughly doubles parsing speed; the grammar, the table construction
and the tree-building callbacks (``ChildFilter`` + our inline transformer) all stay
Lark's.

The driver also does panic-mode error recovery, so that one run reports several syntax
errors instead of stopping at the first.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from lark import Lark
from lark.parsers.lalr_analysis import Shift

END = "$END"
BAD_CHAR = "$BADCHAR"


@dataclass(frozen=True, slots=True)
class SyntaxProblem:
    """One syntax error: the token met and the terminals the parser would have taken."""

    token: tuple[str, str, int, int, int]  # see lexer.Token; type END at end of input
    expected: frozenset[str]


def direct_callback(rule: Any, transformer: Any) -> Any:
    """A callback for ``rule`` that does what Lark's tree builder does for it -- drop filtered
    tokens, insert ``None`` for absent ``[optional]`` parts, return a single child of a
    ``?rule`` unchanged, then call the transformer's method -- as one generated expression
    instead of a chain of generic wrappers. Computed from the same rule metadata Lark uses
    (``parse_tree_builder.maybe_create_child_filter``); None means "keep Lark's own callback"
    (rules needing tree expansion or without a transformer method).
    """
    name = str(rule.alias or rule.origin.name)
    method = getattr(transformer, name, None)
    opts = rule.options
    expansion = rule.expansion
    if method is None or getattr(opts, "template_source", None):
        return None
    empty = opts.empty_indices
    if empty:
        bits = "".join(str(int(b)) for b in empty)
        nones = [len(ones) for ones in bits.split("0")]
    else:
        nones = [0] * (len(expansion) + 1)
    parts: list[str] = []
    for i, sym in enumerate(expansion):
        parts += ["None"] * nones[i]
        if opts.keep_all_tokens or not (sym.is_term and sym.filter_out):
            if not sym.is_term and sym.name.startswith("_"):
                return None  # an inlined helper whose children would be spliced in
            parts.append(f"s[{i}]")
    parts += ["None"] * nones[len(expansion)]
    if opts.expand1 and not rule.alias and len(parts) == 1:
        src = f"lambda s: {parts[0]}"  # a `?rule` with one child returns it unchanged
    else:
        src = f"lambda s: m([{', '.join(parts)}])"
    return eval(compile(src, f"<cosleec callback {name}>", "eval"), {"m": method})


class CompiledLALR:
    """Lark's LALR table for one start symbol, re-keyed for speed."""

    def __init__(self, lark: Lark, start: str = "start", transformer: Any = None) -> None:
        inner = lark.parser.parser.parser  # ParsingFrontend -> LALR_Parser -> _Parser
        table = inner.parse_table
        callbacks = dict(inner.callbacks)
        if transformer is not None:  # same behaviour, without Lark's generic per-call wrappers
            for rule in lark.rules:
                fast = direct_callback(rule, transformer)
                if fast is not None:
                    callbacks[rule] = fast
        self.start_state: int = table.start_states[start]
        self.end_state: int = table.end_states[start]
        triples: dict[Any, tuple[int, str, Any]] = {}
        self.states: dict[int, dict[str, Any]] = {}
        for state, actions in table.states.items():
            row: dict[str, Any] = {}
            for term, (action, arg) in actions.items():
                if action is Shift:
                    row[str(term)] = arg  # a shift (or goto): the target state, a bare int
                else:
                    key = id(arg)
                    if key not in triples:
                        # A `?rule` reducing exactly one kept child returns that child
                        # unchanged: no callback needed (None marks the pass-through).
                        unit = (
                            len(arg.expansion) == 1
                            and arg.options.expand1
                            and arg.alias is None
                            and not arg.expansion[0].is_term
                            and not arg.expansion[0].name.startswith("_")
                        )
                        cb = None if unit else callbacks[arg]
                        triples[key] = (len(arg.expansion), str(arg.origin.name), cb)
                    row[str(term)] = triples[key]  # a reduction: (size, origin, callback)
            self.states[state] = row
        self.units: dict[tuple[int, int, str], int] = {}  # memo of unit-reduction chains

    def expected(self, state: int) -> frozenset[str]:
        return frozenset(t for t in self.states[state] if t.isupper() or t.startswith("$"))

    def parse(self, tokens: Iterable[Any], problems: list[SyntaxProblem]) -> Any:
        """Parse; on error, record a :class:`SyntaxProblem`, skip the token and go on.

        Returns the value of the start symbol, or None when any error occurred (a tree
        built around skipped tokens is not a faithful reading of the file). After an
        error, further errors are recorded only once three tokens have been accepted, so
        one mistake does not produce a cascade.
        """
        states = self.states
        units = self.units
        sstack: list[int] = [self.start_state]
        vstack: list[Any] = []
        quiet = 0
        last: Any = None
        for tok in tokens:
            last = tok
            t = tok[0]
            recovered = False
            while True:
                act = states[sstack[-1]].get(t)
                if act is None:
                    if quiet == 0:
                        problems.append(SyntaxProblem(tok, self.expected(sstack[-1])))
                    quiet = 3
                    if recovered:  # resynchronising did not help: drop the token
                        break
                    recovered = True
                    # Pop to the nearest state that can take this token (its values go
                    # with it, so the stacks stay a viable prefix); none: drop the token.
                    depth = len(sstack) - 1
                    while depth > 0 and t not in states[sstack[depth - 1]]:
                        depth -= 1
                    if depth == 0:
                        break
                    del sstack[depth:]
                    del vstack[depth - 1 :]
                    continue
                if type(act) is int:  # shift
                    sstack.append(act)
                    vstack.append(tok)
                    if quiet:
                        quiet -= 1
                    break
                size, origin, cb = act
                if cb is None:
                    # Unit pass-through reductions keep the value and the state below, so a
                    # whole chain of them (primary -> term -> ... -> condition) ends in a state
                    # that depends only on (state below, top state, lookahead): memoized.
                    below = sstack[-2]
                    key = (below, sstack[-1], t)
                    top = units.get(key)
                    if top is None:
                        top = states[below][origin]
                        while True:
                            nxt = states[top].get(t)
                            if nxt is None or type(nxt) is int or nxt[2] is not None:
                                break
                            top = states[below][nxt[1]]
                        units[key] = top
                    sstack[-1] = top
                    continue
                if size:
                    s = vstack[-size:]
                    del sstack[-size:]
                    del vstack[-size:]
                else:
                    s = []
                vstack.append(cb(s))
                sstack.append(states[sstack[-1]][origin])
        end = (END, "", 0, last[3], last[4] + len(last[1])) if last is not None else (END, "", 0, 1, 1)
        while True:
            act = states[sstack[-1]].get(END)
            if act is None:
                if quiet == 0 or not problems:
                    problems.append(SyntaxProblem(end, self.expected(sstack[-1])))
                return None
            if type(act) is int:  # pragma: no cover - Lark never shifts $END
                return None
            size, origin, cb = act
            if size:
                s = vstack[-size:]
                del sstack[-size:]
                del vstack[-size:]
            else:
                s = []
            value = s[0] if cb is None else cb(s)
            sstack.append(states[sstack[-1]][origin])
            vstack.append(value)
            if sstack[-1] == self.end_state:
                return None if problems else value

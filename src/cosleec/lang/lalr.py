"""A tight LALR(1) driver over the table and callbacks Lark computes from a grammar.

Why: Lark's own driver looks every reduction up by ``Rule``/``Token`` objects that are
equal but not identical, so each step pays for several Python-level ``__eq__`` calls, and
its tree builder wraps each callback in generic helpers. Re-keying Lark's table once, by
plain strings and precomputed ``(size, origin, callback)`` triples, and calling the
transformer directly, makes parsing more than twice as fast (benchmarks/parse_corpus.py
measures it against plain Lark in the same run; the fast driver stays only while it keeps
a 2x advantage). The grammar, the table construction and the tree shape all stay Lark's.

Lark offers no public access to its table, so :func:`read_lark_tables` -- and nothing else
in cosleec -- reads Lark's internals, for the version pinned in pyproject.toml.
tests/unit/lang/test_parser_crosscheck.py holds the driver equal to plain Lark.

The driver also does panic-mode error recovery, so that one run reports several syntax
errors instead of stopping at the first.

May import: lark (``Lark``; its internals only in :func:`read_lark_tables`), lexer.py.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from lark import Lark

from cosleec.lang.lexer import BAD_CHAR, Lexicon, Production, Token

_new = tuple.__new__

END = "$END"
"""The type of the end-of-input token (Lark's name for it)."""


@dataclass(frozen=True, slots=True)
class RuleShape:
    """One grammar rule as Lark's tree builder treats it (read by :func:`read_lark_tables`)."""

    origin: str  # the nonterminal it reduces to
    name: str  # the transformer method that builds its value: the alias, else the origin
    symbols: tuple[str, ...]
    terminal: tuple[bool, ...]  # per symbol: is it a terminal
    kept: tuple[bool, ...]  # per symbol: is it passed to the callback (filtered tokens are not)
    placeholders: tuple[int, ...]  # Nones Lark inserts for absent `[x]` before each symbol and at the end
    expand1: bool  # a `?rule`: a single child is returned unchanged
    aliased: bool
    template: bool  # expanded from a template
    lark_callback: Callable[[list[Any]], Any]  # what Lark's own parser calls on reduction


@dataclass(frozen=True)
class Tables:
    """An LALR table in plain data: a shift is the target state, a reduction its rule."""

    start_states: dict[str, int]
    end_states: dict[str, int]
    states: dict[int, dict[str, int | RuleShape]]
    rules: list[RuleShape]

    def productions(self) -> list[Production]:
        """The rules as the lexicon needs them (see lexer.Lexicon)."""
        return [Production(r.origin, r.symbols) for r in self.rules]


def read_lark_tables(lark: Lark) -> Tables:
    """LARK INTERNALS -- the one place cosleec reads Lark beyond its public API.

    Written against the Lark version pinned in pyproject.toml (1.3.x); any other version
    may move these attributes, and tests/unit/lang/test_parser_crosscheck.py fails then.
    Reads: the LALR parse table (``lark.parser.parser.parser.parse_table``), the callbacks
    Lark's tree builder made for the transformer given to ``Lark`` (``.callbacks``), and
    each rule's shape (``lark.rules``: origin, alias, expansion, options). Everything is
    copied into plain data; the rest of cosleec never touches a Lark object but ``Lark``.
    """
    inner = lark.parser.parser.parser  # ParsingFrontend -> LALR_Parser -> _Parser
    table = inner.parse_table
    shapes: dict[Any, RuleShape] = {}
    for rule in lark.rules:
        opts = rule.options
        n = len(rule.expansion)
        if opts.empty_indices:
            bits = "".join(str(int(b)) for b in opts.empty_indices)
            placeholders = tuple(len(ones) for ones in bits.split("0"))
        else:
            placeholders = (0,) * (n + 1)
        shapes[rule] = RuleShape(
            origin=str(rule.origin.name),
            name=str(rule.alias or rule.origin.name),
            symbols=tuple(str(s.name) for s in rule.expansion),
            terminal=tuple(bool(s.is_term) for s in rule.expansion),
            kept=tuple(
                opts.keep_all_tokens or not (s.is_term and getattr(s, "filter_out", False))
                for s in rule.expansion
            ),
            placeholders=placeholders,
            expand1=bool(opts.expand1),
            aliased=rule.alias is not None,
            template=bool(getattr(opts, "template_source", None)),
            lark_callback=inner.callbacks[rule],
        )
    states: dict[int, dict[str, int | RuleShape]] = {}
    for state, actions in table.states.items():
        states[state] = {
            str(term): (arg if str(action) == "Shift" else shapes[arg])
            for term, (action, arg) in actions.items()
        }
    return Tables(dict(table.start_states), dict(table.end_states), states, list(shapes.values()))


@dataclass(frozen=True, slots=True)
class SyntaxProblem:
    """One syntax error: the token met and the terminals the parser would have taken."""

    token: Token  # type END at the end of input
    expected: frozenset[str]


def direct_callback(rule: RuleShape, transformer: Any) -> Callable[[list[Any]], Any] | None:
    """A callback for ``rule`` that does what Lark's tree builder does for it -- drop filtered
    tokens, insert ``None`` for absent ``[optional]`` parts, return a single child of a
    ``?rule`` unchanged, then call the transformer's method -- as one generated expression
    instead of a chain of generic wrappers. None means "keep Lark's own callback" (rules
    needing tree expansion, or without a transformer method).
    """
    method = getattr(transformer, rule.name, None)
    if method is None or rule.template:
        return None
    parts: list[str] = []
    for i, kept in enumerate(rule.kept):
        parts += ["None"] * rule.placeholders[i]
        if kept:
            if _inlined(rule, i):
                return None  # an inlined helper whose children would be spliced in
            parts.append(f"s[{i}]")
    parts += ["None"] * rule.placeholders[len(rule.kept)]
    if rule.expand1 and not rule.aliased and len(parts) == 1:
        src = f"lambda s: {parts[0]}"  # a `?rule` with one child returns it unchanged
    elif (inlined := _inline_callback(rule, transformer, parts)) is not None:
        return inlined
    elif parts == [f"s[{i}]" for i in range(len(rule.symbols))]:
        as_is: Callable[[list[Any]], Any] = method  # the children as they are: no wrapper at all
        return as_is
    else:
        src = f"lambda s: m([{', '.join(parts)}])"
    fn: Callable[[list[Any]], Any] = eval(
        compile(src, f"<cosleec callback {rule.name}>", "eval"), {"m": method}
    )
    return fn


def _inline_callback(
    rule: RuleShape, transformer: Any, parts: list[str]
) -> Callable[[list[Any]], Any] | None:
    """The transformer's own inline body for ``rule``'s method, compiled with the children
    bound to ``c0``, ``c1``, ... (``inline_body``: see transformer.INLINE_BODIES); None when
    the transformer offers none, or the body reads a child the rule does not have."""
    offer = getattr(transformer, "inline_body", None)
    found = offer(rule.name) if offer is not None else None
    if found is None:
        return None
    body, env = found
    if any(int(k) >= len(parts) for k in re.findall(r"\bc(\d+)\b", body)):
        return None
    lines = [f"    c{k} = {part}" for k, part in enumerate(parts)]
    lines += [f"    {line}" for line in body.splitlines()]
    namespace = dict(env)
    src = "def callback(s):\n" + "\n".join(lines) + "\n"
    exec(compile(src, f"<cosleec callback {rule.name}>", "exec"), namespace)
    fn: Callable[[list[Any]], Any] = namespace["callback"]
    return fn


class CompiledLALR:
    """Lark's LALR table for one start symbol, re-keyed for speed.

    Use :meth:`parse` on the tokens of :meth:`cosleec.lang.lexer.Lexicon.tokens`. With
    ``transformer``, reductions call it directly (see :func:`direct_callback`); without,
    they call Lark's own callbacks (built for the transformer given to ``Lark``).
    """

    def __init__(self, tables: Tables, start: str = "start", transformer: Any = None) -> None:
        self.start_state: int = tables.start_states[start]
        self.end_state: int = tables.end_states[start]
        triples: dict[int, tuple[int, str, Any]] = {}
        self.states: dict[int, dict[str, Any]] = {}
        for state, actions in tables.states.items():
            row: dict[str, Any] = {}
            for term, act in actions.items():
                if type(act) is int:
                    row[term] = act  # a shift (or goto): the target state, a bare int
                    continue
                assert isinstance(act, RuleShape)
                key = id(act)
                if key not in triples:
                    # A `?rule` reducing exactly one kept child returns that child
                    # unchanged: no callback needed (None marks the pass-through).
                    unit = (
                        len(act.symbols) == 1
                        and act.expand1
                        and not act.aliased
                        and not act.terminal[0]
                        and not _inlined(act, 0)
                    )
                    cb = None
                    if not unit:
                        fast = direct_callback(act, transformer) if transformer is not None else None
                        cb = fast or act.lark_callback
                    triples[key] = (len(act.symbols), act.origin, cb)
                row[term] = triples[key]  # a reduction: (size, origin, callback)
            self.states[state] = row
        # The driver's own form of a reduction: (size, goto, callback), where goto maps the
        # state below the reduced symbols to the state after it (one look-up, not two).
        gotos: dict[str, dict[int, int]] = {}
        for origin in {triple[1] for triple in triples.values()}:
            gotos[origin] = {s: row[origin] for s, row in self.states.items() if origin in row}
        by_triple = {id(triple): (triple[0], gotos[triple[1]], triple[2]) for triple in triples.values()}
        self._rows: list[dict[str, Any]] = [{} for _ in range(max(self.states, default=-1) + 1)]
        for state, row in self.states.items():
            self._rows[state] = {
                term: act if type(act) is int else by_triple[id(act)] for term, act in row.items()
            }
        self.units: dict[tuple[int, int, str], int] = {}  # memo of unit-reduction chains
        self.terminals = frozenset(
            {END, *(sym for r in tables.rules for sym, term in zip(r.symbols, r.terminal) if term)}
        )
        kept = {s for r in tables.rules for s, term, k in zip(r.symbols, r.terminal, r.kept) if term and k}
        #: The terminals no rule passes to its callback (filtered out everywhere): the value
        #: stack of :meth:`parse_text` holds their text, not a token.
        self.unkept = self.terminals - kept - {END}

    def expected(self, state: int) -> frozenset[str]:
        """The terminals the parser accepts in ``state``."""
        return frozenset(t for t in self.states[state] if t in self.terminals)

    def parse(self, tokens: Iterable[Token], problems: list[SyntaxProblem]) -> Any:
        """Parse; on error, record a :class:`SyntaxProblem`, skip the token and go on.

        Returns the value of the start symbol, or None when any error occurred (a tree
        built around skipped tokens is not a faithful reading of the file). After an
        error, further errors are recorded only once three tokens have been accepted, so
        one mistake does not produce a cascade.

        The general driver, over any tokens; the front end parses text with
        :meth:`parse_text`, which does the same while it scans.
        """
        states = self._rows
        units = self.units
        state = self.start_state  # always sstack[-1]
        sstack: list[int] = [state]
        vstack: list[Any] = []
        quiet = 0
        recovered: Token | None = None  # the token an error recovery was last tried for
        tok: Token | None = None
        for tok in tokens:
            t = tok[0]
            while True:
                try:  # (a subscript is quicker than .get; a miss is a syntax error, rare)
                    act = states[state][t]
                except KeyError:
                    act = None
                if act is None:
                    if quiet == 0:
                        problems.append(SyntaxProblem(tok, self.expected(state)))
                    quiet = 3
                    if recovered is tok or not self._resync(sstack, vstack, t):
                        break  # resynchronising did not help, or cannot: drop the token
                    recovered = tok
                    state = sstack[-1]
                    continue
                if type(act) is int:  # shift
                    sstack.append(act)
                    vstack.append(tok)
                    state = act
                    if quiet:
                        quiet -= 1
                    break
                size, goto, cb = act
                if cb is None:
                    # Unit pass-through reductions keep the value and the state below, so a
                    # whole chain of them (primary -> term -> ... -> condition) ends in a state
                    # that depends only on (state below, top state, lookahead): memoized.
                    below = sstack[-2]
                    top = units.get((below, state, t))
                    sstack[-1] = state = self._unit_chain(below, state, t) if top is None else top
                    continue
                if size:
                    s = vstack[-size:]
                    del sstack[-size:]
                    del vstack[-size:]
                else:
                    s = []
                vstack.append(cb(s))
                state = goto[sstack[-1]]
                sstack.append(state)
        if tok is not None:
            end = Token(END, "", 0, tok.line, tok.column + len(tok.value))
        else:
            end = Token(END, "", 0, 1, 1)
        return self._finish(sstack, vstack, end, quiet, problems)

    def parse_text(self, lexicon: Lexicon, text: str, problems: list[SyntaxProblem]) -> Any:
        """``parse(lexicon.tokens(text), problems)``, scanning as it parses: the same value,
        the same problems (tokens, positions), in one loop instead of two, and with no token
        object for a terminal that no rule keeps (``when``, ``:``, ...: the value stack holds
        its text, which no callback reads; a problem gets the whole token).

        Why: the front end's parse was the scanner's loop and then the driver's, per token;
        fused, the token list and its appends are gone, and so are over half the token
        objects (the corpus: 40,162 of 74,685 tokens are never kept). One function, against
        the 60-line rule, because every call a token pays for shows in parse_corpus.
        tests/unit/lang/test_fast_parse.py holds it equal to :meth:`parse`.
        """
        states, units, unkept = self._rows, self.units, self.unkept
        state = self.start_state  # always sstack[-1]
        sstack: list[int] = [state]
        vstack: list[Any] = []
        quiet = 0
        recovered = -1  # the offset of the token an error recovery was last tried for
        outside, inside = lexicon.memos()
        memo = outside
        classify, (start_mark, end_mark) = lexicon.classify, lexicon.block_marks
        special = {start_mark, end_mark, BAD_CHAR}
        new, token, length = _new, Token, len  # locals: this loop is hot
        pos, line, line_start = 0, 1, 0
        pairs = lexicon.pairs(text)
        for layout, tok in pairs:
            t = memo.get(tok)
            if t is None:
                if not tok:
                    break  # the end of the text (its layout does not move the end token)
                t = memo[tok] = classify(tok, memo is inside)
            if layout:
                pos += length(layout)
                if "\n" in layout:
                    line += layout.count("\n")
                    line_start = pos - (length(layout) - layout.rindex("\n") - 1)
            if t in special:
                if t == start_mark:
                    memo = inside
                elif t == end_mark:
                    memo = outside
                elif tok == "/" and text.startswith("/*", pos):
                    t, tok = BAD_CHAR, "/*"  # an unterminated block comment: the last token
                    pairs.clear()  # (a list iterator ends at the list's length: this one)
            value = tok if t in unkept else new(token, (t, tok, pos, line, pos - line_start + 1))
            while True:
                try:  # (a subscript is quicker than .get; a miss is a syntax error, rare)
                    act = states[state][t]
                except KeyError:
                    act = None
                if act is None:
                    if quiet == 0:
                        whole = Token(t, tok, pos, line, pos - line_start + 1)
                        problems.append(SyntaxProblem(whole, self.expected(state)))
                    quiet = 3
                    if recovered == pos or not self._resync(sstack, vstack, t):
                        break  # resynchronising did not help, or cannot: drop the token
                    recovered = pos
                    state = sstack[-1]
                    continue
                if type(act) is int:  # shift
                    sstack.append(act)
                    vstack.append(value)
                    state = act
                    if quiet:
                        quiet -= 1
                    break
                size, goto, cb = act
                if cb is None:  # a unit pass-through chain (see parse)
                    below = sstack[-2]
                    top = units.get((below, state, t))
                    sstack[-1] = state = self._unit_chain(below, state, t) if top is None else top
                    continue
                if size:
                    s = vstack[-size:]
                    del sstack[-size:]
                    del vstack[-size:]
                else:
                    s = []
                vstack.append(cb(s))
                state = goto[sstack[-1]]
                sstack.append(state)
            pos += length(tok)
        end = Token(END, "", 0, line, pos - line_start + 1)  # where the last token ends
        return self._finish(sstack, vstack, end, quiet, problems)

    def _unit_chain(self, below: int, state: int, t: str) -> int:
        """The state a chain of unit pass-through reductions ends in, from ``state`` over
        ``below`` with lookahead ``t``; memoized in :attr:`units`."""
        states = self._rows
        top: int = states[state][t][1][below]
        while True:
            nxt = states[top].get(t)
            if nxt is None or type(nxt) is int or nxt[2] is not None:
                break
            top = nxt[1][below]
        self.units[(below, state, t)] = top
        return top

    def _resync(self, sstack: list[int], vstack: list[Any], t: str) -> bool:
        """After a syntax error on a token of type ``t``: pop to the nearest state that can
        take it (its values go with it, so the stacks stay a viable prefix); False, with the
        stacks untouched, when none can (the token is dropped)."""
        states = self._rows
        depth = len(sstack) - 1
        while depth > 0 and t not in states[sstack[depth - 1]]:
            depth -= 1
        if depth == 0:
            return False
        del sstack[depth:]
        del vstack[depth - 1 :]
        return True

    def _finish(
        self, sstack: list[int], vstack: list[Any], end: Token, quiet: int, problems: list[SyntaxProblem]
    ) -> Any:
        """The end of input (the token ``end``): the last reductions, and the start
        symbol's value; None, with a problem recorded, when the input stops too early."""
        states = self._rows
        while True:
            act = states[sstack[-1]].get(END)
            if act is None:
                if quiet == 0 or not problems:
                    problems.append(SyntaxProblem(end, self.expected(sstack[-1])))
                return None
            if type(act) is int:  # pragma: no cover - Lark never shifts $END
                return None
            size, goto, cb = act
            if size:
                s = vstack[-size:]
                del sstack[-size:]
                del vstack[-size:]
            else:
                s = []
            value = s[0] if cb is None else cb(s)
            sstack.append(goto[sstack[-1]])
            vstack.append(value)
            if sstack[-1] == self.end_state:
                return None if problems else value


def _inlined(rule: RuleShape, i: int) -> bool:
    """Is symbol ``i`` an `_rule`, whose children Lark's tree builder splices into the parent?"""
    return not rule.terminal[i] and rule.symbols[i].startswith("_")

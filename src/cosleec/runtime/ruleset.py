"""The one way from rules to a running rule set: a file, SLEEC text or a Specification.

Everything that runs rules -- the embedded :class:`~cosleec.runtime.Manager`, every node,
the command line -- builds its :class:`RuleSet` here::

    rules = RuleSet.from_file("rules.sleec")          # or .from_text(...), .from_spec(...)
    Manager(rules)

A rule file or text is parsed and checked by :mod:`cosleec.lang`; a
:class:`~cosleec.lang.Specification` built in Python is checked directly (not printed
and parsed again). Any error raises :class:`~cosleec.lang.SleecError` carrying every
diagnostic. Lookups by rule name and by trigger are dictionary lookups.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from cosleec.bulk import paused_gc
from cosleec.lang import (
    DiagnosticSink,
    Options,
    SleecError,
    Specification,
    SymbolTable,
    analyse,
    analyse_file,
    check,
    format_spec,
    infer_definitions,
)
from cosleec.runtime.compile import Compiler
from cosleec.runtime.model import CompiledRule, ItemSpec, compile_rule
from cosleec.runtime.values import MeasureSpec


@dataclass(frozen=True, eq=False, kw_only=True)
class RuleSet:
    """A checked specification compiled for execution; immutable, shareable between Managers.

    Build one with :meth:`from_file`, :meth:`from_text` or :meth:`from_spec`.
    """

    spec: Specification
    rules: tuple[CompiledRule, ...]
    measures: Mapping[str, MeasureSpec]
    events: frozenset[str]
    by_trigger: Mapping[str, tuple[CompiledRule, ...]]
    by_name: Mapping[str, CompiledRule]
    items: Mapping[str, ItemSpec]  # every response item by its key (``R1.2:0/o:1``)
    responds: frozenset[str]  # the events some response obliges (capabilities may exist for these)
    digest: str  # sha256 of the canonical text: which rules a journal or audit record belongs to

    @classmethod
    @paused_gc()
    def from_file(cls, path: str | Path, *, infer_defs: bool = False) -> RuleSet:
        """Read, parse, check and compile a rule file (any dialect, or the paper notation)."""
        result = analyse_file(path, infer_defs=infer_defs)
        if not result.ok or result.spec is None or result.symbols is None:
            raise SleecError(result.diagnostics, result.source)
        return cls._compile(result.spec, result.symbols)

    @classmethod
    @paused_gc()
    def from_text(cls, text: str, path: str = "<string>", *, infer_defs: bool = False) -> RuleSet:
        """Parse, check and compile SLEEC text; ``path`` names it in diagnostics."""
        result = analyse(text, path, infer_defs=infer_defs)
        if not result.ok or result.spec is None or result.symbols is None:
            raise SleecError(result.diagnostics, result.source)
        return cls._compile(result.spec, result.symbols)

    @classmethod
    @paused_gc()
    def from_spec(cls, spec: Specification, *, infer_defs: bool = False) -> RuleSet:
        """Check and compile a Specification as it is; ``infer_defs`` fills in a missing def block."""
        sink = DiagnosticSink(spec.path)
        if infer_defs and not spec.definitions:
            spec = infer_definitions(spec, sink)
        symbols = check(spec, sink, Options())
        diagnostics = sink.sorted()
        if any(d.is_error for d in diagnostics):
            raise SleecError(diagnostics)
        return cls._compile(spec, symbols)

    @classmethod
    def _compile(cls, spec: Specification, symbols: SymbolTable) -> RuleSet:
        compiler = Compiler(symbols)
        measures = {m.name: MeasureSpec.of(m) for m in spec.measures}
        literals = {n: m.literals for n, m in measures.items() if m.literals}
        rules = tuple(compile_rule(compiler, i, r, literals, spec.path) for i, r in enumerate(spec.rules))
        items = {it.key: it for r in rules for resp in r.responses() for it in resp.walk()}
        by_trigger: dict[str, list[CompiledRule]] = {}
        for cr in rules:
            by_trigger.setdefault(cr.trigger, []).append(cr)
        return cls(
            spec=spec,
            rules=rules,
            measures=measures,
            events=frozenset(e.name for e in spec.events),
            by_trigger={k: tuple(v) for k, v in by_trigger.items()},
            by_name={r.name: r for r in rules},
            items=items,
            responds=frozenset(it.event for it in items.values() if not it.negated),
            digest=hashlib.sha256(format_spec(spec).encode()).hexdigest(),
        )

    def rule(self, name: str) -> CompiledRule:
        """The rule named ``name``; KeyError if there is none."""
        return self.by_name[name]

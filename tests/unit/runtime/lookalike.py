"""A hostile caller's name: not a string, but hashing and comparing as one."""

from __future__ import annotations


class Lookalike:
    """Hashes and compares equal to ``name`` without being a string: it names no measure and
    no event (the runtime refuses it on every path, as it refuses any name that is no string)."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __hash__(self) -> int:
        return hash(self.name)

    def __eq__(self, other: object) -> bool:
        return other == self.name

    def __repr__(self) -> str:
        return f"Lookalike({self.name!r})"

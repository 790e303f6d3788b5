"""Errors of the CO-SLEEC runtime."""

from __future__ import annotations


class RuntimeErrorBase(Exception):
    """Base class of runtime errors."""


class ContextError(RuntimeErrorBase, ValueError):
    """A context update was rejected (unknown measure, wrong type, value outside the scale)."""


class UnknownMeasureError(RuntimeErrorBase, LookupError):
    """A condition needs a measure that has no (fresh) value."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        super().__init__(f"no value for {', '.join(names)}")


class BindingError(RuntimeErrorBase):
    """Tasks or capabilities do not cover the rules they are bound to (completeness check)."""

    def __init__(self, missing: list[str]) -> None:
        self.missing = missing
        super().__init__("incomplete implementation:\n  - " + "\n  - ".join(missing))

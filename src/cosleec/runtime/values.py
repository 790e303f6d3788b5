"""Typed measure values: validation and conversion (booleans, numbers, scale literals).

Scale values travel as literal names and are stored as their position, so that a
comparison such as ``m >= medium`` is one integer comparison.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cosleec.errors import show
from cosleec.lang import ast as A
from cosleec.runtime.errors import ContextError

Value = bool | int | float | str


@dataclass(frozen=True, slots=True)
class MeasureSpec:
    """A measure's type as the runtime checks it: ``boolean``, ``numeric`` or ``scale``."""

    name: str
    kind: str  # "boolean" | "numeric" | "scale"
    literals: tuple[str, ...] = ()

    @classmethod
    def of(cls, decl: A.MeasureDecl) -> MeasureSpec:
        """The spec of a declared measure."""
        t = decl.type
        if isinstance(t, A.ScaleType):
            return cls(decl.name, "scale", t.literals)
        return cls(decl.name, "boolean" if isinstance(t, A.BooleanType) else "numeric", ())

    def coerce(self, value: object) -> bool | int | float:
        """The stored form of ``value``, or ContextError saying why it is not acceptable."""
        if self.kind == "boolean":
            if isinstance(value, bool):
                return value
            raise ContextError(f"{self.name} is boolean; got {type(value).__name__} {show(value)}")
        if self.kind == "numeric":
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ContextError(f"{self.name} is numeric; got {type(value).__name__} {show(value)}")
            value = _plain(self.name, value)
            try:
                finite = math.isfinite(value)  # an int beyond float range overflows here
            except OverflowError:
                finite = False
            if not finite:
                raise ContextError(
                    f"{self.name} must be a finite number of at most 1.8e308; got {show(value)}"
                )
            return value
        if isinstance(value, str):
            if type(value) is not str:
                raise ContextError(
                    f"{self.name}: a scale value is a plain str, not {type(value).__name__}, "
                    "whose comparisons could differ from the text it holds",
                    hint="pass str(value)",
                )
            try:
                return self.literals.index(value)
            except ValueError:
                raise ContextError(
                    f"{show(value)} is not in the scale of {self.name} ({', '.join(self.literals)})"
                ) from None
        raise ContextError(f"{self.name} is a scale ({', '.join(self.literals)}); got {show(value)}")

    def external(self, stored: bool | int | float) -> Value:
        """The value as users see it (scale positions back to literal names)."""
        if self.kind == "scale":
            return self.literals[int(stored)]
        return stored

    def parse(self, text: str) -> bool | int | float:
        """A value written on a command line: true/false, a number, or a scale literal."""
        t = text.strip()
        if self.kind == "boolean":
            if t.lower() in ("true", "false"):
                return t.lower() == "true"
            raise ContextError(f"{self.name} is boolean: write true or false, not {text!r}")
        if self.kind == "numeric":
            try:
                return self.coerce(int(t))
            except ValueError:
                try:
                    return self.coerce(float(t))
                except ValueError:
                    raise ContextError(f"{self.name} is numeric: {show(text)} is not a number") from None
        return self.coerce(t)


def _plain(name: str, value: int | float) -> int | float:
    """``value`` as a plain int or float: the Manager compares what it stores, so a number
    must not bring comparisons of its own.

    A NumPy scalar (``numpy.float64`` subclasses float) is read as the number it holds;
    any other subclass of int or float is refused, since its class may define ``<`` or
    ``==`` to say something other than the number does.
    """
    kind = type(value)
    if kind is int or kind is float:
        return value
    if kind.__module__ == "numpy" and isinstance(value, float):
        return float.__float__(value)  # the C double it holds, whatever its class says
    raise ContextError(
        f"{name} is numeric: give a plain int or float, not {kind.__name__} (a subclass of "
        f"{'float' if isinstance(value, float) else 'int'}, whose comparisons could differ from its value)",
        hint="pass float(value)",
    )

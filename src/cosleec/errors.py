"""The root of every error cosleec raises for SLEEC reasons, and the branch users can fix.

Floor 0 of the house: this module imports nothing of ours, so every package may raise
these. ``cosleec.cop`` keeps its own root, ``COPError``, because it is a generic COP
library that knows nothing of SLEEC.

Only the command line turns a :class:`UserError` into a message and an exit code; a
library module never prints or calls ``sys.exit``.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any

__all__ = ["ConfigurationError", "CosleecError", "UserError", "clip", "closest", "show"]


class CosleecError(Exception):
    """Base of every error cosleec raises for SLEEC reasons: catch it to catch them all."""


class UserError(CosleecError):
    """A mistake the user can fix: bad input, a wrong option, a missing file.

    The CLI prints :meth:`render` (``where``, the message, the hint) and exits with status 1
    -- never a traceback. Raise it (or a subclass named after the situation) whenever the
    cause is something the user wrote or chose, not a bug of ours.

    ``message`` says what is wrong; ``hint`` says how to fix it ("did you mean
    `userUndressed`?"); ``where`` says where the problem is ("rules.sleec:3:14",
    "mapping.yaml", a topic name). ``str(error)`` is the message with the hint on a second
    line (``unknown event 'FallDetect'\n  hint: did you mean FallDetected?``), so that a
    traceback, a log line or ``print(e)`` shows the fix too; a caller that words the hint
    itself reads ``message``.
    """

    def __init__(self, message: str, *, hint: str = "", where: str = "") -> None:
        super().__init__(message)
        self.message = str(message)
        self.hint = hint
        self.where = where

    def __str__(self) -> str:
        return f"{self.message}\n  hint: {self.hint}" if self.hint else self.message

    def render(self) -> str:
        """The message as the CLI prints it: ``where: message`` and the hint on its own line."""
        head = f"{self.where}: {self.message}" if self.where else self.message
        return f"{head}\n  hint: {self.hint}" if self.hint else head


class ConfigurationError(UserError, ValueError):
    """An option has a value it does not accept (``semantics="nestd"``); the message lists the choices.

    Also a ``ValueError``, for callers who catch that.
    """


def closest(word: object, choices: Iterable[str], cutoff: float = 0.6) -> str | None:
    """The one of ``choices`` that ``word`` most likely misspells, or None: a close match
    (difflib, similarity at least ``cutoff``), else one ignoring case (``userdistresed`` ->
    ``userDistressed``, ``HIGH`` -> ``high``)."""
    text = str(word)
    if len(text) > 200:  # a pasted paragraph misspells nothing
        return None
    names = sorted(choices)
    close = difflib.get_close_matches(text, names, n=1, cutoff=cutoff)
    if close:
        return close[0]
    lowered = {n.lower(): n for n in reversed(names)}
    close = difflib.get_close_matches(text.lower(), list(lowered), n=1, cutoff=cutoff)
    return lowered[close[0]] if close else None


def clip(text: str, limit: int = 200) -> str:
    """``text`` cut to ``limit`` characters, saying how many were cut: ``abc…(9997 more)``.

    Use it wherever a message or record echoes what a user or a sender wrote: cut, a 10 MB
    name makes a short line.
    """
    return text if len(text) <= limit else f"{text[:limit]}…({len(text) - limit} more)"


def show(value: Any, limit: int = 80) -> str:
    """``repr(value)`` cut to ``limit`` characters (:func:`clip`); never raises.

    A value whose repr fails (nested too deep, an int of more digits than Python prints, a
    broken ``__repr__``) is shown by its type.
    """
    try:
        text = repr(value)
    except Exception:  # RecursionError, ValueError (int digits limit), a broken __repr__
        return f"<{type(value).__name__}>"
    return clip(text, limit)

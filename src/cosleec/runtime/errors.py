"""Errors of the CO-SLEEC runtime, named after the situation; all are user errors.

Both derive from :class:`cosleec.errors.UserError`: the CLI prints them with their hint
and exits 1. :class:`ContextError` is also a ``ValueError`` for callers who catch that.
"""

from __future__ import annotations

from cosleec.errors import ConfigurationError, UserError

# ConfigurationError: from cosleec.errors
__all__ = ["BindingError", "ConfigurationError", "ContextError", "ReloadError"]


class ContextError(UserError, ValueError):
    """An input was rejected: unknown measure or event, wrong type, value outside the scale.

    Nothing changed: every update is all-or-nothing.
    """


class BindingError(UserError):
    """Tasks or capabilities do not cover the rules they are bound to (completeness check).

    ``missing`` lists every clause or event without an implementation; the message names
    the first :data:`SHOWN` of them and how many more there are (a 10,000-rule set with no
    capability would otherwise print 20,000 lines).
    """

    SHOWN = 20

    #: the hint of an incomplete implementation (what start() finds)
    INCOMPLETE = "implement each listed clause in its task (@hedge(i)) or register a capability for the event"

    def __init__(self, missing: list[str], hint: str = INCOMPLETE) -> None:
        self.missing = missing
        shown = missing[: self.SHOWN]
        more = len(missing) - len(shown)
        super().__init__(
            "incomplete implementation:\n  - "
            + "\n  - ".join(shown)
            + (f"\n  ... and {more:,} more (BindingError.missing lists them all)" if more else ""),
            hint=hint,
        )


class ReloadError(UserError):
    """A rule set the running Manager cannot take (:meth:`~cosleec.runtime.Manager.reload`).

    Raised before anything changes: the Manager goes on with its old rules, context,
    obligations and bindings, and records nothing. The message names what stands in the
    way; ``hint`` says how to make the reload possible.
    """

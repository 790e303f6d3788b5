"""COP isolation: run a block, then put the global COP configuration back as it was.

Built on public ``cosleec.cop`` API only: :func:`cosleec.cop.global_state` and
:func:`cosleec.cop.restore_globally` (global layers, their counts, dispatch and activation
hooks). Scoped activations need no reset: they end with their ``with`` blocks. Under
pytest, the plugin :mod:`cosleec.testing.plugin` applies it to every test.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from cosleec.cop import GlobalState, global_state, restore_globally

__all__ = ["isolated_cop"]


@contextmanager
def isolated_cop() -> Iterator[GlobalState]:
    """Run the block, then restore the global COP configuration it started with.

    Use it around a what-if simulation or a test that activates layers globally.
    """
    saved = global_state()
    try:
        yield saved
    finally:
        restore_globally(saved)

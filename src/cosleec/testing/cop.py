"""COP isolation for tests: each test leaves the global COP configuration as it found it.

Built on public ``cosleec.cop`` API only: :func:`cosleec.cop.global_state` and
:func:`cosleec.cop.restore_globally` (global layers, their counts, dispatch and activation
hooks). Scoped activations need no reset: they end with their ``with`` blocks.

Use it as a pytest plugin -- ``pytest_plugins = ["cosleec.testing.cop"]`` in the root
``conftest.py`` -- or import :func:`cop_isolation` into a directory's ``conftest.py``;
outside pytest, ``with isolated_cop():``.

PYTEST_DONT_REWRITE: this module has no assertions to rewrite, and the ``cosleec.testing``
face may import it before pytest loads it as a plugin.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from cosleec.cop import GlobalState, global_state, restore_globally


@contextmanager
def isolated_cop() -> Iterator[GlobalState]:
    """Run the block, then restore the global COP configuration it started with."""
    saved = global_state()
    try:
        yield saved
    finally:
        restore_globally(saved)


@pytest.fixture(autouse=True)
def cop_isolation() -> Iterator[GlobalState]:
    """Autouse: a test's global activations and hooks end with the test (a leak cannot reach the next)."""
    with isolated_cop() as saved:
        yield saved

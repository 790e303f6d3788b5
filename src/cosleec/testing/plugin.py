"""The cosleec pytest plugin: every test leaves the global COP configuration as it found it.

Load it with ``pytest_plugins = ["cosleec.testing.plugin"]`` in the root ``conftest.py``.
It is kept apart from the face of :mod:`cosleec.testing` so that importing the test
helpers never needs pytest.

PYTEST_DONT_REWRITE: this module has no assertions to rewrite.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from cosleec.cop import GlobalState
from cosleec.testing.cop import isolated_cop

__all__ = ["cop_isolation"]


@pytest.fixture(autouse=True)
def cop_isolation() -> Iterator[GlobalState]:
    """Autouse: a test's global activations and hooks end with the test (a leak cannot reach the next)."""
    with isolated_cop() as saved:
        yield saved

"""Fixtures of the node tests: an in-process bus, closed after each test."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from cosleec.nodes import LocalBus


@pytest.fixture
def bus() -> Iterator[LocalBus]:
    b = LocalBus()
    yield b
    b.close()

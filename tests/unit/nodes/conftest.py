from __future__ import annotations

from collections.abc import Iterator

import pytest

from cosleec.cop.state import reset_for_tests


@pytest.fixture(autouse=True)
def clean_cop_state() -> Iterator[None]:
    reset_for_tests()
    yield
    reset_for_tests()

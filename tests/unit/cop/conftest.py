"""The COP checklist runs against every dispatcher: the reference and the generated fast path.

A test that asks for the ``layered`` fixture runs once per dispatcher. Isolation comes from
the public ``cosleec.testing.plugin``, which the root ``conftest.py`` loads: each test
leaves the global configuration as it found it.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import pytest

from cosleec import cop


@pytest.fixture(params=["reference", "fast"])
def layered(request: pytest.FixtureRequest) -> Callable[..., Any]:
    """``cop.layered`` with the dispatcher under test."""
    return functools.partial(cop.layered, fast=request.param == "fast")

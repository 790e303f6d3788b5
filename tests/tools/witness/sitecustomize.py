"""The express lane's witness in a Python child of a test (``tests/conftest.py``).

A test run with ``COSLEEC_PATHS_OUT`` puts this directory first on the ``PYTHONPATH`` of the
processes a test starts, and names a file in ``COSLEEC_PATHS_WITNESS``. When such a child
imports the express lane, the lane is wrapped so that the first trigger or update it takes
creates that file: the test then counts as one the lane could have changed
(``scripts/test`` runs it again with ``COSLEEC_EXPRESS=0``). A child that never imports
cosleec pays one environment read.
"""

from __future__ import annotations

import os
import sys
from importlib.machinery import ModuleSpec, PathFinder
from types import ModuleType
from typing import Any

_WITNESS = os.environ.get("COSLEEC_PATHS_WITNESS")
# the lane's modules: the class, the method that puts a trigger's decisions in force (None:
# none), the one that takes an update (None: none), the one that makes a trigger (None: none)
_LANES = {
    "cosleec.runtime.express": ("Express", "_put_in_force", "update", None),
    "cosleec.runtime.plans": ("Plans", None, None, "trigger_function"),
}


def _seen() -> None:
    if _WITNESS and not os.path.exists(_WITNESS):
        open(_WITNESS, "a").close()


def _took(method: Any) -> Any:
    def taken(self: Any, *args: Any) -> Any:
        _seen()
        return method(self, *args)

    return taken


def _unless_none(method: Any) -> Any:
    def updated(self: Any, *args: Any) -> Any:
        out = method(self, *args)
        if out is not None:  # the lane took it
            _seen()
        return out

    return updated


def _made(method: Any) -> Any:
    def make(self: Any) -> Any:
        trigger = method(self)

        def noted(*args: Any) -> Any:
            out = trigger(*args)
            if out is not None:  # the lane took the trigger
                _seen()
            return out

        return noted

    return make


def _wrap(lane: Any, took: str | None, update: str | None, maker: str | None) -> None:
    for name, wrap in ((took, _took), (update, _unless_none), (maker, _made)):
        if name is not None:
            setattr(lane, name, wrap(getattr(lane, name)))


class _Witness:
    """A meta path finder that wraps the express lane's modules as they are imported."""

    def __init__(self) -> None:
        self.waiting = dict(_LANES)

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> ModuleSpec | None:
        wanted = self.waiting.pop(name, None)
        if wanted is None:
            return None
        if not self.waiting:
            sys.meta_path.remove(self)
        spec = PathFinder.find_spec(name, path, target)
        if spec is None or spec.loader is None:
            return spec
        loader = spec.loader
        load = loader.exec_module
        cls, took, update, maker = wanted

        def exec_module(module: ModuleType) -> None:
            load(module)
            _wrap(getattr(module, cls), took, update, maker)

        loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


if _WITNESS:
    sys.meta_path.insert(0, _Witness())

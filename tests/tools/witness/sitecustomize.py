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
_LANE = "cosleec.runtime.express"


class _Witness:
    """A meta path finder that wraps the express lane as it is imported."""

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> ModuleSpec | None:
        if name != _LANE:
            return None
        sys.meta_path.remove(self)
        spec = PathFinder.find_spec(name, path, target)
        if spec is None or spec.loader is None:
            return spec
        loader = spec.loader
        load = loader.exec_module

        def exec_module(module: ModuleType) -> None:
            load(module)
            lane = module.Express
            took, updating = lane._put_in_force, lane.update

            def seen() -> None:
                if _WITNESS and not os.path.exists(_WITNESS):
                    open(_WITNESS, "a").close()

            def taken(self: Any, *args: Any) -> Any:
                seen()
                return took(self, *args)

            def updated(self: Any, *args: Any) -> Any:
                out = updating(self, *args)
                if out is not None:  # the lane took the update
                    seen()
                return out

            lane._put_in_force = taken
            lane.update = updated

        loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


if _WITNESS:
    sys.meta_path.insert(0, _Witness())

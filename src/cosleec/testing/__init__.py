"""Public test helpers for cosleec users and its own tests (floor 2: may import cop and below).

- :mod:`cosleec.testing.cop` -- COP isolation: ``isolated_cop()`` and the autouse pytest
  fixture ``cop_isolation`` (load it with ``pytest_plugins = ["cosleec.testing.cop"]``).
"""

from cosleec.testing.cop import cop_isolation, isolated_cop

__all__ = ["cop_isolation", "isolated_cop"]

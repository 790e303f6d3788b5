"""cosleec: make robots behave according to SLEEC rules, with context-oriented programming.

Packages, one role each:

- :mod:`cosleec.lang` -- the SLEEC language: parser (TK, LEGOS, paper notation), checker, printer;
- :mod:`cosleec.cop` -- a generic context-oriented programming runtime (knows nothing of SLEEC);
- :mod:`cosleec.runtime` -- CO-SLEEC: rules become layers, the context drives activation;
- :mod:`cosleec.ros` -- adapters for ROS 2 and ROS 1 (the core never imports them);
- :mod:`cosleec.cli` -- the ``cosleec`` command.
"""

__version__ = "0.1.0"

"""The assistive-care demo: ten rules around the paper's curtain rule, a robot that obeys
them, and a scripted day, run embedded (:func:`main`, ``cosleec demo``) or over ROS
(``cosleec ros2 demo``, in :mod:`cosleec.ros`); :func:`outcomes` makes the runs comparable
record by record, whatever the transport."""

from cosleec.demo.assistive_care import scenario
from cosleec.demo.compare import Outcome, expected, first_difference, outcomes, summary
from cosleec.demo.player import Step, play
from cosleec.demo.runner import Display, Run, main, rules_path, run
from cosleec.demo.watch import PACE_S, Watch

__all__ = [
    "PACE_S",
    "Display",
    "Outcome",
    "Run",
    "Step",
    "Watch",
    "expected",
    "first_difference",
    "main",
    "outcomes",
    "play",
    "rules_path",
    "run",
    "scenario",
    "summary",
]

"""The assistive-care demo: ten rules around the paper's curtain rule, a robot that obeys
them, and a scripted day, run embedded (:func:`main`, ``cosleec demo``) or over ROS
(``cosleec ros2 demo``, in :mod:`cosleec.ros`)."""

from cosleec.demo.assistive_care import scenario
from cosleec.demo.player import Step, play
from cosleec.demo.runner import Display, Run, main, rules_path, run

__all__ = ["Display", "Run", "Step", "main", "play", "rules_path", "run", "scenario"]

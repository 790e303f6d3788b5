"""The assistive-care example: the rules, a scripted day, and the simulated robot that obeys them.

``rules.sleec`` holds the rules, :mod:`.scenario` the steps and the decisions they must
produce, :mod:`.tasks` the robot's tasks and capabilities; ``mapping.yaml`` and the
launch files run the same example on ROS. The files ship as package data:
:func:`cosleec.demo.rules_path` finds the rules wherever cosleec is installed.
"""

"""The assistive-care robot's curtain (R1) and camera (R10) rules as a py_trees behaviour tree.

    python examples/bt/curtains_and_camera.py                 # play the scenario, embedded
    python examples/bt/curtains_and_camera.py --render DIR    # also draw the tree (dot, png, svg)

Each rule is a :class:`cosleec.bt.RuleTask`: a default subtree and one subtree per
``unless`` clause, run as the Manager's decision says (the paper's COP mapping as a tree).
Every action sits under a :class:`cosleec.bt.Guarded` decorator -- asked before it starts,
reported when it succeeds -- so R6 (no video of a fallen user without consent) stops the
camera even where R10 asks for it, and the Manager judges each obligation by what the tree
reported. :class:`cosleec.bt.Obligations` keeps what is owed on the blackboard. The rules
are the demo's (``src/cosleec/demo/assistive_care/rules.sleec``). Needs the ``bt`` extra.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Access, Status

from cosleec import Manager, VirtualClock
from cosleec.bt import DECISION_KEY, Guarded, Obligations, RuleTask

RULES = Path(__file__).resolve().parents[2] / "src" / "cosleec" / "demo" / "assistive_care" / "rules.sleec"
REQUEST_KEY = "/request"  # the request the robot perceived, set by the scenario below


class Do(py_trees.behaviour.Behaviour):
    """A simulated robot action: says what it does and succeeds (a real one would run for a while)."""

    def __init__(self, name: str, log: list[str], rule: str | None = None) -> None:
        super().__init__(name)
        self.log, self.rule = log, rule
        if rule is not None:  # an explanation reads the decision its rule task left on the blackboard
            self.board = self.attach_blackboard_client(name=name)
            self.board.register_key(key=f"{DECISION_KEY}/{rule}", access=Access.READ)

    def update(self) -> Status:
        """Do it (log it); an explanation says the decision's reason."""
        said = f"   does {self.name}"
        if self.rule is not None:
            said += f': "{self.board.get(f"{DECISION_KEY}/{self.rule}").explanation}"'
        self.log.append(said)
        return Status.SUCCESS


def act(
    event: str, manager: Manager, log: list[str], rule: str | None = None
) -> py_trees.behaviour.Behaviour:
    """The action for ``event``, asked before and reported after (:class:`Guarded`)."""
    return Guarded(event, Do(event, log, rule), manager)


def steps(name: str, *children: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour:
    return py_trees.composites.Sequence(name, memory=True, children=list(children))


def build(manager: Manager, log: list[str]) -> py_trees.behaviour.Behaviour:
    """The mission: what is owed on the blackboard, then serve the request heard, if any."""
    curtains = RuleTask(
        "R1",
        "CurtainOpenRequest",
        manager,
        default=steps("R1 default", act("OpenCurtains", manager, log)),
        clauses=[  # R1.1 unless userUndressed; R1.2 unless userDistressed >= high
            steps("R1.1", act("Refuse", manager, log), act("ExplainWhy", manager, log, "R1")),
            steps("R1.2", act("WarnUser", manager, log), act("OpenCurtains", manager, log)),
        ],
    )
    camera = RuleTask(
        "R10",
        "CameraRequest",
        manager,
        default=steps("R10 default", act("AskConsent", manager, log)),
        clauses=[  # R10.1 unless userConsent; R10.2 unless userUndressed
            steps("R10.1", act("RecordVideo", manager, log)),
            steps("R10.2", act("Refuse", manager, log), act("ExplainWhy", manager, log, "R10")),
        ],
    )

    def heard(event: str) -> py_trees.behaviour.Behaviour:
        return py_trees.behaviours.CheckBlackboardVariableValue(
            name=f"{event}?",
            check=py_trees.common.ComparisonExpression(REQUEST_KEY, event, lambda a, b: a == b),
        )

    serve = py_trees.composites.Selector(
        "serve the request",
        memory=False,
        children=[
            steps("curtains", heard("CurtainOpenRequest"), curtains),
            steps("camera", heard("CameraRequest"), camera),
        ],
    )
    return py_trees.composites.Sequence(
        "assistive care", memory=False, children=[Obligations(manager), serve]
    )


#: (what the robot perceives, the request it hears): the scenario the script plays
SCENARIO: list[tuple[dict[str, Any], str]] = [
    ({"userUndressed": False, "userDistressed": "low", "userConsent": False}, "CurtainOpenRequest"),
    ({"userUndressed": True}, "CurtainOpenRequest"),
    ({"userDistressed": "high"}, "CurtainOpenRequest"),
    ({"userUndressed": False, "userConsent": True}, "CameraRequest"),
    (
        {"userConsent": False, "userConscious": True},
        "UserFallen",
    ),  # R6: no video for 10 min; R4: call support
    ({"userConsent": True}, "CameraRequest"),  # R10.1 asks for video; R6 (decided at the fall) forbids it
]


def play(manager: Manager) -> list[str]:
    """Play :data:`SCENARIO` through the tree; returns what happened, one line each."""
    log: list[str] = []
    root = build(manager, log)
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup()
    board = py_trees.blackboard.Client(name="scenario")
    board.register_key(key=REQUEST_KEY, access=Access.WRITE)
    for values, request in SCENARIO:
        manager.update(values)
        if request == "UserFallen":  # perceived by the Context Listener, not served by this tree
            manager.event(request)
            log.append(f"-- {request}")
            continue
        log.append(f"-- {request} with {values}")
        board.set(REQUEST_KEY, request)
        tree.tick()
        task = root.children[1].current_child.children[1]  # type: ignore[union-attr]
        log.append(f"   {task.name}: {task.status.value}, {task.feedback_message}")
        for leaf in root.iterate():  # a refusal says why
            if isinstance(leaf, Guarded) and leaf.status == Status.FAILURE:
                log.append(f"   refused: {leaf.feedback_message}")
        board.set(REQUEST_KEY, None)
        tree.tick()  # nothing heard: only the obligations are read
        log.append(f"   owed: {root.children[0].feedback_message}")
    return log


def main(argv: list[str] | None = None) -> int:
    """Play the scenario on an embedded Manager; ``--render DIR`` draws the tree there."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--render", metavar="DIR", help="write the tree as dot, png and svg (py_trees' export)"
    )
    args = parser.parse_args(argv)
    manager = Manager.from_file(RULES, clock=VirtualClock())
    manager.start(check=False)  # the tree implements the rules: no tasks are bound
    try:
        for line in play(manager):
            print(line)
        if args.render:
            Path(args.render).mkdir(parents=True, exist_ok=True)
            py_trees.display.render_dot_tree(
                build(manager, []), name="bt-curtains-camera", target_directory=args.render
            )
    finally:
        manager.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""A scripted day of the assistive-care robot that exercises every clause of rules.sleec.

Each step is ``(kind, argument, note)``: ``set`` measures, an ``event`` from the world,
``advance`` the (virtual) clock by some seconds, ``fail``/``recover`` a robot action, or
``request`` an action that may be forbidden. ``EXPECTED`` lists the clause every decision
must take, in order, so the scenario doubles as an end-to-end test.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from cosleec.demo.player import Step

STEPS: list[Step] = [
    (
        "set",
        {
            "userUndressed": False,
            "userDistressed": "low",
            "medicalEmergency": False,
            "roomDark": False,
            "userAssent": True,
            "userConscious": True,
            "userConsent": False,
            "asleep": False,
        },
        "morning: the user is dressed and calm",
    ),
    ("event", "CurtainOpenRequest", "R1 default: open the curtains"),
    ("set", {"userUndressed": True}, "the user is getting changed"),
    ("event", "CurtainOpenRequest", "R1.1: refuse and explain why"),
    ("set", {"userDistressed": "high"}, "...and becomes highly distressed"),
    ("event", "CurtainOpenRequest", "R1.2: warn, then open (the last clause that holds wins)"),
    ("set", {"userDistressed": "low"}, "calm again"),
    ("event", "DressingStarted", "R2 default: close the curtains for privacy"),
    ("set", {"roomDark": True}, "night falls"),
    ("event", "DressingStarted", "R2.2: dark room, no need to close"),
    ("set", {"roomDark": False, "medicalEmergency": True}, "an emergency"),
    ("event", "DressingStarted", "R2.1: emergency exemption"),
    ("set", {"medicalEmergency": False}, "the emergency is over"),
    ("event", "DressingAbandoned", "R3 default: ask for a retry within 2 minutes"),
    ("advance", 150, "the user never agrees: the deadline passes, otherwise calls support"),
    ("set", {"userAssent": False}, "the user withdraws assent"),
    ("event", "DressingAbandoned", "R3.1: explain instead of insisting"),
    ("event", "UserFallen", "R4 default, and R6 forbids filming (no consent)"),
    ("request", "RecordVideo", "a remote carer asks for video: refused while R6 holds"),
    ("set", {"userConscious": False}, "the user does not respond"),
    ("event", "UserFallen", "R4.1: call support within 10 seconds"),
    ("set", {"userConscious": True, "userConsent": True}, "the user recovers and consents"),
    ("event", "UserFallen", "R6.1: consent given, no prohibition this time"),
    ("advance", 30, "support arrives"),
    ("event", "MedicationDue", "R7 default: remind"),
    ("advance", 700, "no sign of the pills: R8's deadline passes, the carer is informed"),
    ("set", {"asleep": True}, "the user is asleep"),
    ("event", "MedicationDue", "R7.1: remind later"),
    ("event", "MedicationTaken", "...and the user takes the medication"),
    ("set", {"asleep": False, "medicalEmergency": True}, "emergency"),
    ("event", "MedicationDue", "R7.2: inform the carer"),
    ("set", {"medicalEmergency": False}, "back to normal"),
    ("event", "EmergencyDetected", "R9: heart rate unknown: the decision is undetermined"),
    ("set", {"heartRate": 135}, "heart-rate sensor online"),
    ("event", "EmergencyDetected", "R9 default: call support"),
    ("set", {"userConscious": False}, "the user is unresponsive"),
    ("event", "EmergencyDetected", "R9.1: call faster and inform the carer"),
    ("set", {"userConscious": True, "userConsent": False, "userUndressed": False}, "later"),
    ("event", "CameraRequest", "R10 default: ask for consent"),
    ("set", {"userConsent": True}, "consent given"),
    ("event", "CameraRequest", "R10.1: record"),
    ("set", {"userUndressed": True}, "but the user is undressed"),
    ("event", "CameraRequest", "R10.2: refuse and explain"),
    ("advance", 600, "end of the day: every window closes"),
]

# (rule, clause) of every decision the scenario produces, in order ("otherwise" follow-ups
# included as (rule, "otherwise")); None for an undetermined decision.
EXPECTED: list[tuple[str, int | str | None]] = [
    ("R1", 0),
    ("R1", 1),
    ("R1", 2),
    ("R2", 0),
    ("R2", 2),
    ("R2", 1),
    ("R3", 0),
    ("R3", "otherwise"),
    ("R3", 1),
    ("R4", 0),
    ("R6", 0),
    ("R5", 0),
    ("R4", 1),
    ("R6", 0),
    ("R5", 0),
    ("R4", 0),
    ("R6", 1),
    ("R5", 0),
    ("R7", 0),
    ("R8", 0),
    ("R8", "otherwise"),
    ("R7", 1),
    ("R8", 0),
    ("R7", 2),
    ("R9", None),
    ("R9", 0),
    ("R5", 0),
    ("R9", 1),
    ("R5", 0),
    ("R10", 0),
    ("R10", 1),
    ("R10", 2),
]


def outcomes(decisions: Iterable[Mapping[str, Any]]) -> list[tuple[str, int | str | None]]:
    """Decisions (as JSON) in the shape of ``EXPECTED``, wherever they were made."""
    return [(d["rule"], "otherwise" if d["event"] == "otherwise" else d["clause"]) for d in decisions]

"""Quality of service of a subscription, as a mapping states it, independent of the middleware.

ROS 2 matches a subscription to a publisher only when their QoS are compatible: a
RELIABLE subscription never hears a BEST_EFFORT publisher (the usual sensor driver), and
the rules would decide on an old value without a word. So every input the Context
Listener reads has a :class:`Qos`, written in the mapping::

    qos: sensor_data                  # a named profile: sensor_data | reliable | latched
    qos: {reliability: best_effort, depth: 5, durability: volatile}

The ROS 2 transport turns it into an rclpy ``QoSProfile`` and warns when a publisher
with incompatible QoS appears; ROS 1 (TCP, always reliable) uses only ``depth`` as its
queue size; the in-process bus ignores it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from cosleec.errors import UserError, closest

RELIABILITIES = ("reliable", "best_effort")
DURABILITIES = ("volatile", "transient_local")


class QosError(UserError, ValueError):
    """A QoS given in a mapping is not one cosleec understands; the message lists the choices."""


@dataclass(frozen=True)
class Qos:
    """Reliability, durability and history depth of one subscription (keep-last history).

    ``best_effort`` hears both kinds of publisher but may lose messages; ``reliable``
    loses none but hears only reliable publishers. ``transient_local`` also receives the
    last messages a latched publisher kept.
    """

    reliability: str = "reliable"
    durability: str = "volatile"
    depth: int = 10

    SENSOR_DATA: ClassVar[Qos]
    RELIABLE: ClassVar[Qos]
    LATCHED: ClassVar[Qos]
    PROFILES: ClassVar[dict[str, Qos]]

    def __post_init__(self) -> None:
        if self.reliability not in RELIABILITIES:
            raise QosError(
                f"reliability {self.reliability!r} is not one of {', '.join(RELIABILITIES)}"
                f"{_near(self.reliability, RELIABILITIES)}"
            )
        if self.durability not in DURABILITIES:
            raise QosError(
                f"durability {self.durability!r} is not one of {', '.join(DURABILITIES)}"
                f"{_near(self.durability, DURABILITIES)}"
            )
        if isinstance(self.depth, bool) or not isinstance(self.depth, int) or not 1 <= self.depth <= 100_000:
            raise QosError(f"depth must be a whole number from 1 to 100000, not {self.depth!r}")

    @classmethod
    def parse(cls, spec: Any, default: Qos | None = None) -> Qos:
        """A profile name or a ``{reliability, durability, depth}`` table -> Qos.

        Keys left out take ``default``'s values (the sensor-data profile when None).
        :class:`QosError` names what is wrong and the choices.
        """
        base = default or cls.SENSOR_DATA
        if isinstance(spec, str):
            profile = cls.PROFILES.get(spec)
            if profile is None:
                raise QosError(f"no QoS profile {spec!r}; profiles: {', '.join(cls.PROFILES)}")
            return profile
        if not isinstance(spec, dict):
            raise QosError(
                f"qos must be a profile name ({', '.join(cls.PROFILES)}) "
                "or a table {reliability, durability, depth}"
            )
        extra = sorted(set(spec) - {"reliability", "durability", "depth"})
        if extra:
            near = "".join(_near(k, ("reliability", "durability", "depth")) for k in extra)
            raise QosError(f"unknown qos key(s) {extra}{near}; allowed: reliability, durability, depth")
        return cls(
            reliability=spec.get("reliability", base.reliability),
            durability=spec.get("durability", base.durability),
            depth=spec.get("depth", base.depth),
        )

    def describe(self) -> str:
        """``best_effort/volatile/depth 5``: how logs and status show it."""
        return f"{self.reliability}/{self.durability}/depth {self.depth}"


def _near(word: object, choices: tuple[str, ...] | list[str]) -> str:
    """`` (did you mean 'reliable'?)`` when ``word`` is close to one of ``choices``, else ``""``."""
    close = closest(word, choices)
    return f" (did you mean {close!r}?)" if close else ""


# rclpy's qos_profile_sensor_data: best effort, volatile, keep last 5
Qos.SENSOR_DATA = Qos("best_effort", "volatile", 5)
Qos.RELIABLE = Qos("reliable", "volatile", 10)
Qos.LATCHED = Qos("reliable", "transient_local", 1)
Qos.PROFILES = {"sensor_data": Qos.SENSOR_DATA, "reliable": Qos.RELIABLE, "latched": Qos.LATCHED}

"""QoS on ROS 2: a :class:`~cosleec.nodes.qos.Qos` as an rclpy profile, and what DDS says of it.

A subscription and a publisher whose QoS cannot match never connect, and DDS says so only
through event callbacks: :class:`QosEvents` counts those peers (node status reports them
as ``qos_incompatible``) and warns with the fix, and counts the messages DDS reports lost.
rclpy is imported only when a profile or a callback is made.
"""

from __future__ import annotations

import logging
import threading
from typing import Any

from cosleec.nodes import Qos

log = logging.getLogger("cosleec.ros")

#: what a cosleec topic that is not latched is published and read with: no record is lost
#: while a thousand wait
TOPIC_QOS = Qos("reliable", "volatile", 1000)


def profile(qos: Qos) -> Any:
    """The rclpy ``QoSProfile`` of a :class:`~cosleec.nodes.qos.Qos` (keep-last history)."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        depth=qos.depth,
        history=HistoryPolicy.KEEP_LAST,
        reliability=ReliabilityPolicy.RELIABLE
        if qos.reliability == "reliable"
        else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL
        if qos.durability == "transient_local"
        else DurabilityPolicy.VOLATILE,
    )


def topic_profile(latched: bool) -> Any:
    """The profile of a cosleec topic: :data:`TOPIC_QOS`, or transient-local depth 1 when ``latched``."""
    return profile(Qos.LATCHED if latched else TOPIC_QOS)


class QosEvents:
    """The QoS event callbacks of one transport's subscriptions and publishers, and their counts.

    ``lost``: messages DDS reports lost on the subscriptions; ``incompatible``: peers
    whose QoS can never match ours that appeared. Thread-safe.
    """

    def __init__(self) -> None:
        self.lost = 0
        self.incompatible = 0
        self._lock = threading.Lock()

    def subscription(self, topic: str) -> Any:
        """The callbacks of a subscription to ``topic``: count what DDS lost, warn of incompatible publishers."""
        from rclpy.event_handler import SubscriptionEventCallbacks

        def lost(status: Any) -> None:
            with self._lock:
                self.lost += int(status.total_count_change)

        return SubscriptionEventCallbacks(
            message_lost=lost, incompatible_qos=lambda s: self._incompatible(topic, "publisher", s)
        )

    def publisher(self, topic: str) -> Any:
        """The callbacks of a publisher on ``topic``: warn of incompatible subscribers."""
        from rclpy.event_handler import PublisherEventCallbacks

        return PublisherEventCallbacks(incompatible_qos=lambda s: self._incompatible(topic, "subscriber", s))

    def _incompatible(self, topic: str, who: str, status: Any) -> None:
        """A peer whose QoS cannot match ours appeared: it will never be heard (or never hear us)."""
        from rclpy.qos import qos_policy_name_from_kind

        with self._lock:
            self.incompatible += int(getattr(status, "total_count_change", 1)) or 1
        policy = qos_policy_name_from_kind(status.last_policy_kind)
        log.warning(
            "%s: a %s with incompatible QoS appeared (policy %s): it is not connected; "
            "set `qos:` for this topic in the mapping (e.g. sensor_data for a best-effort driver)",
            topic,
            who,
            policy,
        )

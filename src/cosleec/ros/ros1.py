"""ROS 1 transport (rospy, TCPROS): typed ``cosleec_interfaces`` topics and services, private
parameters, ``/clock`` and ``/diagnostics``.

Imported only when a ROS 1 transport is created, so the rest of cosleec runs without
rospy. Network safety: run with ROS_HOSTNAME=localhost and a master on 127.0.0.1
(:func:`cosleec.ros.env.ros1_env` sets both); unlike the ROS 2 transport, this one does
not check. ROS 1 has no QoS (TCP is always reliable: a mapping's ``depth`` is the queue
size) and no lifecycle nodes.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import Handler, Qos
from cosleec.ros.diagnostics import Diagnostics
from cosleec.ros.guard import CallbackGuard
from cosleec.ros.interfaces import Once, record_of
from cosleec.ros.messages import message_class, to_dict
from cosleec.ros.parameters import check_overrides, coerce
from cosleec.ros.publishers import Publishers
from cosleec.ros.service import OfferedService, Rejected
from cosleec.ros.wire import Wire, is_status

log = logging.getLogger("cosleec.ros")


class Ros1Transport:
    """The :class:`~cosleec.nodes.Transport` on ROS 1: the process's one rospy node.

    One per node process (see :func:`cosleec.ros.run.transport`); it needs the master of
    ``ROS_MASTER_URI``. rospy's signal handlers are off: the node's own loop owns
    SIGINT/SIGTERM. rospy calls handlers on its own threads, so they may run concurrently.
    A handler that raises is counted in ``errors`` and logged rate-limited
    (:class:`~cosleec.ros.guard.CallbackGuard`), not left to rospy's unbounded log.
    ``wire`` and ``ros_args`` (``_name:=value`` private parameters) as on ROS 2.
    """

    def __init__(self, node_name: str, *, wire: str = "typed", ros_args: list[str] | None = None) -> None:
        import rospy
        from std_msgs.msg import String

        self._rospy = rospy
        self._wire = Wire(wire, String, self._stamp, self._seconds)
        # signals are ours: the node's main loop stops cleanly on SIGINT/SIGTERM
        args = list(ros_args or [])
        for a in args:  # name:=value remappings, _name:=value private parameters
            name, _, value = a.partition(":=")
            if not name or ":=" in value or not name.lstrip("_~/").replace("/", "_").isidentifier():
                raise UserError(
                    f"not a ROS 1 argument: {a!r}",
                    hint="give remappings as name:=value and private parameters as _name:=value",
                )
        #: the private parameters this command line gives, read as rospy reads them (YAML), and
        #: kept here: rospy would put them on the master, where they outlive the node (a crash,
        #: SIGKILL) and a later start without them would run with them, silently
        self._mine: dict[str, Any] = {}
        for a in args:
            if a.startswith("_") and not a.startswith("__"):
                name, _, value = a.partition(":=")
                self._mine[name[1:]] = _yaml_value(value)
        remaps = [a for a in args if not (a.startswith("_") and not a.startswith("__"))]
        rospy.init_node(node_name, anonymous=False, disable_signals=True, argv=["cosleec", *remaps])
        self.node_name = rospy.get_name()
        self._pubs = Publishers()
        self._subs: list[Any] = []
        self._services: list[Any] = []
        self._clients: dict[str, Any] = {}
        self._guard = CallbackGuard()
        self.diagnostics = Diagnostics(node_name, self._publish_diagnostics)
        self._diagnostics_publisher()

    @property
    def wire(self) -> str:
        """``typed`` or ``json``: how cosleec topics advertised or subscribed from now on travel."""
        return self._wire.mode

    @wire.setter
    def wire(self, mode: str) -> None:
        self._wire.mode = mode

    # ------------------------------------------------------------------ time
    def _stamp(self, t: float) -> Any:
        sec, nsec = divmod(round(t * 1e9), 1_000_000_000)
        return self._rospy.Time(sec, nsec)

    @staticmethod
    def _seconds(stamp: Any) -> float:
        return float(stamp.secs) + float(stamp.nsecs) * 1e-9

    # ------------------------------------------------------------------ health
    @property
    def errors(self) -> int:
        """Callbacks that raised (and were caught): node status reports it as ``transport_errors``."""
        return self._guard.errors

    def alive(self) -> bool:
        """False once rospy has shut down (stopped, or evicted by a node of the same name)."""
        return not self._rospy.is_shutdown()

    # ------------------------------------------------------------------ cosleec topics
    def advertise(self, topic: str, latched: bool = False) -> None:
        """Create the publisher of ``topic``, latched when ``latched``; the first call decides.

        Thread-safe.
        """

        def create(latch: bool) -> Any:
            name, cls, _ = self._wire.route(topic)
            return self._rospy.Publisher(name, cls, queue_size=1000, latch=latch, tcp_nodelay=True)

        self._pubs.advertise(topic, latched, create)

    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        """Publish a record on ``topic`` in this wire's form, advertising it (not latched) on first use.

        A ``status`` record also goes to ``/diagnostics``.
        """
        if topic not in self._pubs:
            self.advertise(topic)
        self._pubs[topic].publish(self._wire.outgoing(topic, message))
        if is_status(topic):
            self.diagnostics.report(record_of(message))

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler`` with every message on ``topic``: JSON text, or (typed wire) a function
        that decodes the record, so the receiving node rejects what cannot be read.

        Latching is the publisher's business in ROS 1: a late subscriber gets a latched
        topic's last message without asking.
        """
        name, cls, _ = self._wire.route(topic)
        deliver = self._wire.incoming(topic, handler)

        self._subs.append(
            self._rospy.Subscriber(
                name, cls, self._guard.wrap(name, deliver), queue_size=1000, tcp_nodelay=True
            )
        )

    # ------------------------------------------------------------------ the robot's topics
    def subscribe_typed(
        self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None], qos: Qos | None = None
    ) -> None:
        """Call ``handler`` with every ``type_name`` message on ``topic``, as nested dicts.

        ROS 1 is always reliable: only ``qos.depth`` is used, as the queue size.
        """
        cls = message_class(type_name)
        self._subs.append(
            self._rospy.Subscriber(
                topic,
                cls,
                self._guard.wrap(topic, lambda m: handler(to_dict(m))),
                queue_size=qos.depth if qos is not None else 1000,
            )
        )

    def subscribe_raw(
        self, topic: str, type_name: str, handler: Callable[[Any], None], qos: Qos | None = None
    ) -> None:
        """Call ``handler`` with every ``type_name`` message on ``topic``, as the message object (the guard)."""
        cls = message_class(type_name)
        self._subs.append(
            self._rospy.Subscriber(
                topic, cls, self._guard.wrap(topic, handler), queue_size=qos.depth if qos is not None else 100
            )
        )

    def advertise_raw(self, topic: str, type_name: str, qos: Qos | None = None) -> Any:
        """Create the publisher :meth:`publish_raw` sends on (at start: ROS 1 delivers nothing to a
        subscriber before its connection is made)."""
        return self._pubs.make(
            f"{topic}#{type_name}#raw",
            lambda: self._rospy.Publisher(topic, message_class(type_name), queue_size=100),
        )

    def publish_raw(self, topic: str, type_name: str, data: Any, qos: Qos | None = None) -> None:
        """Publish a message object as it came from :meth:`subscribe_raw`."""
        pub = self._pubs.get(f"{topic}#{type_name}#raw") or self.advertise_raw(topic, type_name, qos)
        pub.publish(data)

    def publish_typed(
        self, topic: str, type_name: str, fields: dict[str, Any], qos: Qos | None = None
    ) -> None:
        """Publish a typed message (simulators, tests): ``std_msgs/Bool``, ``{"data": True}``."""
        pub = self._pubs.make(
            f"{topic}#{type_name}",
            lambda: self._rospy.Publisher(topic, message_class(type_name), queue_size=100),
        )
        pub.publish(message_class(type_name)(**fields))

    def typed_subscribers(self, topic: str, type_name: str) -> int:
        """Connections of this transport's typed publisher on ``topic`` (0 before :meth:`publish_typed`)."""
        pub = self._pubs.get(f"{topic}#{type_name}")
        return pub.get_num_connections() if pub is not None else 0

    def subscribers(self, topic: str) -> int:
        """Subscribers connected to this transport's publisher on ``topic`` (0 if it has none).

        ROS 1 delivers nothing to a subscriber before its connection is made: wait for it.
        """
        pub = self._pubs.get(topic)
        return pub.get_num_connections() if pub is not None else 0

    # ------------------------------------------------------------------ services
    def _resolve(self, name: str) -> str:
        return f"{self.node_name}/{name[2:]}" if name.startswith("~/") else name

    def serve(
        self,
        name: str,
        kind: str,
        handler: Callable[[dict[str, Any]], dict[str, Any]],
        rejected: Rejected | None = None,
    ) -> None:
        """Offer service ``name`` (``~/request`` is under this node's name) of ``kind``; as on ROS 2
        (:class:`~cosleec.ros.service.OfferedService`).

        ROS 1 tells who called: the caller's node name (its ``callerid``, which the caller
        states itself -- nothing on ROS 1 checks it) joins the request as ``_caller``, and
        is given to ``rejected(name, error, caller)`` with a request that cannot be decoded.
        """
        services = self._wire.services()
        cls = services.service_type(kind)
        service = OfferedService(name, kind, services, handler, rejected, self._guard)

        def call(req: Any) -> Any:
            header = getattr(req, "_connection_header", None)
            caller = header.get("callerid") if isinstance(header, dict) else None
            return service.answer(req, cls._response_class, caller if isinstance(caller, str) else None)

        self._services.append(self._rospy.Service(self._resolve(name), cls, call))

    def ask(
        self,
        name: str,
        kind: str,
        fields: dict[str, Any],
        answer: Callable[[dict[str, Any] | None], None],
        timeout: float,
    ) -> None:
        """Call service ``name`` on a worker thread; ``answer`` gets the reply, or None, exactly once."""
        services = self._wire.services()
        once = Once(answer)
        timer = threading.Timer(timeout, lambda: once(None))
        timer.daemon = True
        timer.start()

        def work() -> None:
            reply = None
            try:
                proxy = self.prepare(name, kind)
                reply = services.read_response(kind, proxy(services.make_request(kind, fields)))
            except Exception:  # no service, a failed call, a reply that cannot be read: no answer
                reply = None
            finally:
                timer.cancel()
            once(reply)  # outside the try: an error in the caller's callback is the caller's

        threading.Thread(target=work, name="cosleec-ask", daemon=True).start()

    def prepare(self, name: str, kind: str) -> Any:
        """The proxy of service ``name`` (of ``kind``), made now if it is not yet (a node calls
        it when it starts, as on ROS 2; rospy connects a proxy at each call)."""
        proxy = self._clients.get(name)
        if proxy is None:
            proxy = self._clients[name] = self._rospy.ServiceProxy(
                self._resolve(name), self._wire.services().service_type(kind), persistent=False
            )
        return proxy

    def parameters(self, defaults: dict[str, Any]) -> dict[str, Any]:
        """The node's private parameters (``_semantics:=nested``, ``rosparam set /node/semantics``).

        An option not given keeps ``defaults``' value; ParameterError for a wrong type or a
        private parameter no option has.
        """
        known = set(defaults) | {"use_sim_time"}
        check_overrides(self._mine, known)  # a typo on this command line is an error
        out = {}
        for name, default in defaults.items():
            if name in self._mine:  # this command line's: wins over the parameter server
                value = self._mine[name]
            else:  # set by rosparam or a launch file
                value = self._rospy.get_param(f"~{name}", default if default is not None else "")
            out[name] = coerce(name, value, default)
        prefix = f"{self.node_name}/"
        for p in self._rospy.get_param_names():  # set by rosparam or a launch file: said, not fatal
            rest = p[len(prefix) :] if p.startswith(prefix) else None
            if rest is not None and "/" not in rest and rest not in known:
                log.warning("the parameter server has %s, which no option of this node reads", p)
        return out

    def use_sim_time(self) -> bool:
        """This node's ``_use_sim_time:=`` or ``~use_sim_time``, else ROS 1's global ``/use_sim_time``."""
        if "use_sim_time" in self._mine:
            return self._mine["use_sim_time"] is True
        return bool(self._rospy.get_param("~use_sim_time", self._rospy.get_param("/use_sim_time", False)))

    # ------------------------------------------------------------------ diagnostics
    def _diagnostics_publisher(self) -> Any:
        """The ``/diagnostics`` publisher, made when the node starts.

        Made then, not at the first report: a publisher made just before it publishes has
        no subscriber connected yet, and the report (a WARN sent once, at the change of
        level) would be lost to every monitor.
        """
        from diagnostic_msgs.msg import DiagnosticArray

        return self._pubs.make(
            "/diagnostics#", lambda: self._rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=10)
        )

    def _publish_diagnostics(self, fields: dict[str, Any]) -> None:
        self._diagnostics_publisher().publish(self._wire.diagnostics(fields))

    # ------------------------------------------------------------------ end
    def ok(self) -> bool:
        """False once rospy has shut down: :func:`cosleec.ros.serve` then stops the node."""
        return self.alive()

    def close(self) -> None:
        """Unregister every subscriber, publisher and service, then shut rospy down for this process."""
        for s in self._subs:
            s.unregister()
        for p in self._pubs.all():
            p.unregister()
        for v in self._services:
            v.shutdown()
        self._rospy.signal_shutdown("cosleec node stopped")


def _yaml_value(text: str) -> Any:
    """A ``_name:=value`` value as rospy reads it: YAML (``true``, ``2``, ``[a, b]``), else the text."""
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text

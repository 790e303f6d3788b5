"""ROS 2 transport (rclpy, Fast DDS): typed ``cosleec_interfaces`` topics and services,
parameters, ``/clock``, ``/diagnostics`` and, for the Manager, a lifecycle node.

Imported only when a ROS 2 transport is created, so the rest of cosleec runs without
rclpy. Network safety is checked here, fail closed: the transport refuses to start unless
DDS discovery is confined to this machine (:func:`check_network`).

An exception raised into the executor would end ``spin()`` and leave the node deaf, so
every callback is guarded (:class:`~cosleec.ros.guard.CallbackGuard`), and if the spin
thread ends anyway the transport says so: :meth:`Ros2Transport.alive` and
:meth:`Ros2Transport.ok` turn False and :func:`cosleec.ros.serve` stops the node.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import Handler, Qos
from cosleec.ros.diagnostics import Diagnostics
from cosleec.ros.guard import CallbackGuard
from cosleec.ros.interfaces import Once, ServiceCodec, record_of
from cosleec.ros.lifecycle import lifecycle_node
from cosleec.ros.messages import message_class, to_dict
from cosleec.ros.parameters import ParameterError, check_overrides, coerce
from cosleec.ros.publishers import Publishers
from cosleec.ros.ros2_qos import QosEvents, profile, topic_profile
from cosleec.ros.service import OfferedService, Rejected
from cosleec.ros.wire import Wire, is_status

log = logging.getLogger("cosleec.ros")


class UnsafeNetworkError(UserError):
    """ROS 2 discovery could leave this machine: cosleec refuses to start (fail closed)."""


def check_network() -> None:
    """Refuse to start DDS where discovery could leave loopback (fail closed).

    Passes when ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (as
    :func:`cosleec.ros.env.ros2_env` sets it) or ``COSLEEC_ALLOW_NETWORK`` is set, for a
    deployment on a real robot network; raises :class:`UnsafeNetworkError` otherwise.
    """
    if os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE") != "LOCALHOST" and not os.environ.get(
        "COSLEEC_ALLOW_NETWORK"
    ):
        raise UnsafeNetworkError(
            "refusing to start ROS 2 without ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST",
            hint="set COSLEEC_ALLOW_NETWORK=1 to deploy on a real robot network",
        )


class Ros2Transport:
    """The :class:`~cosleec.nodes.Transport` on ROS 2: one rclpy node, spun on its own thread.

    One per node process (see :func:`cosleec.ros.run.transport`). It checks the network
    first (:class:`UnsafeNetworkError`), and initialises rclpy if needed without rclpy's
    signal handlers: the node's own loop owns SIGINT/SIGTERM. A single-threaded executor
    runs every handler of this transport, one at a time, on the spin thread; a handler
    that raises is counted in ``errors`` and the executor goes on. ``spin_error`` holds
    what ended the spin thread, if something did.

    ``wire`` is ``"typed"`` (``cosleec_interfaces`` messages, the default) or ``"json"``
    (JSON text in ``std_msgs/String``, for tools without the types). ``ros_args`` are the
    node's ``--ros-args`` (``-p name:=value``, ``--params-file``, remappings).
    ``lifecycle`` makes it a managed (lifecycle) node: see :meth:`managed`.
    """

    def __init__(
        self,
        node_name: str,
        *,
        wire: str = "typed",
        ros_args: list[str] | None = None,
        lifecycle: bool = False,
    ) -> None:
        check_network()
        import rclpy
        from std_msgs.msg import String

        self._rclpy = rclpy
        self._wire = Wire(wire, String, _stamp, _seconds)
        self._hooks: dict[str, Callable[[], bool]] = {}
        self.node = _start_node(node_name, ros_args, self._hooks if lifecycle else None)
        self.lifecycle = lifecycle
        self._pubs = Publishers()
        self._subs: list[Any] = []
        self._services: list[Any] = []
        self._clients: dict[str, Any] = {}
        self._guard = CallbackGuard()
        self._events = QosEvents()
        self.diagnostics = Diagnostics(node_name, self._publish_diagnostics)
        self._diagnostics_publisher()
        self._spin = _Spin(self.node, node_name)
        self.executor = self._spin.executor

    @property
    def wire(self) -> str:
        """``typed`` or ``json``: how cosleec topics advertised or subscribed from now on travel."""
        return self._wire.mode

    @wire.setter
    def wire(self, mode: str) -> None:
        self._wire.mode = mode

    # ------------------------------------------------------------------ health
    @property
    def spin_error(self) -> BaseException | None:
        """What ended the spin thread, if something did (None while it runs, and when :meth:`close` ended it)."""
        return self._spin.error

    @property
    def lost(self) -> int:
        """Messages DDS reports lost on this transport's subscriptions (the middleware's own count)."""
        return self._events.lost

    @property
    def incompatible(self) -> int:
        """QoS-incompatible publishers or subscribers that appeared (node status: ``qos_incompatible``)."""
        return self._events.incompatible

    @property
    def errors(self) -> int:
        """Callbacks that raised (and were caught): node status reports it as ``transport_errors``."""
        return self._guard.errors

    def alive(self) -> bool:
        """Is the spin thread still delivering messages? False once it has ended, for whatever reason.

        Node status reports it as ``executor_alive``.
        """
        return self._spin.alive()

    #: the rclpy ``QoSProfile`` of a :class:`~cosleec.nodes.qos.Qos` (:func:`cosleec.ros.ros2_qos.profile`)
    profile = staticmethod(profile)

    # ------------------------------------------------------------------ cosleec topics
    def advertise(self, topic: str, latched: bool = False) -> None:
        """Create the publisher of ``topic``, reliable; transient-local with depth 1 when ``latched``.

        The first call for a topic fixes its QoS. Thread-safe.
        """

        def create(latch: bool) -> Any:
            name, cls, _ = self._wire.route(topic)
            return self.node.create_publisher(
                cls, name, topic_profile(latch), event_callbacks=self._events.publisher(name)
            )

        self._pubs.advertise(topic, latched, create)

    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        """Publish a record on ``topic`` in this wire's form, advertising it (not latched) on first use.

        JSON text is accepted too (parsed first on the typed wire; ValueError if it is not a
        JSON object there). A ``status`` record also goes to ``/diagnostics``.
        """
        if topic not in self._pubs:
            self.advertise(topic)
        self._pubs[topic].publish(self._wire.outgoing(topic, message))
        if is_status(topic):
            self.diagnostics.report(record_of(message))

    def subscribe(self, topic: str, handler: Handler, latched: bool | None = None) -> None:
        """Call ``handler`` with every message on ``topic``: JSON text, or (typed wire) a function
        that decodes the record, so the receiving node rejects what cannot be read.

        ``latched`` asks for transient-local QoS, to receive a latched publisher's last
        message; None decides by the name (a topic ending in ``layers``).
        """
        is_latched = topic.rsplit("/", 1)[-1] == "layers" if latched is None else latched
        name, cls, _ = self._wire.route(topic)
        deliver = self._wire.incoming(topic, handler)

        sub = self.node.create_subscription(
            cls,
            name,
            self._guard.wrap(name, deliver),
            topic_profile(is_latched),
            event_callbacks=self._events.subscription(name),
        )
        self._subs.append(sub)

    # ------------------------------------------------------------------ the robot's topics
    def subscribe_typed(
        self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None], qos: Qos | None = None
    ) -> None:
        """Call ``handler`` with every ``type_name`` message on ``topic``, as nested dicts.

        ``qos`` as the mapping says (reliable, depth 1000 when None). MessageTypeError for a
        type that cannot be loaded; a warning when an incompatible publisher appears.
        """
        cls = message_class(type_name)
        sub = self.node.create_subscription(
            cls,
            topic,
            self._guard.wrap(topic, lambda m: handler(to_dict(m))),
            _profile(qos),
            event_callbacks=self._events.subscription(topic),
        )
        self._subs.append(sub)

    def subscribe_raw(
        self, topic: str, type_name: str, handler: Callable[[Any], None], qos: Qos | None = None
    ) -> None:
        """Call ``handler`` with every ``type_name`` message on ``topic``, serialized, undecoded (the guard)."""
        cls = message_class(type_name)
        sub = self.node.create_subscription(
            cls,
            topic,
            self._guard.wrap(topic, handler),
            _profile(qos),
            event_callbacks=self._events.subscription(topic),
            raw=True,
        )
        self._subs.append(sub)

    def advertise_raw(self, topic: str, type_name: str, qos: Qos | None = None) -> Any:
        """Create the publisher :meth:`publish_raw` sends on (at start, so that subscribers have
        matched it before the first message goes out); the first call for a topic decides."""
        return self._pubs.make(
            f"{topic}#{type_name}#raw",
            lambda: self.node.create_publisher(
                message_class(type_name), topic, _profile(qos), event_callbacks=self._events.publisher(topic)
            ),
        )

    def publish_raw(self, topic: str, type_name: str, data: Any, qos: Qos | None = None) -> None:
        """Publish a serialized ``type_name`` message as it came from :meth:`subscribe_raw`."""
        pub = self._pubs.get(f"{topic}#{type_name}#raw") or self.advertise_raw(topic, type_name, qos)
        pub.publish(data)

    def publish_typed(
        self, topic: str, type_name: str, fields: dict[str, Any], qos: Qos | None = None
    ) -> None:
        """Publish a typed message (simulators, tests): ``std_msgs/Bool``, ``{"data": True}``."""
        pub = self._pubs.make(
            f"{topic}#{type_name}",
            lambda: self.node.create_publisher(message_class(type_name), topic, _profile(qos)),
        )
        pub.publish(message_class(type_name)(**fields))

    def typed_subscribers(self, topic: str, type_name: str) -> int:
        """Subscribers of this transport's typed publisher on ``topic`` (0 before :meth:`publish_typed`)."""
        pub = self._pubs.get(f"{topic}#{type_name}") or self._pubs.get(f"{topic}#{type_name}#raw")
        return pub.get_subscription_count() if pub is not None else 0

    def subscribers(self, topic: str) -> int:
        """Subscribers matched to this transport's publisher on ``topic`` (0 if it has none).

        Node status reports these, so a harness can tell the graph is connected.
        """
        pub = self._pubs.get(topic)
        return pub.get_subscription_count() if pub is not None else 0

    # ------------------------------------------------------------------ services
    def serve(
        self,
        name: str,
        kind: str,
        handler: Callable[[dict[str, Any]], dict[str, Any]],
        rejected: Rejected | None = None,
    ) -> None:
        """Offer service ``name`` (``~/request``) of ``kind`` (request, decide, reload).

        ``handler`` takes the request as a dict and returns the answer as a dict. An
        exception in it answers with the service's failure form (not permitted, not
        accepted, not reloaded) and is counted: a caller is never left without an answer.
        A request that cannot be decoded (a value of an unknown kind, a measure given
        twice) is answered so too, and told to ``rejected(name, error, caller)``. rclpy does
        not tell a service callback who called (the request's writer is taken inside its
        executor), so the caller is None here and no ``_caller`` joins the request.
        """
        services = self._wire.services()
        cls = services.service_type(kind)
        service = OfferedService(name, kind, services, handler, rejected, self._guard)

        def call(req: Any, resp: Any) -> Any:
            return service.answer(req, lambda: resp)

        self._services.append(self.node.create_service(cls, name, call))

    def ask(
        self,
        name: str,
        kind: str,
        fields: dict[str, Any],
        answer: Callable[[dict[str, Any] | None], None],
        timeout: float,
    ) -> None:
        """Call service ``name`` without blocking; ``answer`` gets the reply, or None -- exactly once.

        None when the service is not there, fails, or does not answer within ``timeout``
        seconds: the caller decides what that means (the guard blocks).
        """
        _call(self.prepare(name, kind), self._wire.services(), kind, fields, Once(answer), timeout)

    def prepare(self, name: str, kind: str) -> Any:
        """The client of service ``name`` (of ``kind``), made now if it is not yet: call it when
        a node starts, so the client has found the service before the first :meth:`ask`
        (a client made at the first ask finds none yet, and that ask gets no answer)."""
        client = self._clients.get(name)
        if client is None:
            client = self._clients[name] = self.node.create_client(
                self._wire.services().service_type(kind), name
            )
        return client

    # ------------------------------------------------------------------ parameters
    def parameters(self, defaults: dict[str, Any]) -> dict[str, Any]:
        """Declare one ROS parameter per option, with its default; return their values.

        Values come from ``--ros-args -p name:=value`` or ``--params-file``; an option not
        given keeps ``defaults``' value. :class:`ParameterError` for a value of the wrong
        type or a parameter no option has (with did-you-mean).
        """
        out = {name: _declare(self.node, name, default) for name, default in defaults.items()}
        given = set(getattr(self.node, "_parameter_overrides", {}))  # what -p / --params-file set
        check_overrides(given, set(defaults) | {"use_sim_time", "qos_overrides"})
        return out

    def use_sim_time(self) -> bool:
        """The standard ``use_sim_time`` parameter (rclpy declares it on every node)."""
        return bool(self.node.get_parameter("use_sim_time").value)

    # ------------------------------------------------------------------ lifecycle
    def managed(self, **hooks: Callable[[], bool]) -> None:
        """Set the lifecycle hooks (``configure``, ``activate``, ``deactivate``, ``cleanup``,
        ``shutdown``): each returns True for success; an exception counts as failure."""
        self._hooks.update(hooks)

    def transition(self, name: str) -> bool:
        """Drive this lifecycle node through transition ``name`` itself (autostart); True if it succeeded."""
        from rclpy.lifecycle import TransitionCallbackReturn

        result = getattr(self.node, f"trigger_{name}")()
        return bool(result == TransitionCallbackReturn.SUCCESS)

    # ------------------------------------------------------------------ diagnostics
    def _diagnostics_publisher(self) -> Any:
        """The ``/diagnostics`` publisher, made when the node starts.

        Made then, not at the first report: a publisher made just before it publishes has
        no subscriber connected yet, and the report (a WARN sent once, at the change of
        level) would be lost to every monitor.
        """
        from diagnostic_msgs.msg import DiagnosticArray

        return self._pubs.make(
            "/diagnostics#", lambda: self.node.create_publisher(DiagnosticArray, "/diagnostics", 10)
        )

    def _publish_diagnostics(self, fields: dict[str, Any]) -> None:
        self._diagnostics_publisher().publish(self._wire.diagnostics(fields))

    # ------------------------------------------------------------------ end
    def ok(self) -> bool:
        """False once rclpy has shut down or the spin thread has ended: :func:`cosleec.ros.serve` then stops the node."""
        return bool(self._rclpy.ok()) and self.alive()

    def close(self) -> None:
        """Shut down in the order that avoids aborts at exit: executor, spin thread, node, rclpy.

        Errors along the way (a context already invalid) are ignored.
        """
        self._spin.stop()
        with contextlib.suppress(Exception):
            self.node.destroy_node()
        if self._rclpy.ok():
            with contextlib.suppress(Exception):
                self._rclpy.shutdown()


def _stamp(t: float) -> Any:
    """The ROS 2 time (``builtin_interfaces/Time``) of ``t`` seconds."""
    from builtin_interfaces.msg import Time

    sec, nanosec = divmod(round(t * 1e9), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def _seconds(stamp: Any) -> float:
    """The seconds of a ROS 2 time."""
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def _start_node(
    node_name: str, ros_args: list[str] | None, hooks: dict[str, Callable[[], bool]] | None
) -> Any:
    """The rclpy node of a transport, a lifecycle node calling ``hooks`` when they are given.

    rclpy is initialised first if it is not yet, without its signal handlers. ``ros_args``
    that rcl refuses are the user's to fix: a UserError.
    """
    import rclpy

    if not rclpy.ok():
        from rclpy.signals import SignalHandlerOptions

        # the node's own loop owns SIGINT/SIGTERM: a signal during start-up must not
        # invalidate the context under our feet
        # args=[]: the node takes its ROS arguments itself (cli_args); rclpy must not
        # parse this process's command line, which is cosleec's
        rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
    args = ["--ros-args", *ros_args] if ros_args and ros_args[0] != "--ros-args" else (ros_args or [])
    try:
        if hooks is not None:
            return lifecycle_node(node_name, args, hooks)
        return rclpy.create_node(node_name, cli_args=args or None)
    except Exception as e:  # rcl refuses malformed or unknown --ros-args: the user's to fix
        if not type(e).__module__.startswith("rclpy"):
            raise
        raise UserError(
            f"ROS 2 cannot use these ROS arguments {args}: {type(e).__name__}: {e}",
            hint="ROS arguments come last: `... --ros-args -p name:=value [--params-file FILE]`",
        ) from None


class _Spin:
    """The single-threaded executor that runs every callback of one node, one at a time, on a
    thread of its own. ``error`` holds what ended that thread, if something did before :meth:`stop`."""

    def __init__(self, node: Any, node_name: str) -> None:
        from rclpy.executors import SingleThreadedExecutor

        self.executor = SingleThreadedExecutor()
        self.executor.add_node(node)
        self.error: BaseException | None = None
        self._closing = False
        self._thread = threading.Thread(target=self._run, name=f"{node_name}-spin", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self.executor.spin()
        except Exception as e:
            if not self._closing:  # not a shutdown race: the node has gone deaf, say why
                self.error = e
                log.error("the ROS 2 executor stopped: %s: %s", type(e).__name__, e, exc_info=e)
        if not self._closing and self.error is None:
            log.error("the ROS 2 executor stopped (rclpy shut down?)")

    def alive(self) -> bool:
        """Is the thread still delivering messages?"""
        return self._thread.is_alive()

    def stop(self) -> None:
        """Shut the executor down and wait (up to 5 s) for its thread; errors along the way are ignored."""
        self._closing = True
        with contextlib.suppress(Exception):
            self.executor.shutdown()
        self._thread.join(5)


def _call(
    client: Any, services: ServiceCodec, kind: str, fields: dict[str, Any], once: Once, timeout: float
) -> None:
    """Call the service of ``client`` without blocking; ``once`` gets the reply, or None.

    None at once when the service is not there; None when the call fails, the reply cannot
    be read, or none comes within ``timeout`` seconds (the request is then cancelled).
    """
    if not client.service_is_ready():
        once(None)
        return
    future = client.call_async(services.make_request(kind, fields))

    def expired() -> None:
        future.cancel()  # rclpy then forgets the request (and what it holds)
        once(None)

    timer = threading.Timer(timeout, expired)
    timer.daemon = True
    timer.start()

    def done(f: Any) -> None:
        timer.cancel()
        try:
            reply = None if f.cancelled() else services.read_response(kind, f.result())
        except Exception:  # a reply that cannot be read is no answer
            reply = None
        once(reply)  # outside the try: an error in the caller's callback is the caller's

    future.add_done_callback(done)


def _declare(node: Any, name: str, default: Any) -> Any:
    """Declare the parameter ``name`` of ``node`` and return its value (``default`` if not given).

    Dynamically typed: ``-p timeout:=2`` is as good as 2.0; :func:`coerce` checks the type,
    with a message that names the parameter, and its option's checks follow.
    """
    from rcl_interfaces.msg import ParameterDescriptor

    try:
        value = node.declare_parameter(name, None, ParameterDescriptor(dynamic_typing=True)).value
    except Exception as e:  # a value rclpy cannot hold
        raise ParameterError(
            f"parameter {name!r}: {e}",
            hint=f"give it as {_type_name(default)} (the option's default is {default!r})",
        ) from None
    return default if value is None else coerce(name, value, default)


def _profile(qos: Qos | None) -> Any:
    """The profile a robot's topic is read or written with: ``qos`` as the mapping says, else
    a cosleec topic's (reliable, depth 1000)."""
    return profile(qos) if qos is not None else topic_profile(False)


def _type_name(default: Any) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", list: "a list of strings"}.get(
        type(default), "a string"
    )

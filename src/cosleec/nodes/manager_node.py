"""The Manager node: rules, context, layers, decisions and obligations for a whole robot.

It consumes ``context``, ``events``, ``request`` (and ``clock`` in simulated time) and
publishes ``decisions``, ``obligations`` (for the task nodes), ``violations``,
``conflicts``, ``refusals``, ``request_reply`` and ``status``. Each decision carries the
layer chosen under the context as of that trigger, so task nodes dispatch exactly that
variant: no stale dispatch across processes, whatever the timing of the layer topic.

Where the transport offers services it also answers ``~/request`` (may E happen now, and
why not), ``~/decide`` (apply values, let an event occur, return the decisions) and
``~/reload`` (new rules without a restart, :meth:`ManagerNode.reload`).

**Privileged services stay privileged.** Anyone on the robot's ROS domain can call a
service, so the two that change what the Manager enforces take only what the operator
allowed when starting the node. ``~/reload`` re-reads the rule file the node runs and,
with ``reload_dir``, reads files under that directory (symlinks and ``..`` resolved before
the check); any other path is refused with a fixed message, without touching the file,
so the answer says nothing of what exists or what it holds. Every attempt is recorded in
the audit log (a ``reload-attempt`` record: caller where the middleware says who it is,
path, outcome, both rule hashes). ``~/decide`` is ``off`` unless the operator chooses
``events-only`` (an event, no values) or ``all``; a refused call is recorded as
``rejected``. So is every message the node cannot decode: the runtime never sees it, so
the node records it (:meth:`cosleec.runtime.Manager.note`).

**Active and inactive.** A Manager node enforces only while active (the default). While
inactive -- a lifecycle node before ``activate`` or after ``deactivate`` -- it refuses
every request (fail closed: "the Manager is inactive") and rejects every event and
Decide call, counted and reported on ``rejected``; it keeps taking context updates and
the clock, so that its view of the world is current when it is activated again.
"""

from __future__ import annotations

import difflib
import logging
import math
import os
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

from cosleec.errors import ConfigurationError, CosleecError, UserError, clip, show
from cosleec.nodes.base import REASON_LIMIT, MessageError, Node, context_values, excerpt
from cosleec.nodes.recording import McapRecorder
from cosleec.nodes.transport import DEFAULT_NAMESPACE, Transport
from cosleec.runtime import (
    Clock,
    ContextError,
    HedgeSemantics,
    Manager,
    MonotonicClock,
    Permission,
    RuleSet,
    RuntimeEvent,
    VirtualClock,
)

#: how long the subscribers of ``obligations`` must stay the same before a restarted Manager
#: node publishes again what it decided but perhaps never published (discovery settles)
REPUBLISH_SETTLE_S = 1.0
#: how long they must then stay the same before what it published again counts as heard (it
#: leaves the journal's outbox); until then a subscriber matched later gets it again: DDS
#: matches each subscriber on its own, and a task node's may come seconds after a driver's
REPUBLISH_WINDOW_S = 10.0

#: the longest event name (or request id) the Manager node takes; SLEEC names are identifiers
MAX_NAME = 256

#: what ``~/decide`` takes: nothing, an event without values, or values and an event
DECIDE = ("off", "events-only", "all")
#: ``~/decide`` is off unless the operator turns it on: enforcement needs it not (the
#: context comes from the Context Listener), and a service that changes the context is
#: one more way in for anyone on the domain (docs/ros.md, "Threat model")
DEFAULT_DECIDE = "off"
#: the longest path a ``reload-attempt`` record keeps (a caller chooses what it sends)
MAX_PATH_SHOWN = 300


class ManagerNode(Node):
    """The Manager as a node: one per robot, the only node that decides.

    It decides only; task nodes run the implementations. ``sim_time`` takes time from the
    ``clock`` topic and judges deadlines on each clock message (no timer thread);
    otherwise the monotonic clock and a timer thread do. ``audit`` and ``record`` name a
    JSON Lines audit trail and an MCAP recording; ``manager_kw`` goes to :class:`Manager`
    (``journal=PATH`` keeps the state across a crash; in simulated time the clock then goes
    on from the journal's last time). ``load`` reads a rule file for :meth:`reload` (the
    CLI gives ``RuleSet.from_file`` and the file it started with as ``rules_path``);
    ``reload_dir`` is a directory whose files :meth:`reload` may read besides that one
    (None: no other file); ``decide`` is what ``~/decide`` takes (:data:`DECIDE`, off by
    default); ``active=False`` starts it inactive (a lifecycle node before ``activate``).
    ``on_manager(manager)`` is called with each Manager the node builds, just before it
    starts (a live view attached there hears start's records: the CLI's ``--web``, since
    ``nodes`` names no view); what it returns, if anything, is called before that Manager
    closes, or at once if its start fails.
    """

    name = "manager"

    def __init__(
        self,
        transport: Transport,
        rules: RuleSet,
        *,
        namespace: str = DEFAULT_NAMESPACE,
        semantics: HedgeSemantics | None = None,
        sim_time: bool = False,
        audit: str | None = None,
        record: str | None = None,
        record_format: str | None = None,
        status_each: bool = False,
        rules_path: str | None = None,
        load: Callable[[str], RuleSet] | None = None,
        active: bool = True,
        reload_dir: str | None = None,
        decide: str = DEFAULT_DECIDE,
        on_manager: Callable[[Manager], Callable[[], None] | None] | None = None,
        **manager_kw: Any,
    ) -> None:
        if decide not in DECIDE:
            raise ConfigurationError(f"decide must be one of {', '.join(DECIDE)}, not {show(decide)}")
        self.decide = decide
        self.reload_dir = _directory(reload_dir) if reload_dir is not None else None
        super().__init__(transport, namespace)
        self.rules_path = rules_path
        self._load = load or RuleSet.from_file
        self.active = active
        self._republish: list[dict[str, Any]] = []  # decisions held until the task nodes can hear them
        self._matched: tuple[int, float] | None = None  # obligations' subscriber count, and since when
        # published again, perhaps not yet heard by every task node (REPUBLISH_WINDOW_S), and
        # how many subscribers had been matched when they were last sent
        self._unconfirmed: list[dict[str, Any]] = []
        self._sent_to = 0
        # while starting (and, if decisions are held then, until the task nodes' subscriptions
        # have settled), decisions are held rather than published to no one
        self._settled = False
        self._hand_lock = threading.Lock()
        # status after every message lets a harness know when the system is quiet; in
        # deployment the heartbeat (every 0.5 s) is enough and keeps the hot path short
        self.status_each = status_each
        self.sim_time, self._on_manager = sim_time, on_manager
        self._options = {"semantics": semantics, "audit": audit, "dispatch": False, **manager_kw}
        self.recorder = McapRecorder(record, fmt=record_format) if record else None
        for t in ("decisions", "obligations", "violations", "conflicts", "refusals", "request_reply"):
            self.advertise(t)
        self._start(rules)
        self.on("context", self._context)
        self.on("events", self._event)
        self.on("request", self._request)
        if sim_time:
            self.on("clock", self._clock)
        serve = getattr(transport, "serve", None)
        if serve is not None:  # the typed interface: ask, decide and reload as services
            for name, kind, handler in (
                ("~/request", "request", self._serve_request),
                ("~/decide", "decide", self._serve_decide),
                ("~/reload", "reload", self._serve_reload),
            ):
                serve(name, kind, handler, rejected=self._service_rejected)
        self.status()

    def _start(self, rules: RuleSet) -> None:
        """Build and start the Manager for ``rules`` (at construction, and after :meth:`reset`)."""
        self.clock: Clock = VirtualClock() if self.sim_time else MonotonicClock()
        self.manager = Manager(rules, clock=self.clock, **self._options)
        # with a journal, decision ids go on across restarts: so does the session task nodes
        # de-duplicate by, and a decision published again after a restart is not run twice
        self.session = self.manager.lineage
        self.manager.subscribe(self._runtime_event)
        # decided before a crash, perhaps never published: published again once a task node listens
        self._republish = [{**d, "_again": True} for d in self.manager.undelivered]
        self.manager.undelivered.clear()
        self._unconfirmed, self._matched = [], None
        self._release_attached = self._on_manager(self.manager) if self._on_manager is not None else None
        try:
            self.manager.start(check=False, timer=not self.sim_time)  # may decide fallbacks: held, as above
        except BaseException:
            self._release()  # a start that failed serves no view
            raise
        with self._hand_lock:
            # nothing held (a first start, a clean stop): publish as decided from now on; else
            # what is decided later waits behind the held decisions, in order
            self._settled = not self._republish

    # ------------------------------------------------------------------ lifecycle
    def reset(self, rules: RuleSet) -> None:
        """Forget everything and start again with ``rules``, inactive (a lifecycle cleanup, then
        configure): the Manager is closed (its audit log ends) and a new one takes over. With a
        journal the new one restores what the journal holds -- obligations outlive a cleanup."""
        self.active = False
        self._release()
        self.manager.close()
        self._start(rules)
        self.status()

    def _release(self) -> None:
        """Call, once, what ``on_manager`` returned for the Manager now running: before it closes."""
        release, self._release_attached = self._release_attached, None
        if release is not None:
            release()

    def activate(self) -> None:
        """Start enforcing: triggers are decided and requests answered from now on."""
        self.active = True
        self.status()

    def deactivate(self) -> None:
        """Stop enforcing: every request is refused and every event rejected until :meth:`activate`."""
        self.active = False
        self.status()

    def _inactive(self) -> str:
        return "the Manager is inactive (lifecycle): it refuses every request until it is activated"

    def reload(
        self, path: str | None = None, *, via: str = "call", caller: str | None = None
    ) -> dict[str, Any]:
        """Read the rules at ``path`` (default: the file it runs) and swap them in between two decisions.

        Only a file the operator allowed is read (:meth:`allowed`): any other path is
        refused with a fixed message and never touched. The new rules are checked first: on
        any error the old rules stay and the answer says why (``success`` false, ``message``
        the diagnostics). Otherwise obligations of rules that still exist are kept and those
        of removed rules withdrawn (:meth:`cosleec.runtime.Manager.reload`). Every attempt
        gets a ``reload-attempt`` record in the audit log: ``via`` (service, signal, call),
        ``caller`` (who asked, where the middleware says), the path, the outcome
        (``reloaded``, ``failed``: allowed but not taken, ``refused``: not allowed), both hashes.
        """
        before = self.manager.rules_hash
        target = self.allowed(path)
        if target is None:
            self._count("reloads_refused")
            return self._reloaded(
                via, caller, path, None, "refused", self._refused_reload(path), before, before
            )
        try:
            rules = self._load(target)
            done = self.manager.reload(rules)
        except UserError as e:
            self._count("reloads_rejected")
            why = e.render() if hasattr(e, "render") else str(e)
            return self._reloaded(via, caller, path, target, "failed", why, before, before)
        except Exception as e:  # a bug of ours: recorded as an attempt all the same, then raised
            self._reloaded(via, caller, path, target, "failed", f"{type(e).__name__}: {e}", before, before)
            raise
        self.rules_path = target
        self._count("reloads")
        self.status()
        message = (
            f"reloaded {target}: +{len(done.added)} -{len(done.removed)} ~{len(done.changed)} rules, "
            f"{len(done.withdrawn)} obligation(s) withdrawn"
        )
        return self._reloaded(
            via, caller, path, target, "reloaded", message, done.previous_hash, done.current_hash
        )

    def allowed(self, path: str | None) -> str | None:
        """The file a reload of ``path`` may read, or None if the operator allowed no such file.

        No path, or the running file's own path, is the running file. With ``reload_dir``, a
        path under that directory is allowed once symlinks and ``..`` are resolved and it is
        still under it (the resolved path is what is read). Everything else is refused
        before the file system is asked anything: only a path already under the directory
        (as written, ``..`` collapsed) is resolved at all.
        """
        if not path:
            return self.rules_path
        if "\0" in path:
            return None
        given = os.path.normpath(os.path.abspath(path))
        if self.rules_path and given == os.path.normpath(os.path.abspath(self.rules_path)):
            return self.rules_path
        if self.reload_dir is None:
            return None
        real_dir, as_given = self.reload_dir
        if not any(_under(given, d) for d in {real_dir, as_given}):
            return None
        real = os.path.realpath(given)  # a symlink under the directory may point anywhere
        return real if _under(real, real_dir) else None

    def _refused_reload(self, path: str | None) -> str:
        """The fixed answer to a reload that is not allowed: the same whatever the path, so that
        it says nothing of what exists or what a file holds."""
        if not path:
            return "no rule file to reload: this Manager was started without one" + (
                "; give one under the directory its operator allowed" if self.reload_dir else ""
            )
        if self.reload_dir is None:
            return (
                "reload refused: this Manager reloads only the rule file it runs (call ~/reload with "
                "no path); its operator can allow a directory of rule files with --reload-dir"
            )
        return (
            "reload refused: this Manager reloads only the rule file it runs (call ~/reload with no "
            "path) or a rule file under the directory its operator allowed with --reload-dir"
        )

    def _reloaded(
        self,
        via: str,
        caller: str | None,
        path: str | None,
        target: str | None,
        outcome: str,
        message: str,
        previous: str,
        current: str,
    ) -> dict[str, Any]:
        """Record a reload attempt in the audit log; return the answer to the caller."""
        record: dict[str, Any] = {
            "via": via,
            "caller": clip(caller, MAX_NAME) if caller else None,
            "path": clip(path, MAX_PATH_SHOWN) if path else None,
            "outcome": outcome,
            "previous_hash": previous,
            "current_hash": current,
        }
        if target is not None:  # what was read, symlinks resolved (only ever an allowed file)
            record["file"] = target
        if outcome != "reloaded":
            record["reason"] = clip(message, REASON_LIMIT)
        self._note("reload-attempt", record)
        return {
            "success": outcome == "reloaded",
            "message": message,
            "previous_hash": previous,
            "current_hash": current,
        }

    def _note(self, kind: str, record: dict[str, Any]) -> None:
        """Write ``record`` in the audit log through the Manager; a Manager that takes no more
        steps (closed, its journal failed) cannot, which is logged, never raised into a caller."""
        try:
            self.manager.note(kind, record)
        except CosleecError as e:
            self.limiter.log(logging.ERROR, ("note", kind), "manager: cannot record %s: %s", kind, e)

    # ------------------------------------------------------------------ services
    def _permission(self, event: str, source: str = "") -> Permission:
        if not self.active:
            return Permission(event=event, permitted=False, rules=(), reason=self._inactive())
        return self.manager.request(event, source=source)  # the service is asked before acting: an attempt

    def _serve_request(self, req: dict[str, Any]) -> dict[str, Any]:
        name = req.get("event")
        if not isinstance(name, str) or not name or len(name) > MAX_NAME:
            return {"permitted": False, "rules": [], "reason": f"not an event name: {show(name)}"}
        try:
            p = self._permission(name, str(req.get("source", ""))[:MAX_NAME])
        except ContextError as e:  # an event no rule declares (unknown_events="raise"): refused, and why
            hint = f" ({e.hint})" if e.hint else ""
            return {"permitted": False, "rules": [], "reason": f"{e.message}{hint}"}
        return {"permitted": p.permitted, "rules": list(p.rules), "reason": p.reason}

    def _serve_decide(self, req: dict[str, Any]) -> dict[str, Any]:
        values, name = req.get("values") or {}, req.get("event") or ""
        turned_off = self._decide_refusal(bool(values))
        if turned_off is not None:
            self._audit_rejected("~/decide", turned_off, req, req.get("_caller"))
            self.reject("~/decide", turned_off, {k: v for k, v in req.items() if k != "_caller"})
            return {"accepted": False, "error": turned_off, "decisions": []}
        if not self.active:
            return {"accepted": False, "error": self._inactive(), "decisions": []}
        if name and name not in self.manager.ruleset.events:  # before any value is taken: all or nothing
            close = difflib.get_close_matches(str(name), sorted(self.manager.ruleset.events), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            return {"accepted": False, "error": f"unknown event {show(name)}{hint}", "decisions": []}
        try:
            if values:
                checked = context_values({"values": values})
                self._check_numbers(checked)
            if not name:  # values alone (or nothing at all)
                if values:
                    self.manager.update(checked)
                decisions = []
            else:  # the values and the event as one: nothing of another thread's comes between
                decisions = self.manager.event(name, values=checked if values else None)
        except (MessageError, ContextError) as e:
            return {"accepted": False, "error": str(e), "decisions": []}
        return {"accepted": True, "error": "", "decisions": [d.to_json() for d in decisions]}

    def _decide_refusal(self, with_values: bool) -> str | None:
        """Why ``~/decide`` refuses a call (None: it takes it), as the operator chose (``decide``)."""
        if self.decide == "off":
            return (
                "~/decide is off on this Manager: publish measures on `context` and events on `events`, "
                "or start the Manager with --decide events-only or --decide all"
            )
        if self.decide == "events-only" and with_values:
            return (
                "~/decide takes events only on this Manager (--decide events-only), not values: "
                "publish measures on `context`, or start the Manager with --decide all"
            )
        return None

    def _serve_reload(self, req: dict[str, Any]) -> dict[str, Any]:
        caller = req.get("_caller")
        return self.reload(
            str(req.get("rules") or "") or None,
            via="service",
            caller=caller if isinstance(caller, str) else None,
        )

    def _service_rejected(self, name: str, error: Exception, caller: str | None = None) -> None:
        """A call to service ``name`` the transport could not decode (a value of an unknown kind, a
        measure given twice): rejected, counted, published and recorded like a bad message."""
        reason = str(error) or type(error).__name__
        self._audit_rejected(name, reason, "", caller)
        self.reject(name, reason, "")

    def reject_error(self, where: str, error: Exception, payload: Any) -> None:
        """As :meth:`Node.reject_error`, and a ``rejected`` record in the audit log for what the
        runtime never saw: a message that could not be decoded or read, an event while
        inactive. (What the runtime refused -- a ContextError -- it recorded itself.)"""
        if not isinstance(error.__cause__, ContextError):
            self._audit_rejected(where, str(error) or type(error).__name__, payload)
        super().reject_error(where, error, payload)

    def _audit_rejected(self, where: str, reason: str, payload: Any, caller: Any = None) -> None:
        """A ``rejected`` record (as the runtime writes for an unknown event) for an input of ``where``."""
        record: dict[str, Any] = {
            "reason": clip(reason, REASON_LIMIT),
            "what": where.rsplit("/", 1)[-1],
            "topic": where,
        }
        if payload not in ("", None) and not callable(payload):  # (a typed message's decoder shows nothing)
            shown = (
                {k: v for k, v in payload.items() if k != "_caller"} if isinstance(payload, dict) else payload
            )
            record["payload"] = excerpt(shown, REASON_LIMIT)
        if isinstance(caller, str) and caller:
            record["caller"] = clip(caller, MAX_NAME)
        self._note("rejected", record)

    def status(self, **extra: Any) -> None:
        """Publish the counters with the context version, runtime statistics, active layers and time.

        The scenario driver reads these to know when the system is quiet.
        """
        self._publish_again()  # the heartbeat: decisions a restart must publish again, once heard
        m = self.manager
        with self._status_lock:  # the extra fields are part of the same ordered snapshot
            super().status(
                context_version=m.context.version,
                stats=dict(m.stats),
                lifecycle="active" if self.active else "inactive",
                rules_hash=m.rules_hash,
                active=m.active_layers(),
                time=self.clock.now(),
                holding=len(self._republish),  # decided, not yet handed on: the task nodes cannot hear yet
                **extra,
            )

    # ------------------------------------------------------------------ inputs
    # Each handler refuses what the runtime must not see by raising MessageError: the
    # message is rejected, counted and reported (Node.on), and the node goes on.
    def _context(self, msg: dict[str, Any]) -> None:
        values = context_values(msg)
        self._check_numbers(values)
        self._feed(self.manager.update, values)

    @staticmethod
    def _check_numbers(values: dict[str, Any]) -> None:
        for name, v in values.items():  # the runtime takes any int; a float it cannot be is refused here
            if isinstance(v, int) and not isinstance(v, bool) and abs(v) > sys.float_info.max:
                raise MessageError(
                    f"{show(name)} is an integer too large for a float ({v.bit_length()} bits)"
                )

    def _event(self, msg: dict[str, Any]) -> None:
        if not self.active:
            raise MessageError(self._inactive())
        name = msg.get("event")
        if not isinstance(name, str):
            raise MessageError("event message needs a string `event`")
        if len(name) > MAX_NAME:  # unknown anyway; refused before the runtime echoes it in its records
            raise MessageError(f"event name of {len(name)} characters (at most {MAX_NAME}): {show(name)}")
        values = msg.get("values")
        if values is not None and values != {}:  # measures observed with it: applied just before it
            checked = context_values({"values": values})
            self._check_numbers(checked)
            self._feed(lambda n: self.manager.event(n, values=checked), name)
            return
        self._feed(self.manager.event, name)

    def _feed(self, step: Any, arg: Any) -> None:
        """Hand one input to the runtime; what it rejects becomes a rejected message."""
        try:
            step(arg)
        except ContextError as e:
            raise MessageError(str(e)) from e

    def _request(self, msg: dict[str, Any]) -> None:
        name, rid = msg.get("event"), msg.get("id")
        if not isinstance(name, str) or isinstance(rid, bool) or not isinstance(rid, str | int):
            raise MessageError("request message needs an `id` (string or integer) and a string `event`")
        if len(name) > MAX_NAME or len(str(rid)) > MAX_NAME:  # the reply echoes both
            raise MessageError(f"request `id` or `event` longer than {MAX_NAME} characters")
        source = msg.get("source")
        try:
            p = self._permission(name, source if isinstance(source, str) else "")
        except ContextError as e:  # an event no rule declares: refused, and the task learns why
            self.publish("request_reply", {"id": rid, "event": name, "allowed": False, "reason": str(e)})
            raise MessageError(str(e)) from e
        reply: dict[str, Any] = {"id": rid, "event": name, "allowed": p.permitted}
        if not p.permitted:
            reply.update(rules=list(p.rules), reason=p.reason)
        self.publish("request_reply", reply)

    def _clock(self, msg: dict[str, Any]) -> None:
        """Simulated time: ``t`` must be a finite number, and time never goes back.

        A ``t`` earlier than now is rejected and counted, and time stays where it is
        (silently keeping the later time would hide a simulator that restarted or a
        stale publisher); ``t`` equal to now judges deadlines again, harmlessly.
        """
        t = msg.get("t")
        if not isinstance(t, int | float) or isinstance(t, bool):
            raise MessageError("clock message needs a number `t`")
        try:
            seconds = float(t)
        except OverflowError:  # an integer of hundreds of digits
            raise MessageError("clock `t` is an integer too large for a float") from None
        if not math.isfinite(seconds):
            raise MessageError(f"clock `t` must be a finite number, not {t!r}")
        assert isinstance(self.clock, VirtualClock)
        now = self.clock.now()
        if seconds < now:
            raise MessageError(f"clock went back from {now} to {seconds}: time does not go back")
        self.clock.set(seconds)
        self.manager.tick()

    def after_message(self) -> None:
        """With ``status_each``, a status after every message, once it is handled (harnesses)."""
        if self.status_each:
            self.status()

    # ------------------------------------------------------------------ outputs
    def _runtime_event(self, ev: RuntimeEvent) -> None:
        d = ev.data
        if ev.kind == "decision":
            if "dispatch" not in d:  # held or changed by a conflict: handed on by its `dispatch` record
                self._hand_on(d)
            self.publish("decisions", d)
        elif ev.kind == "dispatch":  # a held decision now allowed, or one a conflict changed
            self._hand_on(d["decision"])
        elif ev.kind == "obligation" and (d["status"] == "violated" or d["late"]):
            self.publish("violations", d)
        elif ev.kind == "conflict":
            self.publish("conflicts", d)
        elif ev.kind == "refused":
            self.publish("refusals", d)
        if self.recorder is not None:
            self.recorder.write(ev.kind, ev.time, d)

    def _publish_again(self) -> None:
        """Publish the decisions a journal held as perhaps never published, once someone listens;
        again to subscribers matched later; then let them leave the journal's outbox.

        A restarted node's publisher is new: what it sends before the task nodes have matched
        it would be lost. The heartbeat calls this until they have: until the subscriber count
        is not 0 and stayed the same for :data:`REPUBLISH_SETTLE_S`. That count may be a
        driver's or a recorder's while a task node is still being discovered, so what went out
        is sent again (counted ``resent``; task nodes run each action once) whenever the count
        grows and settles, until it stayed the same for :data:`REPUBLISH_WINDOW_S`: only then
        is it delivered (a restart before that publishes it again). A transport that cannot
        count subscribers publishes at once and delivers at once.
        """
        with self._hand_lock:
            if self._settled and not self._unconfirmed:
                return
            count = getattr(self.transport, "subscribers", None)
            n, stable = 0, math.inf
            if count is not None:
                now, n = time.monotonic(), count(self.topic("obligations"))
                if n == 0 or self._matched is None or self._matched[0] != n:
                    self._matched = (n, now)
                    return
                stable = now - self._matched[1]
                if stable < REPUBLISH_SETTLE_S:
                    return
            if not self._settled:
                self._settled = True
                self._unconfirmed, self._republish = self._republish, []
                for d in self._unconfirmed:
                    self._count("republished" if d.get("_again") else "obligations_held")
                    self._send(d, deliver=False)
                self._sent_to = n
            elif n > self._sent_to:  # matched since they went out (a task node discovered late)
                for d in self._unconfirmed:
                    self._send(d, deliver=False, counter="resent")
                self._sent_to = n
            if stable >= REPUBLISH_WINDOW_S:
                for d in self._unconfirmed:
                    self.manager.delivered(int(d["id"]))
                self._unconfirmed = []

    def _hand_on(self, d: dict[str, Any]) -> None:
        """Publish a decision to the task nodes -- held until they can hear it after a start, and
        while what was published again is not yet heard, sent again with it (:meth:`_publish_again`)."""
        with self._hand_lock:
            if not self._settled:  # a new publisher: what it sent now could reach no one
                self._republish.append(d)
                return
            if self._unconfirmed:  # a task node may not be matched yet: it gets this too, later
                self._unconfirmed.append(d)
                self._send(d, deliver=False)
                return
        self._send(d)

    def _send(self, d: dict[str, Any], *, deliver: bool = True, counter: str = "obligations") -> None:
        """Publish a decision that chose a clause to the task nodes (counted in ``counter``), then
        tell the Manager it left (``deliver``: not yet for one published again, :meth:`_publish_again`)."""
        d = {k: v for k, v in d.items() if k != "_again"}
        if d["clause"] is not None:  # the task nodes first: they are on the critical path
            self._count(counter)
            # task nodes run each (session, id, action) once: a duplicate on the wire is not re-run
            self.publish("obligations", {**d, "session": self.session})
        if deliver:
            self.manager.delivered(int(d["id"]))

    def close(self) -> None:
        """Stop what ``on_manager`` attached, then the Manager (timer, audit log), and finish the
        recording; the transport is the caller's."""
        try:
            self._release()
        finally:
            self.manager.close()
        if self.recorder is not None:
            self.recorder.close()


def _directory(path: str) -> tuple[str, str]:
    """``reload_dir`` resolved (symlinks and ``..``) and as given (absolute); UserError unless a directory."""
    if not os.path.isdir(path):
        raise UserError(
            f"the reload directory {path!r} is not a directory",
            hint="give --reload-dir an existing directory that only the operator can write to",
        )
    return os.path.realpath(path), os.path.normpath(os.path.abspath(path))


def _under(path: str, directory: str) -> bool:
    """Is ``path`` strictly inside ``directory`` (both absolute, normalised)? Pure string work."""
    return path != directory and os.path.commonpath([path, directory]) == directory

"""The SubBroker: link client, planner, fan-out, delivery, queryables, status,
composed (docs/subbroker.md).

>>> broker = SubBroker(config_from_model("scenario1.modd"))   # doctest: +SKIP
>>> broker.start()                                           # doctest: +SKIP
>>> broker.stop()                                            # doctest: +SKIP
"""

from __future__ import annotations

import json
import logging
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from modd_model.query import topics
from modd_model.signing import NonceGuard
from modd_plan import Plan
from modd_plan.streams import Source, StreamKey

from modd.link.frames import AuthOk, Config, ConfigAck, Status
from modd.link.receiver import Window

from ..zenoh_auth import CredentialStore
from ..zenoh_session import open_session, secured
from .config import SubBrokerConfig, resolve_key
from .delivery import Sink, SlotDelivery, TcpDelivery, ZenohDelivery, tcp_endpoints
from .deploy import DeployRequest, parse_request
from .dglink import DatagramLinkClient
from .dynamic import DynamicSubscriptions
from .fanout import FanOut
from .keys import deploy_key, subscribe_key
from .link import ConfigRejected, LinkDown
from .planning import config_for, plan_for
from .status import StatusPublisher
from .transport import link_client

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker")


@dataclass
class Running:
    """A config the PubBroker acknowledged, with everything to fan it out."""

    model: dict[str, Any]
    plan: Plan
    config: Config
    epoch_ns: int
    fanout: FanOut
    topic_info: dict[str, tuple[str, str]] = field(default_factory=dict)  # unit, type
    slots: SlotDelivery | None = None

    def route(self, stream: StreamKey, sources: tuple[Source, ...], subscriber: str) -> None:
        self.fanout.route(stream, sources, subscriber)

    def unroute(self, subscriber: str) -> bool:
        return self.fanout.unroute(subscriber)


class SubBroker:
    """One drone's base-station broker. ``start`` opens the zenoh session
    (unless one is given), declares the queryables and starts the link."""

    def __init__(self, config: SubBrokerConfig, session: zenoh.Session | None = None) -> None:
        self.config = config
        self.drone = config.drone
        self._key = resolve_key(config.key_ref)
        self._session = session
        self._own_session = session is None
        self._store = CredentialStore(config.credentials_dir)
        self._deploy_key = b""
        self._nonces = NonceGuard()
        self._model = self._initial_model()
        self._running: Running | None = None
        self._by_id: dict[int, Running] = {}
        self._planned: dict[int, tuple[dict[str, Any], Plan]] = {}
        self._last_id = 0
        self._lock = threading.RLock()
        self._deploy_lock = threading.Lock()
        self.dynamic = DynamicSubscriptions(self.drone, self._static_names)
        self.link = link_client(config, self._key, self, self._liveness)
        self._zenoh: ZenohDelivery | None = None
        self._tcp: TcpDelivery | None = None
        self._status: StatusPublisher | None = None
        self._queryables: list[Any] = []
        self._workers = ThreadPoolExecutor(max_workers=4, thread_name_prefix="modd-query")
        self.delivered = 0

    # -- lifecycle -------------------------------------------------------------

    def _initial_model(self) -> dict[str, Any]:
        saved = self._state_file()
        if saved is not None and saved.exists():
            log.info("running the deployed model kept in %s", saved)
            model: dict[str, Any] = json.loads(saved.read_text())
            return model
        return self.config.model

    def _state_file(self) -> Path | None:
        d = self.config.state_dir
        return d / "deployed.json" if d is not None else None

    def start(self) -> None:
        self._store.ensure()
        self._deploy_key = self._store.deploy_key()
        if self._session is None:
            settings = secured(self.config.zenoh, self._store, "subbroker", self.drone)
            self._session = open_session(settings)
        session = self._session
        if self.config.delivery.zenoh:
            self._zenoh = ZenohDelivery(session, self.drone)
        if self.config.delivery.tcp:
            self._tcp = TcpDelivery({}, self.config.delivery.tcp_queue)
        self._queryables = [
            session.declare_queryable(subscribe_key(self.drone), self._on_query(self._subscribe)),
            session.declare_queryable(deploy_key(self.drone), self._on_query(self._deploy)),
        ]
        self._status = StatusPublisher(
            session, self.drone, self.config.delivery.status_period_s, self.status,
            lambda: self.link.stats,
        )
        self._status.start()
        self.link.start()
        log.info("SubBroker for %s: link %s %s:%d", self.drone, self.config.transport,
                 *self.config.endpoint)

    def stop(self) -> None:
        self.link.stop()
        if self._status is not None:
            self._status.stop()
        for q in self._queryables:
            q.undeclare()
        self._workers.shutdown(wait=True, cancel_futures=True)
        if self._tcp is not None:
            self._tcp.close()
        if self._zenoh is not None:
            self._zenoh.close()
        if self._own_session and self._session is not None:
            self._session.close()  # type: ignore[no-untyped-call]

    # -- planning ----------------------------------------------------------------

    def _static_names(self) -> set[str]:
        running = self._running
        model = running.model if running else self._model
        return {s["name"] for s in model.get("subscribers", [])}

    def _liveness(self) -> float:
        if self.config.link.liveness_timeout_s > 0:
            return self.config.link.liveness_timeout_s
        running = self._running
        if running is None or not running.config.streams:
            return 3.0
        shortest = min(s.period_us for s in running.config.streams) / 1e6
        return max(3.0, 2 * shortest + 1.0)

    def _prepare(self, model: dict[str, Any], avoid: int) -> Config:
        plan = plan_for(model, self.link.stats.rtt_s)
        if not plan.sent_streams:
            raise ValueError("the plan sends nothing over the link (no published subscription)")
        with self._lock:
            cid = self._last_id % 255 + 1
            if cid == avoid:
                cid = cid % 255 + 1
            self._last_id = cid
            # kept until acked: an ack that comes after the deploy timed out
            # still means the PubBroker runs it, so the SubBroker follows
            self._planned[cid] = (model, plan)
            for stale in list(self._planned)[:-8]:
                del self._planned[stale]
        return config_for(plan, cid, self.config.link.pubbroker_status_period_s)

    # -- LinkHandler -------------------------------------------------------------

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | None:
        running = self._running
        if running and ok.config_id == running.config.config_id and ok.epoch_ns == running.epoch_ns:
            log.info("resuming config %d", ok.config_id)
            return None
        model = running.model if running else self._model
        return self._prepare(model, avoid=ok.config_id)

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None:
        with self._lock:
            model, plan = self._planned.pop(config.config_id)
        sent = [s.stream for s in plan.sent_streams]
        running = Running(model, plan, config, ack.epoch_ns, FanOut(sent))
        running.topic_info = {t.name: (t.unit, t.type) for t in topics(model).values()}
        running.slots = SlotDelivery(running.fanout, config.config_id, ack.epoch_ns,
                                     running.topic_info)
        for ps in plan.streams:
            for sub in ps.subscribers:
                running.route(ps.stream, ps.sources, sub)
        for name, reason in self.dynamic.reroute(running):
            log.warning("dynamic subscription %s dropped by the new plan: %s", name, reason)
            if self._zenoh is not None:
                self._zenoh.forget(name)
        with self._lock:
            self._by_id = {config.config_id: running}
            self._running = running
            self._model = model
        if self._tcp is not None:
            self._tcp.set_endpoints(tcp_endpoints(model))
        log.info("config %d running (epoch %d ns, %d streams sent)", config.config_id,
                 ack.epoch_ns, len(config.streams))

    def on_windows(self, windows: list[Window]) -> None:
        running = self._by_id.get(windows[0].config_id)
        if running is None or running.slots is None:
            return
        sinks: list[Sink] = [s for s in (self._zenoh, self._tcp) if s is not None]
        self.delivered += running.slots.deliver(windows, sinks)

    def on_status(self, status: Status) -> None:
        log.debug("PubBroker status %s", status.as_dict())

    # -- queryables ----------------------------------------------------------------

    def _on_query(self, handler: Any) -> Any:
        def callback(query: zenoh.Query) -> None:
            payload = query.payload.to_bytes() if query.payload is not None else b""
            self._workers.submit(self._serve, query, handler, payload)

        return callback

    def _serve(self, query: zenoh.Query, handler: Any, payload: bytes) -> None:
        try:
            reply = handler(payload)
        except Exception as exc:  # the caller must get an answer, never silence
            log.exception("query on %s failed", query.key_expr)
            reply = {"status": "ERROR", "reason": f"internal error: {exc}"}
        try:
            query.reply(query.key_expr, json.dumps(reply, separators=(",", ":")))
        finally:
            query.drop()  # type: ignore[no-untyped-call]

    def _subscribe(self, payload: bytes) -> dict[str, Any]:
        try:
            request = json.loads(payload or b"{}")
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            return {"status": "ERROR", "reason": f"the request is not JSON: {exc}"}
        if not isinstance(request, dict):
            return {"status": "ERROR", "reason": "the request must be a JSON object"}
        reply = self.dynamic.handle(request, self._running)
        if reply["status"] == "CANCELLED" and self._zenoh is not None:
            self._zenoh.forget(reply["subscriber"])
        return reply

    def _deploy(self, payload: bytes) -> dict[str, Any]:
        request = parse_request(payload, self.drone, self._verify)
        if request.model is None:
            if request.reply.get("status") == "UNAUTHORISED":
                log.warning("deploy refused: %s", request.reply["reason"])
            return request.reply
        with self._deploy_lock:
            return self.deploy(request)

    def _verify(self, request: dict[str, Any]) -> str | None:
        refused = self._nonces.verify(self._deploy_key, request)
        if refused is None:
            log.info("deploy of revision %s signed for %s", request.get("revision"),
                     str(request.get("deployed_by"))[:64])
        return refused

    def deploy(self, request: DeployRequest) -> dict[str, Any]:
        """Plan ``request.model``, send CONFIG, wait for the ack; the reply."""
        assert request.model is not None
        try:
            config = self._prepare(request.model, avoid=0)
        except ValueError as exc:
            return {"status": "REJECTED", "reason": str(exc)}
        try:
            ack = self.link.send_config(config, request.timeout_s)
        except LinkDown as exc:
            return {"status": "LINK_DOWN", "reason": str(exc)}
        except TimeoutError as exc:
            return {"status": "TIMEOUT", "reason": f"{exc} within {request.timeout_s} s"}
        except ConfigRejected as exc:
            return {"status": "NACK", "reason": str(exc), "code": exc.status}
        self._save(request.model)
        plan = self._running.plan if self._running else None
        summary = plan.to_json() if plan else {}
        return {
            "status": "ACKED",
            "config_id": ack.config_id,
            "epoch_ns": ack.epoch_ns,
            "streams_sent": len(config.streams),
            "hyperperiod_s": summary.get("hyperperiod_s"),
            "messages_per_hyperperiod": summary.get("messages_per_hyperperiod"),
            "buffer_sizes": summary.get("buffer_sizes"),
            "predicted_link_bytes_per_s": summary.get("predicted_link_bytes_per_s"),
            "warnings": request.warnings,
        }

    def _save(self, model: dict[str, Any]) -> None:
        path = self._state_file()
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps(model))
            tmp.replace(path)

    # -- status ------------------------------------------------------------------

    def status(self) -> dict[str, Any]:
        """The status document (docs/subbroker.md, "Status")."""
        stats = self.link.stats
        running = self._running
        predicted = running.plan.link.to_json() if running else None
        return {
            "drone": self.drone,
            "time_ns": time.time_ns(),
            "link": stats.state,
            "endpoint": "{}:{}".format(*self.config.endpoint),
            "rtt_s": stats.rtt_s,
            "config_id": running.config.config_id if running else None,
            "epoch_ns": running.epoch_ns if running else None,
            "bytes_in": stats.bytes_in,
            "bytes_out": stats.bytes_out,
            "data_frames": stats.data_frames,
            "skipped_frames": stats.bad_frames,
            "connects": stats.connects,
            "last_data_ns": stats.last_data_ns,
            "last_error": stats.last_error,
            "delivered": self.delivered,
            "predicted_link_bytes_per_s": predicted,
            "routes": running.fanout.routes() if running else {},
            "dynamic": self.dynamic.names(),
            "tcp": self._tcp.stats() if self._tcp else {},
            "pubbroker": dict(stats.pubbroker),
            "transport": self.config.transport,
            "link_budget": (running.plan.budget.to_json()
                            if running is not None and running.plan.budget is not None else None),
            "radio": (self.link.radio_status()
                      if isinstance(self.link, DatagramLinkClient) else None),
        }


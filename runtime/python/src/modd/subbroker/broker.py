"""The SubBroker: link client, planner, fan-out, delivery, queryables, status,
composed (docs/subbroker.md).

>>> broker = SubBroker(config_from_model("scenario1.modd"))   # doctest: +SKIP
>>> broker.start()                                           # doctest: +SKIP
>>> broker.stop()                                            # doctest: +SKIP
"""

from __future__ import annotations

import hmac
import json
import logging
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Any

from modd_contracts.link_wire_gen import MAX_ONBOARD_BYTES, MAX_ONBOARD_WIRE, ONBOARD_WAIT_MS
from modd_model.diagnostics import Diagnostic, ModelError
from modd_model.query import topics
from modd_model.signing import NonceGuard, signature
from modd_plan import Plan
from modd_plan.streams import StreamKey

from modd.link import codec
from modd.link.frames import AuthOk, Config, ConfigAck, ErrorCode, Onboard, Status
from modd.link.receiver import Window

from .. import onboard
from ..zenoh_auth import CredentialStore
from ..zenoh_gate import AcceptGate, start_gates
from ..zenoh_session import open_session, secured
from . import backfill_query, delivery_auth
from .backfill import BackfillManager
from .config import ConfigError, SubBrokerConfig, resolve_key
from .delivery import Filled, Sink, SlotDelivery, TcpDelivery, ZenohDelivery, tcp_endpoints
from .deploy import DeployRequest, parse_request
from .dglink import DatagramLinkClient
from .diversity import Diversity
from .dynamic import DynamicSubscriptions
from .fanout import FanOut
from .fleet_record import FleetRecord, merge
from .handover import RunningConfig, model_digest
from .kept import Deployment, StateDir, same_model
from .keys import backfill_key, deploy_key, subscribe_key
from .linkhooks import Adopted, ConfigRejected, LinkDown
from .planning import config_for, plan_within, trailing_fields
from .pump import Pump
from .record import BaseRecord
from .rehearsal import CutSwitch
from .request import MAX_DEPLOY_BYTES, MAX_SMALL_BYTES, read_request
from .running import Running
from .serving import ServingSwitch
from .status import StatusPublisher
from .transport import link_client

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker")

#: After a reconnection, live values flow again before the automatic backfill looks for gaps.
AUTO_BACKFILL_DELAY_S = 2.0


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
        self._state = StateDir(config.state_dir)
        self._model, self._meta = self._initial_model()
        self._running: Running | None = None
        self._by_id: dict[int, Running] = {}
        # model, plan, deployment, and the round trip the plan was made for
        self._planned: dict[int, tuple[dict[str, Any], Plan, Deployment, float | None]] = {}
        self._last_id = 0
        self._lock = threading.RLock()
        self._deploy_lock = threading.Lock()
        self.dynamic = DynamicSubscriptions(self.drone, self._static_names)
        if config.resume:
            self.dynamic.restore(self._state.load_dynamic())
        self.dynamic.persist = self._state.save_dynamic
        self.link = link_client(config, self._key, self, self._liveness)
        if config.rehearsal_dir is not None and isinstance(self.link, Pump):
            self.link.cut = CutSwitch(config.rehearsal_dir)
        self._zenoh: ZenohDelivery | None = None
        self._tcp: TcpDelivery | None = None
        self._status: StatusPublisher | None = None
        self._queryables: list[Any] = []
        self._workers = ThreadPoolExecutor(max_workers=4, thread_name_prefix="modd-query")
        self.delivered = 0
        self._onboard: dict[str, Any] = {}  # what the on-board processes did with the last deploy
        # Backfill (docs/subbroker.md, "Backfill") and the base-station record of every delivery.
        records = config.record_dir or (config.state_dir / "records" if config.state_dir else None)
        self.record = BaseRecord(records, self.drone) if records is not None else None
        self.backfill = BackfillManager(
            self.link.send_frame, self._sinks, self._state, drone=self.drone
        )
        self.link.backfill_sink = self.backfill.on_frame
        self.link.on_up = self._link_up

    # -- lifecycle -------------------------------------------------------------

    def _initial_model(self) -> tuple[dict[str, Any], Deployment]:
        """The kept deployment, said loudly (it is not the configured model),
        unless ``resume`` is off; else the configured model."""
        kept = self._state.load_deployment()
        where = self._state.deployment_file()
        if kept is None:
            return self.config.model, Deployment.configured()
        model, meta = kept
        if not self.config.resume:
            log.warning(
                "NOT resuming the deployment kept in %s (%s): running the configured model",
                where,
                meta.describe(),
            )
            return self.config.model, Deployment.configured()
        self._differs = not same_model(model, self.config.model)
        log.warning(
            "RESUMING the deployment kept in %s: %s%s",
            where,
            meta.describe(),
            "; it DIFFERS from the configured model"
            if self._differs
            else " (the same as the configured model)",
        )
        return model, meta

    def nonce_file(self) -> Path:
        """The deploy nonces accepted within the signing window (replay
        guard across restarts): beside the deployed model, else beside
        the deploy key."""
        d = self.config.state_dir
        return (d if d is not None else self.config.credentials_dir) / f"deploy-nonces-{self.drone}"

    _differs = False

    def start(self) -> None:
        self._store.ensure()
        self._deploy_key = self._store.deploy_key()
        nonces = self.nonce_file()
        nonces.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        self._nonces = NonceGuard(path=nonces)
        if self._session is None:
            settings = secured(self.config.zenoh, self._store, "subbroker", self.drone)
            settings, self._gates = start_gates(settings)
            try:
                self._session = open_session(settings)
            except BaseException:
                self._stop_gates()
                raise
        session = self._session
        if self.config.station and isinstance(self.link, Pump):
            self.fleet = FleetRecord(session, self.drone, self.config.station, self._told)
            self.backfill.fleet = self.fleet.others
            self.serving = ServingSwitch(
                session, self.drone, self.config.station, lambda: self.link.up, self._serves
            )
            self.link.cut = self.serving
            if isinstance(self.link, DatagramLinkClient):
                self.diversity = Diversity(session, self.drone, self.config.station, self.link)
        if self.config.delivery.zenoh:
            self._zenoh = ZenohDelivery(session, self.drone)
        if self.config.delivery.tcp:
            key = self.config.delivery.key
            if key:  # a configured key must be readable now, not at the first subscriber
                try:
                    delivery_auth.load_key(key)
                except delivery_auth.DeliveryKeyError as exc:
                    raise ConfigError(str(exc)) from exc
            self._tcp = TcpDelivery({}, self.config.delivery.tcp_queue, key)
        if self.serving is None:  # a station answers while it serves (_serves)
            self._declare_queryables(session)
        self._status = StatusPublisher(
            session,
            self.drone,
            self.config.delivery.status_period_s,
            self.status,
            lambda: self.link.stats,
        )
        if self.serving is not None:
            self._status.quiet = self.serving.another_serves
        self._status.start()
        self.link.start()
        log.info(
            "SubBroker for %s: link %s %s:%d",
            self.drone,
            self.config.transport,
            *self.config.endpoint,
        )

    serving: ServingSwitch | None = None
    fleet: FleetRecord | None = None
    diversity: Diversity | None = None

    def _declare_queryables(self, session: zenoh.Session) -> None:
        self._queryables = [
            session.declare_queryable(subscribe_key(self.drone), self._on_query(self._subscribe)),
            session.declare_queryable(deploy_key(self.drone), self._on_query(self._deploy)),
            session.declare_queryable(backfill_key(self.drone), self._on_query(self._backfill)),
        ]

    def _serves(self, serving: bool) -> None:
        """This station took the drone's link (its queryables answer) or left it."""
        if serving and not self._queryables and self._session is not None:
            self._declare_queryables(self._session)
        elif not serving:
            for q in self._queryables:
                q.undeclare()
            self._queryables = []

    def stop(self) -> None:
        self.link.stop()
        if self.serving is not None:
            self.serving.close()
        if self.diversity is not None:
            self.diversity.close()
        if self.fleet is not None:
            self.fleet.close()
        if self._status is not None:
            self._status.stop()
        self._serves(False)
        self._workers.shutdown(wait=True, cancel_futures=True)
        if self._tcp is not None:
            self._tcp.close()
        if self._zenoh is not None:
            self._zenoh.close()
        if self.record is not None:
            self.record.close()
        self.backfill.close()
        if self._own_session and self._session is not None:
            self._session.close()  # type: ignore[no-untyped-call]
        self._stop_gates()

    _gates: list[AcceptGate] = []  # noqa: RUF012 - replaced per instance in start()

    def _stop_gates(self) -> None:
        for gate in self._gates:
            gate.stop()
        self._gates = []

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

    def _told(self) -> dict[str, Any]:
        """The fleet's answer: the window record and, while this station serves, what
        its PubBroker runs."""
        doc = self.backfill.record_json()
        running = self.running_config() if self.link.up else None
        if running is not None:
            doc["running"] = running
        return doc

    def _prepare(self, model: dict[str, Any], avoid: int, meta: Deployment) -> Config:
        rtt = self.link.stats.rtt_s
        plan = plan_within(model, rtt, self.config.link.plan_budget_s)
        if not plan.sent_streams:
            raise ValueError("the plan sends nothing over the link (no published subscription)")
        with self._lock:
            cid = self._last_id % 255 + 1
            if cid == avoid:
                cid = cid % 255 + 1
            self._plan_kept(cid, model, plan, meta, rtt)
        return self._config_of(model, plan, cid)

    def _plan_kept(
        self, cid: int, model: dict[str, Any], plan: Plan, meta: Deployment, rtt: float | None
    ) -> None:
        """(Under the lock.) Kept until acked: an ack that comes after the deploy timed
        out still means the PubBroker runs it, so the SubBroker follows."""
        self._last_id = cid
        self._planned[cid] = (model, plan, meta, rtt)
        for stale in list(self._planned)[:-8]:
            del self._planned[stale]

    def _config_of(self, model: dict[str, Any], plan: Plan, cid: int) -> Config:
        delay_ms, resolutions = trailing_fields(
            model, self.config.model, self.config.transport, plan
        )
        return config_for(
            plan, cid, self.config.link.pubbroker_status_period_s, delay_ms, resolutions
        )

    def _adopt(self, ok: AuthOk) -> Adopted | None:
        """The config another station had the PubBroker run, when it still runs it and
        this station's model planned for that station's round trip gives the very same
        CONFIG (handover.py); None otherwise (a new CONFIG is sent)."""
        if self.fleet is None or ok.config_id == 0:
            return None
        running = self._running
        model, meta = (running.model, running.meta) if running else (self._model, self._meta)
        for station, told in self.fleet.running():
            if (told.config_id, told.epoch_ns) != (ok.config_id, ok.epoch_ns):
                continue
            if told.model != model_digest(model):
                log.info(
                    "config %d of station %s was planned from another model: a new config",
                    told.config_id,
                    station,
                )
                return None
            try:
                plan = plan_within(model, told.rtt_s, self.config.link.plan_budget_s)
                config = self._config_of(model, plan, told.config_id)
            except (ValueError, KeyError, TypeError, ArithmeticError) as exc:
                log.info(
                    "config %d of station %s cannot be planned here: %s",
                    told.config_id,
                    station,
                    exc,
                )
                return None
            if codec.encode(config) != told.config:
                log.info(
                    "config %d of station %s differs from this station's plan: a new config",
                    told.config_id,
                    station,
                )
                return None
            with self._lock:
                self._plan_kept(told.config_id, model, plan, meta, told.rtt_s)
            log.info(
                "adopting config %d of station %s (epoch %d ns): the PubBroker runs it",
                told.config_id,
                station,
                told.epoch_ns,
            )
            self._adopted = (station, told)
            return Adopted(config, ConfigAck(told.config_id, 0, told.epoch_ns), told.slot)
        return None

    def running_config(self) -> dict[str, Any] | None:
        """What the PubBroker runs, as the fleet is told it (handover.py)."""
        running = self._running
        if running is None:
            return None
        session = self.link.dgram.nonces if isinstance(self.link, DatagramLinkClient) else None
        return RunningConfig(
            running.config.config_id,
            running.epoch_ns,
            codec.encode(running.config),
            running.rtt_s,
            model_digest(running.model),
            running.last_slot,
            session,
        ).to_json()

    #: the station and running config adopted by the last on_connect (handover.py)
    _adopted: tuple[str, RunningConfig] | None = None

    def _deliver_heard(self, running: Running, station: str, told: RunningConfig) -> None:
        """After a takeover: the windows this station's modem heard while the previous
        station served and after the last one heard delivered, read under that station's
        session (diversity.py), delivered now when no station holds them rather than
        backfilled later (docs/fleet.md, "Diversity reception")."""
        if self.diversity is None or self.fleet is None or told.session is None:
            return
        assert isinstance(self.link, DatagramLinkClient)
        heard = self.diversity.take_heard()
        if not heard:
            return
        slots = self.link.dgram.read_heard(
            running.config, told.epoch_ns, told.slot, told.session, heard
        )
        after = self.fleet.heard_until()
        view = merge(self.fleet.others())

        def held(sub: str, stream: StreamKey, start: int, end: int) -> bool:
            return view.holds(sub, stream, start, end) or self.backfill.filled_already(
                sub, stream, start, end
            )

        new = [w for w in slots if after is None or w[0].end_ns > after]
        values = sum(self._deliver(running, w, held) for w in new)
        log.info(
            "took over with %d datagrams this station's modem heard: %d slots read under "
            "station %s's session, %d after the last window heard delivered, %d values "
            "delivered (the rest held by some station)",
            len(heard),
            len(slots),
            station,
            len(new),
            values,
        )

    # -- LinkHandler -------------------------------------------------------------

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | Adopted | None:
        self._adopted = None  # set again by _adopt when this connection adopts
        running = self._running
        if running and ok.config_id == running.config.config_id and ok.epoch_ns == running.epoch_ns:
            log.info("resuming config %d", ok.config_id)
            return None
        adopted = self._adopt(ok)
        if adopted is not None:
            return adopted
        if running:
            return self._prepare(running.model, ok.config_id, running.meta)
        try:
            return self._prepare(self._model, ok.config_id, self._meta)
        except (ValueError, KeyError, TypeError, AttributeError, ArithmeticError) as exc:
            # a kept model that cannot be planned (a damaged deployed.json) never stops the run
            if self._meta.source != "kept":
                raise
            log.error(
                "the kept deployment (%s) cannot be planned: %s; running the configured model",
                self._meta.describe(),
                exc,
            )
            self._model, self._meta = self.config.model, Deployment.configured()
            self._differs = False
            return self._prepare(self._model, ok.config_id, self._meta)

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None:
        with self._lock:
            model, plan, meta, rtt = self._planned.pop(config.config_id)
        if meta.source == "deploy" and meta.deployed_at_ns is None:
            # acked, even after its deploy timed out: this is what the drone runs now
            meta = meta.acked()
            self._differs = not same_model(model, self.config.model)
            try:
                self._state.save_deployment(model, meta)
            except OSError as exc:
                log.error("cannot keep the deployment in the state directory: %s", exc)
        sent = [s.stream for s in plan.sent_streams]
        running = Running(model, plan, config, ack.epoch_ns, FanOut(sent), meta, rtt_s=rtt)
        running.topic_info = {t.name: (t.unit, t.type) for t in topics(model).values()}
        running.slots = SlotDelivery(
            running.fanout, config.config_id, ack.epoch_ns, running.topic_info, self.drone
        )
        for ps in plan.streams:
            for sub in ps.subscribers:
                running.route(ps.stream, ps.sources, sub)
        for name, reason in self.dynamic.reroute(running):
            log.warning("dynamic subscription %s dropped by the new plan: %s", name, reason)
            if self._zenoh is not None:
                self._zenoh.forget(name)
        with self._lock:
            # the replaced config's last windows (dated up to the new epoch) may still
            # come: over a datagram link, the group packed before the switch, up to
            # the old accepted delay later. They go to the deployment they belong to.
            previous = self._running
            self._by_id = {config.config_id: running}
            if previous is not None and previous.config.config_id != config.config_id:
                self._by_id[previous.config.config_id] = previous
            self._running = running
            self._model, self._meta = model, meta
        self.backfill.on_config(running)
        if self._tcp is not None:
            self._tcp.set_endpoints(tcp_endpoints(model))
        if self.record is not None:
            self.record.begin(str(model.get("name") or self.drone), ack.epoch_ns)
        log.info(
            "config %d running (epoch %d ns, %d streams sent): %s",
            config.config_id,
            ack.epoch_ns,
            len(config.streams),
            meta.describe() if meta.source != "configured" else "the configured model",
        )
        adopted, self._adopted = self._adopted, None
        if adopted is not None and adopted[1].config_id == config.config_id:
            try:
                self._deliver_heard(running, *adopted)
            except Exception:  # what the modem heard is a bonus: the gaps are backfilled
                log.exception("the datagrams heard before the takeover could not be read")
        if self._status is not None:  # what runs is known at once, not a period later
            try:
                self._status.publish_now()
            except Exception:  # a status must never stop the link
                log.exception("status publication failed")

    def on_windows(self, windows: list[Window]) -> None:
        running = self._by_id.get(windows[0].config_id)
        if running is not None:
            self._deliver(running, windows, self.backfill.filled_already)

    def _deliver(self, running: Running, windows: list[Window], filled: Filled) -> int:
        """One slot's windows: held (journal and record: backfill.journal_live), then put
        to each subscriber whose window ``filled`` does not say is delivered already."""
        if running.slots is None:
            return 0
        running.last_slot = max(running.last_slot, windows[-1].slot)
        self.backfill.journal_live(running, windows)
        n = running.slots.deliver(
            windows, self._sinks(), filled, lambda d: self.backfill.journal_derived(*d)
        )
        self.delivered += n
        return n

    def _link_up(self) -> None:
        """After a reconnection: the running backfill resumes, and the subscriptions whose
        model asks for it (``backfill = gaps | mission``) get their gaps filled once live
        values flow again."""
        self.backfill.on_up()
        since = self.backfill.received_until()
        if since is None:  # the first connection: nothing was missed
            return
        timer = threading.Timer(AUTO_BACKFILL_DELAY_S, self._auto_backfill, (since,))
        timer.daemon = True
        timer.start()

    def _auto_backfill(self, since_ns: int) -> None:
        running = self._running
        until = self.backfill.received_until()
        if running is None or until is None:
            return
        for sub in running.model.get("subscribers", []):
            policy = sub.get("backfill", "off")
            if policy == "off":
                continue
            start = self.backfill.mission_start(running) if policy == "mission" else since_ns
            if self.backfill.running(sub["name"], "(policy)"):
                continue  # a flapping link: the job of an earlier reconnection runs on
            runs = self.backfill.gaps(running, sub["name"], start, until)
            if runs:
                log.info(
                    "backfill of %s (%s): %d runs after the outage", sub["name"], policy, len(runs)
                )
                self.backfill.start(
                    sub["name"], runs, backfill_query.spare_budget(running), "(policy)"
                )

    def _sinks(self) -> list[Sink]:
        return [s for s in (self._zenoh, self._tcp, self.record) if s is not None]

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
        request, problem = read_request(payload, MAX_SMALL_BYTES)
        if request is None:
            return {"status": "ERROR", "reason": problem}
        reply = self.dynamic.handle(request, self._running)
        if reply["status"] == "CANCELLED" and self._zenoh is not None:
            self._zenoh.forget(reply["subscriber"])
        return reply

    def _backfill(self, payload: bytes) -> dict[str, Any]:
        def until(running: Running) -> int:
            got = self.backfill.received_until()
            return got if got is not None else time.time_ns()

        return backfill_query.handle(
            payload, self.backfill, lambda: self._running, until, self.dynamic.owner_of
        )

    def _deploy(self, payload: bytes) -> dict[str, Any]:
        with self._deploy_lock:  # one at a time, and a repeated request sees the first's end
            already = self._already_running(payload)
            if already is not None:
                return already
            request = parse_request(payload, self.drone, self._verify)
            if request.model is None:
                if request.reply.get("status") == "UNAUTHORISED":
                    log.warning("deploy refused: %s", request.reply["reason"])
                return request.reply
            return self.deploy(request)

    def _already_running(self, payload: bytes) -> dict[str, Any] | None:
        """The reply to a deploy request that is the one running (same signed
        nonce, sent again by a workbench resuming it): nothing re-applied. A
        replayed nonce stays refused (UNAUTHORISED), but the reply says it is
        what runs (``already_running`` and the ACKED fields), so a resumed
        deploy learns its outcome."""
        running = self._running
        if running is None or not running.meta.nonce:
            return None
        request, _ = read_request(payload, MAX_DEPLOY_BYTES)
        if request is None or request.get("nonce") != running.meta.nonce:
            return None
        sig = request.get("signature")
        if not isinstance(sig, str) or not hmac.compare_digest(
            sig, signature(self._deploy_key, request)
        ):
            return None
        return {
            **self._acked_reply(running, running.config, []),
            "status": "UNAUTHORISED",
            "reason": "the deploy request was already applied (replayed nonce): it is the "
            "deployment running now",
            "already_running": True,
        }

    def _verify(self, request: dict[str, Any]) -> str | None:
        refused = self._nonces.verify(self._deploy_key, request)
        if refused is None:
            log.info(
                "deploy of revision %s signed for %s",
                request.get("revision"),
                str(request.get("deployed_by"))[:64],
            )
        return refused

    def deploy(self, request: DeployRequest) -> dict[str, Any]:
        """Plan ``request.model``, send CONFIG, wait for the ack; the reply."""
        assert request.model is not None
        meta = Deployment.from_request(request.fields)
        try:
            config = self._prepare(request.model, 0, meta)
        except ValueError as exc:
            log.warning("deploy of %s refused: %s", meta.describe(), exc)
            return {
                "status": "REJECTED",
                "reason": str(exc),
                "diagnostics": _located(exc, request.model),
            }
        packed = b""
        if self.config.onboard_over_link:
            packed = onboard.pack(request.model)
            if len(packed) > MAX_ONBOARD_WIRE:
                return _onboard_too_large(len(packed), request.model)
        deadline = time.monotonic() + request.timeout_s
        delay, busy = 0.05, 0
        while True:
            try:
                self.link.send_config(config, max(0.01, deadline - time.monotonic()))
                break
            except LinkDown as exc:
                return {"status": "LINK_DOWN", "reason": str(exc)}
            except TimeoutError as exc:
                return {
                    "status": "TIMEOUT",
                    "reason": f"{exc} within {request.timeout_s} s" + _older_peer(config),
                }
            except ConfigRejected as exc:
                if exc.status != ErrorCode.BUSY or time.monotonic() + delay >= deadline:
                    hint = _older_peer(config) if exc.status == ErrorCode.BAD_FRAME else ""
                    return {
                        "status": "NACK",
                        "reason": str(exc) + hint,
                        "code": exc.status,
                        "busy_retries": busy,
                    }
                # a CONFIG still waits for its switch date: send again after a backoff
                busy += 1
                time.sleep(delay)
                delay = min(delay * 2, 1.0)
        running = self._running
        assert running is not None
        reply = {**self._acked_reply(running, config, request.warnings), "busy_retries": busy}
        if packed:
            reply["onboard"] = self._send_onboard(config.config_id, packed)
        elif self.config.onboard_model is not None:
            reply["onboard"] = self._hand_over(self.config.onboard_model, request.model)
        return reply

    def _send_onboard(self, config_id: int, packed: bytes) -> dict[str, Any]:
        """The acked model to the on-board processes over the link (ONBOARD); what
        each did, from the ONBOARD_ACK, also kept for the status."""
        wait_s = ONBOARD_WAIT_MS / 1000 + 3.0  # their answers, and the link's round trip
        try:
            ack = self.link.send_onboard(Onboard(config_id, packed), wait_s)
            results = onboard.unpack_answers(ack.answers, MAX_ONBOARD_BYTES)
        except (LinkDown, TimeoutError, ValueError) as exc:
            results = {"link": {"ok": False, "problem": f"on-board model not handed over: {exc}"}}
        else:
            if ack.status != 0 and not results:
                results = {"pubbroker": {"ok": False, "problem": f"status {ack.status}"}}
        return self._answers(results)

    def _answers(self, results: dict[str, Any]) -> dict[str, Any]:
        for name, r in results.items():
            if not isinstance(r, dict) or not r.get("ok", False):
                log.warning("deploy: on-board %s did not apply it all: %s", name, _problems(r))
        self._onboard = results
        return results

    def _hand_over(self, path: Path, model: dict[str, Any]) -> dict[str, Any]:
        """The acked model to the on-board processes on this machine (modd.onboard);
        what each did, also kept for the status (the Monitor shows a problem)."""
        try:
            applied = onboard.hand_over(path, model)
        except OSError as exc:
            results = {"handover": {"ok": False, "problem": f"cannot write {path}: {exc}"}}
        else:
            results = onboard.wait_results(path, applied)
        return self._answers(results)

    def _acked_reply(
        self, running: Running, config: Config, warnings: list[dict[str, Any]]
    ) -> dict[str, Any]:
        summary = running.plan.to_json()
        return {
            "status": "ACKED",
            "config_id": config.config_id,
            "epoch_ns": running.epoch_ns,
            "streams_sent": len(config.streams),
            "hyperperiod_s": summary.get("hyperperiod_s"),
            "messages_per_hyperperiod": summary.get("messages_per_hyperperiod"),
            "buffer_sizes": summary.get("buffer_sizes"),
            "predicted_link_bytes_per_s": summary.get("predicted_link_bytes_per_s"),
            "warnings": warnings,
            "deployment": running.meta.as_json(),
        }

    # -- status ------------------------------------------------------------------

    def _deployment_status(self, running: Running | None) -> dict[str, Any]:
        """Which revision runs, deployed when and by whom, and whether it is
        the configured model (docs/subbroker.md, "Status")."""
        meta = running.meta if running else self._meta
        return {
            **meta.as_json(),
            "running": running is not None,
            "differs_from_configured": meta.source != "configured" and self._differs,
        }

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
            "deployment": self._deployment_status(running),
            "bytes_in": stats.bytes_in,
            "bytes_out": stats.bytes_out,
            "data_frames": stats.data_frames,
            "skipped_frames": stats.bad_frames,
            "connects": stats.connects,
            "last_data_ns": stats.last_data_ns,
            "last_error": stats.last_error,
            "delivered": self.delivered,
            # state files that could not be used and were renamed aside (docs/subbroker.md)
            **(
                {"state_files_set_aside": list(self._state.set_aside_files)}
                if self._state.set_aside_files
                else {}
            ),
            "predicted_link_bytes_per_s": predicted,
            "routes": running.fanout.routes() if running else {},
            "dynamic": self.dynamic.names(),
            "tcp": self._tcp.stats() if self._tcp else {},
            "pubbroker": dict(stats.pubbroker),
            **({"sensors": dict(stats.sensors)} if stats.sensors else {}),
            "transport": self.config.transport,
            **({"station": self.config.station} if self.config.station else {}),
            "link_budget": (
                running.plan.budget.to_json()
                if running is not None and running.plan.budget is not None
                else None
            ),
            "radio": self.link.radio_status(),
            **({"onboard": self._onboard} if self._onboard else {}),
        }


def _onboard_too_large(size: int, model: dict[str, Any]) -> dict[str, Any]:
    """The deploy refused before its CONFIG: the on-board model does not fit ONBOARD."""
    why = (
        f"the on-board model is {size} B compressed, more than the {MAX_ONBOARD_WIRE} B "
        "an ONBOARD frame carries: declare fewer instruments or mappings"
    )
    where = "/drone/sensors" if model.get("drone", {}).get("sensors") else ""
    return {"status": "REJECTED", "reason": why, "diagnostics": [Diagnostic(why, where).to_json()]}


def _problems(result: Any) -> str:
    """A process's result's problems, in one line."""
    if not isinstance(result, dict):
        return "unreadable answer"
    found = [str(result["problem"])] if result.get("problem") else []
    found += [f"{s['sensor']}: {s['problem']}" for s in result.get("sensors", ()) if "problem" in s]
    return "; ".join(found) or "not ok"


def _located(exc: ValueError, model: dict[str, Any]) -> list[dict[str, object]]:
    """A planning refusal as diagnostics pinned where the model can be
    changed: the planner's own, the subscription of an over-large topic, else
    the whole model."""
    if isinstance(exc, ModelError) and exc.diagnostics:
        return [d.to_json() for d in exc.diagnostics]
    pointer = ""
    subscribers = getattr(exc, "subscribers", ())
    for i, sub in enumerate(model.get("subscribers", [])):
        if isinstance(sub, dict) and sub.get("name") in subscribers:
            pointer = f"/subscribers/{i}"
            break
    return [Diagnostic(str(exc), pointer).to_json()]


def _older_peer(config: Config) -> str:
    """Why a CONFIG with declared resolutions may be refused: a PubBroker older
    than them reads its resolution field as trailing bytes (docs/protocol.md,
    "Quantised values": BAD_FRAME over tcp, dropped as malformed over udp/serial)."""
    if config.resolutions is None:
        return ""
    return (
        "; this CONFIG declares resolutions (protocol 1 with quantised values): a "
        "PubBroker older than them refuses it; update the PubBroker, or deploy the "
        "model without resolutions"
    )

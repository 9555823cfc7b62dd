"""Delivery of values to subscribers: on zenoh (``modd/<drone>/sub/<name>``)
and over TCP to the subscriber's endpoint (the paper's delivery, one JSON
object per line). Neither ever blocks the link thread: zenoh puts are
non-blocking (congestion control DROP), and each TCP subscriber has its own
sender thread with a bounded queue that drops its oldest value when full.

:class:`SlotDelivery` is the hot path from one DATA slot's windows to those
sinks: fan-out (:mod:`.fanout`), each window encoded once for all its
subscribers (:class:`~.payload.StreamPayload`), one put per subscriber.

>>> tcp = TcpDelivery({"sub_1": ("127.0.0.1", 7401)}, queue_size=10)   # doctest: +SKIP
>>> tcp.deliver(value)                                                # doctest: +SKIP
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol

from modd_contracts import labels
from modd_plan.streams import StreamKey
from modd_plan.windows import EventsWindow, split_window, window_of

from modd.link.receiver import Window

from . import delivery_auth
from .fanout import FanOut, period_us
from .keys import sub_key
from .payload import DeliveredValue, StreamPayload, event_fields, subscriber_prefix

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker.delivery")

#: How long a new TCP delivery connection waits for a subscriber's challenge
#: (delivery_auth); a plain JSON-lines sink that sends none gets values after it.
CHALLENGE_WAIT_S = 0.5


class ZenohDelivery:
    """Puts each value on the subscriber's key, through one declared
    publisher per subscriber (declared on first use)."""

    def __init__(self, session: zenoh.Session, drone: str) -> None:
        self._session = session
        self._drone = drone
        self._publishers: dict[str, Any] = {}
        self._lock = threading.Lock()
        self.delivered = 0

    def _publisher(self, subscriber: str) -> Any:
        import zenoh

        from ..zenoh_recovery import values_publisher

        with self._lock:
            pub = self._publishers.get(subscriber)
            if pub is None:
                pub = values_publisher(  # numbered and cached: readers recover (fleet.md)
                    self._session,
                    sub_key(self._drone, subscriber),
                    zenoh.Encoding.APPLICATION_JSON,
                    zenoh.CongestionControl.DROP,
                )
                self._publishers[subscriber] = pub
            return pub

    def deliver(self, value: DeliveredValue) -> None:
        self.put(value.subscriber, value.to_json())

    def put(self, subscriber: str, payload: bytes) -> None:
        """Put an encoded value (:mod:`.payload`) on the subscriber's key."""
        pub = self._publishers.get(subscriber)  # no lock: a dict read is atomic
        if pub is None:
            pub = self._publisher(subscriber)
        pub.put(payload)
        self.delivered += 1

    def forget(self, subscriber: str) -> None:
        """Undeclare a subscriber's publisher (cancelled or undeployed)."""
        with self._lock:
            pub = self._publishers.pop(subscriber, None)
        if pub is not None:
            pub.undeclare()

    def close(self) -> None:
        for name in list(self._publishers):
            self.forget(name)


class _TcpSender(threading.Thread):
    """Sends one subscriber's values to its endpoint, reconnecting with backoff."""

    def __init__(
        self, name: str, endpoint: tuple[str, int], queue_size: int, key_ref: str = ""
    ) -> None:
        super().__init__(name=f"tcp-delivery-{name}", daemon=True)
        self.endpoint = endpoint
        self.key_ref = key_ref
        self.queue: deque[bytes] = deque()
        self.queue_size = queue_size
        self.cond = threading.Condition()
        self.stopping = False
        self.sent = 0
        self.dropped = 0
        self.connected = False
        self.key: bytes | None = None  # the delivery key, loaded when first asked

    def push(self, line: bytes) -> None:
        with self.cond:
            if len(self.queue) >= self.queue_size:
                self.queue.popleft()
                self.dropped += 1
            self.queue.append(line)
            self.cond.notify()

    def stop(self) -> None:
        with self.cond:
            self.stopping = True
            self.cond.notify()

    def _wait(self, seconds: float) -> bool:
        """Sleep unless stopped; True when stopping."""
        with self.cond:
            self.cond.wait_for(lambda: self.stopping, timeout=seconds)
            return self.stopping

    def run(self) -> None:
        backoff = 0.1
        while not self.stopping:
            try:
                sock = socket.create_connection(self.endpoint, timeout=1.0)
            except OSError:
                if self._wait(backoff):
                    return
                backoff = min(backoff * 2, 2.0)
                continue
            try:
                self._answer_challenge(sock)
            except (OSError, delivery_auth.DeliveryKeyError) as exc:
                log.warning("TCP delivery to %s:%d: handshake failed: %s", *self.endpoint, exc)
                sock.close()
                if self._wait(backoff):
                    return
                backoff = min(backoff * 2, 2.0)
                continue
            backoff = 0.1
            self.connected = True
            log.info("TCP delivery connected to %s:%d", *self.endpoint)
            try:
                self._pump(sock)
            except OSError as exc:
                log.info("TCP delivery to %s:%d lost: %s", *self.endpoint, exc)
            finally:
                self.connected = False
                sock.close()

    def _answer_challenge(self, sock: socket.socket) -> None:
        """Prove the delivery key when the subscriber asks (its first line is a
        challenge); a subscriber that sends nothing within CHALLENGE_WAIT_S asked
        for no proof."""
        sock.settimeout(CHALLENGE_WAIT_S)
        data = b""
        while b"\n" not in data and len(data) < 256:
            try:
                chunk = sock.recv(256 - len(data))
            except TimeoutError:
                if not data:
                    return
                raise
            if not chunk:
                raise ConnectionError("closed by the subscriber")
            data += chunk
        line = data.split(b"\n", 1)[0]
        if not line.startswith(delivery_auth.GREETING):
            raise ConnectionError(f"unexpected first line {line[:40]!r}")
        nonce = line[len(delivery_auth.GREETING) :].decode("ascii", "replace")
        if self.key is None:
            self.key = delivery_auth.load_key(self.key_ref)
        sock.sendall(b"AUTH " + delivery_auth.proof(self.key, nonce).encode() + b"\n")

    def _pump(self, sock: socket.socket) -> None:
        sock.settimeout(5.0)
        while True:
            with self.cond:
                self.cond.wait_for(lambda: self.queue or self.stopping)
                if self.stopping:
                    return
                batch = list(self.queue)
                self.queue.clear()
            try:
                sock.sendall(b"".join(batch))
            except OSError:
                with self.cond:  # put them back, oldest first, within the bound
                    self.queue.extendleft(reversed(batch))
                    while len(self.queue) > self.queue_size:
                        self.queue.popleft()
                        self.dropped += 1
                raise
            self.sent += len(batch)


class TcpDelivery:
    """TCP delivery to the subscribers whose model entry has an endpoint."""

    def __init__(
        self, endpoints: Mapping[str, tuple[str, int]], queue_size: int = 1000, key_ref: str = ""
    ) -> None:
        """``key_ref``: where the delivery key comes from (``[delivery] key``;
        empty: ``$MODD_DELIVERY_KEY``, else the user's delivery.key)."""
        self._queue_size = queue_size
        self._key_ref = key_ref
        self._senders: dict[str, _TcpSender] = {}
        self._lock = threading.Lock()
        self.set_endpoints(endpoints)

    def set_endpoints(self, endpoints: Mapping[str, tuple[str, int]]) -> None:
        """Replace the subscriber -> endpoint map (after a deploy); senders of
        unchanged entries keep their connection and their queue."""
        with self._lock:
            for name, sender in list(self._senders.items()):
                if endpoints.get(name) != sender.endpoint:
                    sender.stop()
                    del self._senders[name]
            for name, endpoint in endpoints.items():
                if name not in self._senders:
                    sender = _TcpSender(name, endpoint, self._queue_size, self._key_ref)
                    sender.start()
                    self._senders[name] = sender

    def deliver(self, value: DeliveredValue) -> None:
        self.put(value.subscriber, value.to_json())

    def put(self, subscriber: str, payload: bytes) -> None:
        """Queue an encoded value for the subscriber, when it has an endpoint."""
        sender = self._senders.get(subscriber)
        if sender is not None:
            sender.push(payload + b"\n")

    def stats(self) -> dict[str, dict[str, int | bool]]:
        return {
            name: {"connected": s.connected, "sent": s.sent, "dropped": s.dropped}
            for name, s in self._senders.items()
        }

    def close(self) -> None:
        with self._lock:
            senders = list(self._senders.values())
            self._senders.clear()
        for s in senders:
            s.stop()
        for s in senders:
            s.join(timeout=2.0)


def tcp_endpoints(model: Mapping[str, object]) -> dict[str, tuple[str, int]]:
    """Subscriber name -> endpoint, for the subscribers that have one."""
    out: dict[str, tuple[str, int]] = {}
    subs = model.get("subscribers", [])
    assert isinstance(subs, list)
    for sub in subs:
        ep = sub.get("endpoint")
        if ep:
            out[sub["name"]] = (str(ep["host"]), int(ep["port"]))
    return out


class Sink(Protocol):
    """Where encoded values go (:class:`ZenohDelivery`, :class:`TcpDelivery`)."""

    def put(self, subscriber: str, payload: bytes) -> None: ...


#: Was this window (subscriber, stream, start, end) delivered by a backfill already?
Filled = Callable[[str, StreamKey, int, int], bool]


class SlotDelivery:
    """One running config's way from the windows of a DATA slot to the sinks.

    Everything that does not change between slots is prepared once: the
    sent streams' value kinds, each routed stream's constant payload part
    (on first use) and each subscriber's payload prefix. Per slot it costs
    the fan-out, one encoding per window due and, per subscriber, one bytes
    concatenation and one put.
    """

    def __init__(
        self,
        fanout: FanOut,
        config_id: int,
        epoch_ns: int,
        topic_info: Mapping[str, tuple[str, str]],
        drone: str | None = None,
    ) -> None:
        """``drone``: the windows carry their identity (docs/fleet.md); None: they do not."""
        self.drone = drone
        self.fanout = fanout
        self._config_id = config_id
        self._epoch_ns = epoch_ns
        self._topic_info = topic_info
        self._kinds = [(s.aggregation, topic_info[s.topic][1]) for s in fanout.sent]
        self._sent = frozenset(fanout.sent)
        #: event streams: a window without an event is not delivered
        self._events = frozenset(s for s in fanout.sent if labels.is_event(s.aggregation))
        self._payloads: dict[StreamKey, tuple[StreamPayload, int]] = {}
        self._prefixes: dict[str, bytes] = {}

    def _payload(self, stream: StreamKey) -> tuple[StreamPayload, int]:
        unit = self._topic_info[stream.topic][0]
        period_text = stream.key.rsplit("/", 1)[1]
        period = period_us(stream)
        ident = None if self.drone is None else (self.drone, self._epoch_ns, period * 1000)
        payload = StreamPayload(
            stream.topic, stream.aggregation, period_text, unit, self._config_id, ident
        )
        entry = (payload, period)
        self._payloads[stream] = entry
        return entry

    def _prefix(self, subscriber: str) -> bytes:
        prefix = self._prefixes[subscriber] = subscriber_prefix(subscriber)
        return prefix

    def deliver(
        self,
        windows: Sequence[Window],
        sinks: Sequence[Sink],
        filled: Filled | None = None,
        derived: Callable[[tuple[StreamKey, int, int]], None] | None = None,
    ) -> int:
        """Deliver what the slot of ``windows`` completes; the number of values
        (one per subscriber and window, whatever the number of sinks). A window
        ``filled`` says a backfill delivered already (a NACK's resend that comes
        after the backfill it raced) is not delivered twice. ``derived`` is told
        each derived window delivered (stream, start, end: the window record's)."""
        first = windows[0]
        slot, end_ns, epoch = first.slot, first.end_ns, self._epoch_ns
        date_us = (end_ns - epoch) // 1000
        kinds = self._kinds
        by_id = {w.stream: window_of(w.value, *kinds[w.stream]) for w in windows}
        now = time.time_ns()
        payloads, prefixes, sent = self._payloads, self._prefixes, self._sent
        events_ = self._events
        # an empty slot (a datagram link carries it; tcp does not send it) completes
        # derived windows but delivers no sent stream's window
        empty = all(v is None for v in by_id.values())
        count = 0
        for out in self.fanout.on_slot(slot, date_us, by_id):
            if empty and out.stream in sent or out.value is None and out.stream in events_:
                continue
            payload, period = payloads.get(out.stream) or self._payload(out.stream)
            value, samples = split_window(out.stream.aggregation, out.value)
            end_ns = epoch + out.end_us * 1000  # a derived window's end, not the slot's
            start_ns = end_ns - period * 1000
            if derived is not None and out.stream not in sent:
                derived((out.stream, start_ns, end_ns))
            events = ""
            if isinstance(out.value, EventsWindow):
                events = event_fields(out.value.event_ns(start_ns), out.value.coalesced)
            tail = payload.tail(slot, start_ns, end_ns, value, samples, now, events)
            for sub in out.subscribers:
                if filled is not None and filled(sub, out.stream, start_ns, end_ns):
                    continue
                data = (prefixes.get(sub) or self._prefix(sub)) + tail
                for sink in sinks:
                    sink.put(sub, data)
                count += 1
        return count

"""Python publisher client: hands samples to the on-board PubBroker's ingress (docs/ingress.md).

Same contract as the C++ client (runtime/cpp/include/modd/client/publisher.hpp):

* the broker sends the drone's topic catalogue on connection (the constructor waits up to
  ``connect_wait_s`` for it); with it, ``publish`` refuses at the call (returns False, counts
  it, logs it once per topic and reason, keeps the words in ``last_error``) an unknown or
  ambiguous topic name, a value that does not fit the declared type, a timestamp beyond the
  broker's bounds; a short name (a dotted suffix of one topic's full name) is accepted when
  unambiguous; any number is converted to the declared type (``modd.ingress.convert``);
* ``publish`` never blocks on the network and never raises; a bounded queue is sent in
  batches by a background thread that reconnects by itself (the first retry at once);
* ``stats()`` tells apart accepted at the call (published), written to the socket (sent),
  acknowledged on disk (on_disk) and refused by the broker (rejected_by_broker); samples
  sent but not yet on disk are sent again after a reconnection (at least once).

Example::

    with Publisher("pub_1", "unix:/tmp/modd/usv/ingress.sock") as pub:
        pub.publish("accel_z", time.time_ns(), 9.81)
        pub.wait_on_disk(2.0)
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from modd.ingress import (
    INGRESS_VERSION,
    MAX_FRAME,
    Ack,
    Catalogue,
    Number,
    OutOfRange,
    Reject,
    convert,
    decode_reply,
    encode_health,
    encode_hello,
    encode_register,
    encode_samples,
    frame,
    resolve,
)
from modd.link.codec import FrameSplitter
from modd.link.frames import ProtocolError, SensorHealth, ValueType

__all__ = [
    "INGRESS_VERSION",
    "Publisher",
    "PublisherStats",
    "connect",
    "encode_hello",
    "encode_register",
    "encode_samples",
    "frame",
]
log = logging.getLogger("modd.publisher")
Record = tuple[int, int, Number]


def connect(address: str, timeout: float = 2.0) -> socket.socket:
    """`unix:PATH` or `tcp:HOST:PORT`."""
    if address.startswith("unix:"):
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.settimeout(timeout)
        try:
            s.connect(address[5:])
        except OSError:
            s.close()
            raise
    elif address.startswith("tcp:"):
        host, _, port = address[4:].rpartition(":")
        s = socket.create_connection((host, int(port)), timeout=timeout)
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    else:
        raise ValueError(f"ingress address {address!r} is neither unix:PATH nor tcp:HOST:PORT")
    s.settimeout(None)
    return s


@dataclass
class PublisherStats:
    published: int = 0  # accepted at the call into the queue
    sent: int = 0  # written to the broker's socket (replays included)
    on_disk: int = 0  # acknowledged by the broker as in the archive file
    rejected_by_broker: int = 0  # refused by the broker (REJECT), reason logged
    dropped_queue_full: int = 0
    dropped_bad_topic: int = 0  # refused at the call, every reason (the four below)
    refused_unknown_topic: int = 0
    refused_wrong_type: int = 0
    refused_out_of_range: int = 0  # includes NaN/inf
    refused_timestamp: int = 0
    dropped_at_close: int = 0  # still queued when closed with no broker
    replayed: int = 0  # sent again after a reconnection
    replay_dropped: int = 0  # not yet on disk but pushed out of the replay buffer
    connects: int = 0


class Publisher:
    def __init__(
        self,
        name: str,
        ingress: str,
        queue_capacity: int = 65536,
        batch_max: int = 256,
        reconnect_s: float = 0.2,
        connect_wait_s: float = 1.0,
        replay_capacity: int = 65536,
        on_error: Callable[[str, str], None] | None = None,
    ) -> None:
        self.name = name
        self.ingress = ingress
        self._capacity = queue_capacity
        self._batch_max = batch_max
        self._reconnect_s = reconnect_s
        self._replay_capacity = replay_capacity
        self._on_error = on_error
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._idle = threading.Condition(self._lock)
        self._queue: deque[Record] = deque()
        self._resend: deque[Record] = deque()
        self._unacked: deque[tuple[int, Record]] = deque()
        self._ids: dict[str, int] = {}  # name as given -> local id
        self._full_ids: dict[str, int] = {}
        self._types: list[ValueType] = []
        self._names: list[str] = []
        self._declared: dict[str, ValueType] = {}
        self._catalogue: Catalogue | None = None
        self._reported: set[tuple[str, str]] = set()
        self._stats = PublisherStats()
        self.last_error = ""
        self._stopping = False
        self._in_flight = False
        self._connected = False
        self._conn_sent = 0
        self._conn_archived = 0
        self._sock: socket.socket | None = None
        self._health: bytes | None = None  # a HEALTH frame to send (the latest replaces)
        self._thread = threading.Thread(target=self._run, name=f"modd-pub-{name}", daemon=True)
        self._thread.start()
        with self._lock:
            self._idle.wait_for(lambda: self._catalogue is not None, connect_wait_s)

    def __enter__(self) -> Publisher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def declare(self, topic: str, vtype: ValueType | str) -> None:
        t = ValueType.parse(vtype) if isinstance(vtype, str) else vtype
        with self._lock:
            self._declared[topic] = t

    def _report(self, topic: str, why: str) -> None:
        key = (topic, why.split(":", 1)[0])
        if key in self._reported:
            return
        self._reported.add(key)
        if self._on_error is not None:
            self._on_error(topic, why)
        else:
            log.warning("publisher %s: %s", self.name, why)

    def _refuse(self, topic: str, counter: str, why: str) -> bool:
        setattr(self._stats, counter, getattr(self._stats, counter) + 1)
        self._stats.dropped_bad_topic += 1
        self.last_error = why
        self._report(topic, why)
        return False

    def _local_id(self, topic: str, value: Number) -> int | str:
        """The local id, or the refusal counter and message as 'counter|why'."""
        lid = self._ids.get(topic)
        if lid is not None:
            return lid
        cat = self._catalogue
        full = topic
        if cat is not None:
            try:
                full = resolve(cat, topic)
            except KeyError as e:
                return "refused_unknown_topic|" + str(e.args[0])
        declared = self._declared.get(full, self._declared.get(topic))
        if cat is not None and full in cat.topics:
            vtype = cat.topics[full]
            if declared is not None and declared != vtype:
                return (
                    f"refused_wrong_type|wrong type: topic {full!r} is {vtype.label} on drone "
                    f"{cat.drone!r}, declared {declared.label}"
                )
        elif declared is not None:
            vtype = declared
        else:
            vtype = (
                ValueType.BOOL
                if isinstance(value, bool)
                else ValueType.INT
                if isinstance(value, int)
                else ValueType.FLOAT64
            )
        lid = self._full_ids.get(full)
        if lid is None:
            lid = self._full_ids[full] = len(self._names)
            self._names.append(full)
            self._types.append(vtype)
        self._ids[topic] = lid
        return lid

    def publish(self, topic: str, timestamp_ns: int, value: Number) -> bool:
        """Queues one sample; False (counted, why in `last_error`) if refused or queue full."""
        try:
            with self._lock:
                lid = self._local_id(topic, value)
                if isinstance(lid, str):
                    counter, why = lid.split("|", 1)
                    return self._refuse(topic, counter, why)
                full, vtype = self._names[lid], self._types[lid]
                try:
                    v = convert(value, vtype)
                except OutOfRange as e:
                    why = f"value out of range: {e} for topic {full!r} ({vtype.label})"
                    return self._refuse(topic, "refused_out_of_range", why)
                cat = self._catalogue
                ts = int(timestamp_ns)
                if cat is not None:
                    ahead = ts - time.time_ns()
                    if (cat.max_future_ms and ahead > cat.max_future_ms * 1_000_000) or (
                        cat.max_past_ms and -ahead > cat.max_past_ms * 1_000_000
                    ):
                        return self._refuse(
                            topic,
                            "refused_timestamp",
                            f"topic {full!r}: timestamp out of bounds: {ts} ns is "
                            f"{abs(ahead) / 1e9:.3g} s "
                            f"{'ahead of' if ahead > 0 else 'behind'} this clock (bounds "
                            f"{cat.max_future_ms} ms ahead, {cat.max_past_ms} ms behind)",
                        )
                if len(self._queue) >= self._capacity:
                    self._stats.dropped_queue_full += 1
                    return False
                self._queue.append((lid, ts, v))
                self._stats.published += 1
                self._wake.notify()
            return True
        except Exception:  # never raise into the caller's sensor loop
            return False

    def report_health(self, sensors: Sequence[SensorHealth]) -> None:
        """Tells the broker these instruments' health (docs/ingress.md, HEALTH); sent with
        the next write, replacing a report not yet sent. Needs a broker that knows HEALTH."""
        frame = encode_health(sensors)
        with self._lock:
            self._health = frame
            self._wake.notify()

    def _drained(self) -> bool:
        return not self._queue and not self._resend and not self._in_flight

    def flush(self, timeout: float = 5.0) -> bool:
        """Waits until everything queued was written to the broker's socket."""
        with self._lock:
            self._wake.notify()
            return self._idle.wait_for(self._drained, timeout)

    def wait_on_disk(self, timeout: float = 5.0) -> bool:
        """Waits until every sample sent is acknowledged on disk (or refused) by the broker."""
        with self._lock:
            self._wake.notify()
            return self._idle.wait_for(lambda: self._drained() and not self._unacked, timeout)

    def close(self, timeout: float = 2.0) -> None:
        end = time.monotonic() + timeout
        self.flush(timeout)
        if self._catalogue is not None:
            self.wait_on_disk(max(0.0, end - time.monotonic()))
        with self._lock:
            self._stopping = True
            self._wake.notify()
        self._thread.join(timeout + 1.0)
        self._disconnect()

    @property
    def connected(self) -> bool:
        with self._lock:
            return self._connected

    @property
    def catalogue(self) -> Catalogue | None:
        with self._lock:
            return self._catalogue

    def stats(self) -> PublisherStats:
        with self._lock:
            return PublisherStats(**vars(self._stats))

    def _disconnect(self) -> None:
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.close()
        self._sock = None
        with self._lock:
            self._connected = False

    def _connect(self) -> bool:
        try:
            self._sock = connect(self.ingress)
            self._sock.sendall(encode_hello(self.name))
        except OSError:
            self._disconnect()
            return False
        self._sock.setblocking(False)
        with self._lock:
            self._connected = True
            self._stats.connects += 1
            self._conn_sent = self._conn_archived = 0
            # Sent but not known on disk: sent again first (a broker restart loses its buffers).
            self._stats.replayed += len(self._unacked)
            self._resend.extendleft(rec for _, rec in reversed(self._unacked))
            self._unacked.clear()
        return True

    def _on_reply(self, reply: Catalogue | Ack | Reject) -> None:
        with self._lock:
            if isinstance(reply, Catalogue):
                self._catalogue = reply
            elif isinstance(reply, Ack):
                while self._unacked and self._unacked[0][0] < reply.settled:
                    self._unacked.popleft()
                if reply.archived > self._conn_archived:
                    self._stats.on_disk += reply.archived - self._conn_archived
                    self._conn_archived = reply.archived
            else:
                self._stats.rejected_by_broker += reply.count
                topic = self._names[reply.local_id] if reply.local_id < len(self._names) else "?"
                why = f"refused by the broker ({reply.reason_text}): {reply.detail}"
                self.last_error = why
                self._report(topic, f"broker {reply.reason}: {why}")
            self._idle.notify_all()

    def _read_replies(self, splitter: FrameSplitter) -> bool:
        assert self._sock is not None
        while True:
            try:
                data = self._sock.recv(65536)
            except (BlockingIOError, InterruptedError):
                return True
            except OSError:
                return False
            if not data:
                return False
            try:
                for f in splitter.feed(data):
                    self._on_reply(decode_reply(f.type, f.body))
            except ProtocolError as e:
                log.warning("publisher %s: bad reply from the broker: %s", self.name, e)
                return False

    def _send(self, data: bytes) -> bool:
        assert self._sock is not None
        view = memoryview(data)
        while view:
            try:
                n = self._sock.send(view)
            except (BlockingIOError, InterruptedError):
                time.sleep(0.001)
                continue
            except OSError:
                return False
            view = view[n:]
        return True

    def _run(self) -> None:
        registered = 0
        next_attempt = 0.0  # the first attempt, and the first after a loss, at once
        splitter = FrameSplitter(MAX_FRAME)
        while True:
            with self._lock:
                self._wake.wait_for(
                    lambda: (
                        self._stopping
                        or (
                            bool(self._queue or self._resend or self._health)
                            and self._sock is not None
                        )
                    ),
                    0.02,
                )
                if self._stopping and (self._sock is None or not (self._queue or self._resend)):
                    if self._sock is None:
                        self._stats.dropped_at_close += len(self._queue) + len(self._resend)
                    self._queue.clear()
                    self._resend.clear()
                    self._idle.notify_all()
                    return
            if self._sock is None:
                if time.monotonic() < next_attempt:
                    continue
                if not self._connect():
                    next_attempt = time.monotonic() + self._reconnect_s
                    continue
                registered = 0
                splitter = FrameSplitter(MAX_FRAME)
            if not self._read_replies(splitter):
                self._disconnect()
                next_attempt = 0.0
                continue
            with self._lock:
                health, self._health = self._health, None
            if health is not None and not self._send(health):
                self._disconnect()
                next_attempt = 0.0
                continue
            with self._lock:
                batch: list[Record] = []
                while self._resend and len(batch) < self._batch_max:
                    batch.append(self._resend.popleft())
                while self._queue and len(batch) < self._batch_max:
                    batch.append(self._queue.popleft())
                if not batch:
                    self._in_flight = False
                    self._idle.notify_all()
                    continue
                self._in_flight = True
                names = list(self._names)
                types = list(self._types)
            out = b"".join(
                encode_register(i, types[i], names[i]) for i in range(registered, len(names))
            )
            out += encode_samples(batch, types)
            if not self._send(out):
                self._disconnect()
                with self._lock:
                    self._resend.extendleft(reversed(batch))  # sent again, first
                    self._in_flight = False
                next_attempt = 0.0
                continue
            registered = len(names)
            with self._lock:
                self._stats.sent += len(batch)
                for rec in batch:
                    if len(self._unacked) >= self._replay_capacity:
                        self._unacked.popleft()
                        self._stats.replay_dropped += 1
                    self._unacked.append((self._conn_sent, rec))
                    self._conn_sent += 1
                self._in_flight = False
                if not self._queue and not self._resend:
                    self._idle.notify_all()

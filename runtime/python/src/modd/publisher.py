"""Python publisher client: hands samples to the on-board PubBroker's ingress (docs/ingress.md).

Same behaviour as the C++ client (runtime/cpp/include/modd/client/publisher.hpp):
``publish`` never blocks on the network and never raises; it appends to a bounded queue
that a background thread sends in batches, reconnecting and re-registering topics by
itself. A full queue drops the sample and counts it in ``stats()``.

Example::

    with Publisher("pub_1", "unix:/tmp/modd/usv/ingress.sock") as pub:
        pub.declare("usv.accelerometer.accel_x", "float32")
        pub.publish("usv.accelerometer.accel_x", time.time_ns(), 0.25)
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

from modd.link.codec import string, varint
from modd.link.frames import ValueType

INGRESS_VERSION = 1
HELLO, REGISTER, SAMPLES = 0x01, 0x02, 0x03
_VALUE_FORMAT = {ValueType.FLOAT32: "<f", ValueType.FLOAT64: "<d", ValueType.INT: "<q",
                 ValueType.BOOL: "<B"}

Number = float | int | bool


def frame(mtype: int, body: bytes) -> bytes:
    return varint(len(body) + 1) + bytes([mtype]) + body


def encode_hello(publisher: str) -> bytes:
    return frame(HELLO, bytes([INGRESS_VERSION]) + string(publisher))


def encode_register(local_id: int, vtype: ValueType, topic: str) -> bytes:
    return frame(REGISTER, varint(local_id) + bytes([vtype]) + string(topic))


def encode_samples(records: Sequence[tuple[int, int, Number]], types: Sequence[ValueType]) -> bytes:
    """records: (local id, timestamp ns, value); types[local id] gives each value's encoding."""
    parts = [varint(len(records))]
    for lid, ts, value in records:
        t = types[lid]
        v: Number = (1 if value else 0) if t == ValueType.BOOL else value
        parts.append(varint(lid) + struct.pack("<q", ts) + struct.pack(_VALUE_FORMAT[t], v))
    return frame(SAMPLES, b"".join(parts))


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
    published: int = 0  # accepted into the queue
    sent: int = 0  # written to the broker's socket
    dropped_queue_full: int = 0
    dropped_bad_topic: int = 0  # value kind clashes with the topic's type
    dropped_at_close: int = 0  # still queued when closed with no broker
    connects: int = 0


class Publisher:
    def __init__(self, name: str, ingress: str, queue_capacity: int = 65536,
                 batch_max: int = 256, reconnect_s: float = 0.2) -> None:
        self.name = name
        self.ingress = ingress
        self._capacity = queue_capacity
        self._batch_max = batch_max
        self._reconnect_s = reconnect_s
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._idle = threading.Condition(self._lock)
        self._queue: deque[tuple[int, int, Number]] = deque()
        self._ids: dict[str, int] = {}
        self._types: list[ValueType] = []
        self._names: list[str] = []
        self._stats = PublisherStats()
        self._stopping = False
        self._in_flight = False
        self._connected = False
        self._sock: socket.socket | None = None
        self._thread = threading.Thread(target=self._run, name=f"modd-pub-{name}", daemon=True)
        self._thread.start()

    def __enter__(self) -> Publisher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def declare(self, topic: str, vtype: ValueType | str) -> None:
        t = ValueType.parse(vtype) if isinstance(vtype, str) else vtype
        with self._lock:
            if topic not in self._ids:
                self._ids[topic] = len(self._names)
                self._names.append(topic)
                self._types.append(t)

    def publish(self, topic: str, timestamp_ns: int, value: Number) -> bool:
        """Queues one sample; False (and counted) if the queue is full or the type clashes."""
        try:
            with self._lock:
                lid = self._ids.get(topic)
                if lid is None:
                    inferred = (ValueType.BOOL if isinstance(value, bool) else
                                ValueType.INT if isinstance(value, int) else ValueType.FLOAT64)
                    lid = self._ids[topic] = len(self._names)
                    self._names.append(topic)
                    self._types.append(inferred)
                t = self._types[lid]
                is_float = t in (ValueType.FLOAT32, ValueType.FLOAT64)
                if is_float and not isinstance(value, int | float):
                    self._stats.dropped_bad_topic += 1
                    return False
                if not is_float and isinstance(value, float):
                    self._stats.dropped_bad_topic += 1
                    return False
                if len(self._queue) >= self._capacity:
                    self._stats.dropped_queue_full += 1
                    return False
                self._queue.append((lid, int(timestamp_ns), value))
                self._stats.published += 1
                self._wake.notify()
            return True
        except Exception:  # never raise into the caller's sensor loop
            return False

    def flush(self, timeout: float = 5.0) -> bool:
        """Waits until everything queued was written to the broker's socket."""
        with self._lock:
            self._wake.notify()
            return self._idle.wait_for(lambda: not self._queue and not self._in_flight, timeout)

    def close(self, timeout: float = 2.0) -> None:
        self.flush(timeout)
        with self._lock:
            self._stopping = True
            self._wake.notify()
        self._thread.join(timeout + 1.0)
        self._disconnect()

    @property
    def connected(self) -> bool:
        with self._lock:
            return self._connected

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
        with self._lock:
            self._connected = True
            self._stats.connects += 1
        return True

    def _run(self) -> None:
        batch: list[tuple[int, int, Number]] = []
        registered = 0
        while True:
            with self._lock:
                if not batch:
                    self._wake.wait_for(lambda: self._stopping or bool(self._queue))
                    if not self._queue and self._stopping:
                        break
                    while self._queue and len(batch) < self._batch_max:
                        batch.append(self._queue.popleft())
                self._in_flight = True
                if self._stopping and self._sock is None:
                    self._stats.dropped_at_close += len(batch) + len(self._queue)
                    self._queue.clear()
                    self._in_flight = False
                    self._idle.notify_all()
                    break
                names = list(self._names)
                types = list(self._types)
            if self._sock is None:
                if not self._connect():
                    time.sleep(self._reconnect_s)
                    continue
                registered = 0
            out = b"".join(encode_register(i, types[i], names[i])
                           for i in range(registered, len(names)))
            out += encode_samples(batch, types)
            try:
                assert self._sock is not None
                self._sock.sendall(out)
            except OSError:
                self._disconnect()
                continue  # keep the batch; send it again after reconnecting
            registered = len(names)
            with self._lock:
                self._stats.sent += len(batch)
                batch = []
                self._in_flight = False
                if not self._queue:
                    self._idle.notify_all()

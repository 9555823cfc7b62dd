"""The Python subscriber API: the values a SubBroker delivers on zenoh.

Iterate, give a callback, or collect into a pandas DataFrame::

    import modd
    for sample in modd.subscribe("usv", "sub_1"):              # blocks
        print(sample.end_ns, sample.value, sample.count)

    sub = modd.subscribe("usv", "sub_5", callback=print)       # zenoh's thread calls print
    df = modd.subscribe("usv", "sub_3").dataframe(duration_s=10)
    sub.latest            # the newest live value: a backfilled one never replaces it

    # a dynamic subscription (cancelled when closed)
    with modd.subscribe_dynamic("usv", "usv.accelerometer.accel_x", "4.0", "AVERAGE") as sub:
        first = sub.get(timeout_s=10)

By default the session connects to the SubBroker at ``tcp/127.0.0.1:7447``
(``MODD_ZENOH_CONNECT`` or ``connect=`` to change it). Each value is a
:class:`~modd.subbroker.payload.DeliveredValue`; docs/subbroker.md gives its fields.
"""

from __future__ import annotations

import logging
import os
import queue
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, fields
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from modd_contracts.types_gen import DeliveredValueFields

from .subbroker.keys import sub_key, subscribe_key
from .subbroker.payload import DeliveredValue
from .subbroker.seen import Seen, identity
from .zenoh_recovery import values_subscriber

if TYPE_CHECKING:
    import pandas  # type: ignore[import-untyped]
    import zenoh

Sample = DeliveredValue
log = logging.getLogger("modd.subscriber")

#: Values kept for an iterating consumer that falls behind (the oldest go first).
QUEUE_LIMIT = 100_000


class Subscription:
    """Values of one subscriber key. Iterate it, call :meth:`get`, or read a
    DataFrame; close it (or use ``with``) to stop."""

    def __init__(
        self,
        session: zenoh.Session,
        key: str,
        callback: Callable[[DeliveredValue], None] | None = None,
        own_session: bool = False,
        on_close: Callable[[], None] | None = None,
    ) -> None:
        self.key = key
        #: The SubBroker's reply to a dynamic subscription (``subscribe_dynamic``), else None.
        self.accepted: dict[str, Any] | None = None
        self.dropped = 0
        self.malformed = 0
        #: Windows received again (same identity, another station: docs/fleet.md), not given.
        self.duplicates = 0
        #: The newest live value (by window end), None before the first: a backfilled
        #: window (historical, ``backfilled`` True) never becomes it, however late it comes.
        self.latest: DeliveredValue | None = None
        self._seen = Seen()
        self._session = session
        self._own_session = own_session
        self._callback = callback
        self._queue: queue.Queue[DeliveredValue | None] = queue.Queue(QUEUE_LIMIT)
        self._on_close = on_close
        self._closed = False
        # what a break in the mesh kept from it, it asks the publishers for (fleet.md)
        self._sub = values_subscriber(session, key, self._receive)

    def _receive(self, sample: zenoh.Sample) -> None:
        """One payload: a malformed one is dropped alone and counted
        (``malformed``), never raised into zenoh's thread nor kept."""
        try:
            value = DeliveredValue.from_json(sample.payload.to_bytes())
        except ValueError as exc:  # json's errors and over-deep input are ValueErrors
            self.malformed += 1
            if self.malformed <= 10 or self.malformed % 1000 == 0:
                log.warning(
                    "%s: malformed value dropped (%d so far): %s", self.key, self.malformed, exc
                )
            return
        ident = identity(value)
        if ident is not None and not self._seen.first(ident):
            self.duplicates += 1
            return
        if not value.backfilled and (self.latest is None or value.end_ns > self.latest.end_ns):
            self.latest = value
        if self._callback is not None:
            try:
                self._callback(value)
            except Exception:  # the user's callback: reported, the subscription goes on
                log.exception("%s: the callback raised", self.key)
            return
        while True:
            try:
                self._queue.put_nowait(value)
                return
            except queue.Full:
                try:
                    self._queue.get_nowait()
                    self.dropped += 1
                except queue.Empty:
                    pass

    def get(self, timeout_s: float | None = None) -> DeliveredValue | None:
        """The next value, or None after ``timeout_s`` or once closed."""
        try:
            return self._queue.get(timeout=timeout_s)
        except queue.Empty:
            return None

    def __iter__(self) -> Iterator[DeliveredValue]:
        while not self._closed:
            value = self._queue.get()
            if value is None:
                return
            yield value

    def collect(self, count: int | None = None, duration_s: float | None = None) -> list[Sample]:
        """Values until ``count`` arrived or ``duration_s`` passed (one of them needed)."""
        if count is None and duration_s is None:
            raise ValueError("give count, duration_s or both")
        deadline = time.monotonic() + duration_s if duration_s is not None else None
        out: list[DeliveredValue] = []
        while count is None or len(out) < count:
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                break
            value = self.get(timeout_s=left)
            if value is None:
                if self._closed:
                    break
                continue
            out.append(value)
        return out

    def dataframe(
        self, count: int | None = None, duration_s: float | None = None
    ) -> pandas.DataFrame:
        """:meth:`collect` as a DataFrame, one row per window (see :func:`to_dataframe`)."""
        return to_dataframe(self.collect(count, duration_s))

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._sub.undeclare()
        if self._on_close is not None:
            self._on_close()
        self._queue.put(None)
        if self._own_session:
            self._session.close()  # type: ignore[no-untyped-call]

    def __enter__(self) -> Subscription:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def to_dataframe(values: list[DeliveredValue]) -> pandas.DataFrame:
    """Rows of delivered values; ``start``, ``end`` and ``delivered`` as UTC
    timestamps, ``backfilled`` True for values filled from the drone's archive,
    the other fields as they are."""
    import pandas as pd

    # The contract's fields in its order, the times without their _ns suffix.
    columns = {f.name: f.name.removesuffix("_ns") for f in fields(DeliveredValueFields)}
    rows: list[dict[str, Any]] = [{columns[k]: x for k, x in asdict(v).items()} for v in values]
    df = pd.DataFrame(rows, columns=list(columns.values()))
    for field, col in columns.items():
        if field != col:
            df[col] = pd.to_datetime(df[col], unit="ns", utc=True)
    return df


def _session(
    session: zenoh.Session | None,
    connect: str | None,
    credentials: str | os.PathLike[str] | None = None,
) -> tuple[zenoh.Session, bool]:
    if session is not None:
        return session, False
    from .zenoh_session import client_settings, open_session, wait_connected

    opened = open_session(client_settings(connect, credentials))
    wait_connected(opened, timeout_s=2.0)
    return opened, True


def subscribe(
    drone: str,
    subscriber: str,
    callback: Callable[[DeliveredValue], None] | None = None,
    *,
    connect: str | None = None,
    session: zenoh.Session | None = None,
    credentials: str | os.PathLike[str] | None = None,
) -> Subscription:
    """Subscribe to the values a SubBroker delivers to ``subscriber`` of ``drone``.

    With ``callback``, each value is passed to it on zenoh's thread (keep it
    short); without, iterate the returned :class:`Subscription`.
    ``credentials``: the ``user:password`` file to connect with (a viewer's,
    ``viewer.cred``), else ``$MODD_ZENOH_CREDENTIALS`` (docs/security.md).
    """
    s, own = _session(session, connect, credentials)
    return Subscription(s, sub_key(drone, subscriber), callback, own_session=own)


def subscribe_dynamic(
    drone: str,
    topic: str,
    period_s: str | Fraction,
    aggregation: str,
    callback: Callable[[DeliveredValue], None] | None = None,
    *,
    connect: str | None = None,
    session: zenoh.Session | None = None,
    timeout_s: float = 5.0,
    credentials: str | os.PathLike[str] | None = None,
) -> Subscription:
    """Ask the SubBroker for a new (topic, period, aggregation) while the
    mission runs; raises :class:`NotAvailable` with the SubBroker's reason
    when the running plan cannot serve it, NoReply when no SubBroker answers.
    Closing the subscription cancels it. Only the ``backend`` identity may
    ask (``credentials``, docs/security.md)."""
    from .subbroker.client import request

    s, own = _session(session, connect, credentials)
    period = period_s if isinstance(period_s, str) else str(float(period_s))
    try:
        reply = request(
            s,
            subscribe_key(drone),
            {"topic": topic, "period_s": period, "aggregation": aggregation},
            timeout_s,
        )
        if reply.get("status") != "ACCEPTED":
            raise NotAvailable(str(reply.get("reason", reply)))
    except BaseException:
        if own:
            s.close()  # type: ignore[no-untyped-call]
        raise

    def cancel() -> None:
        try:
            request(
                s,
                subscribe_key(drone),
                {"action": "cancel", "subscriber": reply["subscriber"]},
                timeout_s,
            )
        except Exception as exc:  # the SubBroker may be gone: nothing left to cancel
            log.info("cancel of %s: %s", reply["subscriber"], exc)

    sub = Subscription(s, str(reply["key"]), callback, own_session=own, on_close=cancel)
    sub.accepted = reply
    return sub


class NotAvailable(RuntimeError):
    """The SubBroker cannot serve a dynamic subscription; the message says why."""

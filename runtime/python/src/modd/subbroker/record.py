"""The base-station record: every value the SubBroker delivers (live and
backfilled), in one MCAP file per drone and mission (docs/subbroker.md,
"Base-station record"), one channel per subscriber key
(``modd/<drone>/sub/<subscriber>``), JSON messages (the delivered payload),
``log_time`` = the window's end on the drone's clock. After a backfill the
base station so holds a gap-free copy of every subscription.

A :class:`~.delivery.Sink`: the link thread calls :meth:`put`; the file is
finished (summary, footer) at :meth:`close` and when the mission changes.

>>> rec = BaseRecord(Path("/tmp/records"), "usv")    # doctest: +SKIP
>>> rec.begin("scenario1", 1_763_700_000_000_000_000)  # doctest: +SKIP
"""

from __future__ import annotations

import json
import logging
import re
import threading
import time
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from .keys import sub_key

if TYPE_CHECKING:
    from mcap.writer import Writer

log = logging.getLogger("modd.subbroker.record")

_SAFE = re.compile(r"[^A-Za-z0-9_.-]")
# One JSON type per field, as Foxglove and Lichtblick read schemas (a field
# without a type makes them drop the channel); a null or an ALL window's list
# still travels in "value".
_SCHEMA = json.dumps({"type": "object", "properties": {
    "value": {"type": "number"}, "start_ns": {"type": "integer"},
    "end_ns": {"type": "integer"}, "backfilled": {"type": "boolean"}}}).encode()


class BaseRecord:
    """Writes one MCAP per drone and mission under ``root/<drone>/``."""

    def __init__(self, root: Path, drone: str) -> None:
        self.root = root
        self.drone = drone
        self._lock = threading.Lock()
        self._file: IO[bytes] | None = None
        self._writer: Writer | None = None
        self._schema = 0
        self._channels: dict[str, int] = {}
        self._mission: tuple[str, int] | None = None
        self.path: Path | None = None
        self.messages = 0

    def begin(self, mission: str, epoch_ns: int) -> None:
        """Record into the file of ``mission`` (a new one when the mission changes)."""
        with self._lock:
            if self._mission is not None and self._mission[0] == mission:
                return
            self._close()
            directory = self.root / _SAFE.sub("_", self.drone)
            directory.mkdir(parents=True, exist_ok=True)
            stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime(epoch_ns / 1e9))
            self.path = directory / f"{_SAFE.sub('_', mission)}-{stamp}.mcap"
            n = 1
            while self.path.exists():
                self.path = directory / f"{_SAFE.sub('_', mission)}-{stamp}-{n}.mcap"
                n += 1
            from mcap.writer import CompressionType, Writer  # on first use: a light start-up

            self._file = self.path.open("wb")
            self._writer = Writer(self._file, compression=CompressionType.ZSTD)
            self._writer.start(profile="", library="modd-subbroker")
            self._schema = self._writer.register_schema("modd.DeliveredValue", "jsonschema",
                                                        _SCHEMA)
            self._channels = {}
            self._mission = (mission, epoch_ns)
            log.info("base-station record: %s", self.path)

    def put(self, subscriber: str, payload: bytes) -> None:
        with self._lock:
            writer = self._writer
            if writer is None:
                return
            ch = self._channels.get(subscriber)
            if ch is None:
                ch = self._channels[subscriber] = writer.register_channel(
                    sub_key(self.drone, subscriber), "json", self._schema)
            data: dict[str, Any] = json.loads(payload)
            end = int(data.get("end_ns", 0))
            writer.add_message(ch, end, payload, int(data.get("delivered_ns", end)))
            self.messages += 1

    def _close(self) -> None:
        if self._writer is not None:
            self._writer.finish()  # type: ignore[no-untyped-call]
        if self._file is not None:
            self._file.close()
        self._writer, self._file, self._mission = None, None, None

    def close(self) -> None:
        with self._lock:
            self._close()

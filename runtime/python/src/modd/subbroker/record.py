"""The base-station record: every value the SubBroker delivers (live and
backfilled), in one MCAP file per drone and mission (docs/subbroker.md,
"Base-station record"), one channel per subscriber key
(``modd/<drone>/sub/<subscriber>``), JSON messages (the delivered payload),
``log_time`` = the window's end on the drone's clock. After a backfill the
base station so holds a gap-free copy of every subscription.

A :class:`~.delivery.Sink`: the link thread calls :meth:`put`; the file is
finished (summary, footer) at :meth:`close` and when the mission changes.

A write error (the base station's disk full) never reaches the link thread: live
delivery goes on, the values not recorded are counted (``dropped``), one log line
says so, and every ``RETRY_S`` a new file of the mission is tried (one line when
recording resumes); the interrupted file is left as it is (the mission's values
are backfillable from the drone's archive).

>>> rec = BaseRecord(Path("/tmp/records"), "usv")    # doctest: +SKIP
>>> rec.begin("scenario1", 1_763_700_000_000_000_000)  # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
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

RETRY_S = 2.0
#: Bytes of messages per MCAP chunk (about 5 s of a 20-subscriber mission).
RECORD_CHUNK = 32 * 1024
_SAFE = re.compile(r"[^A-Za-z0-9_.-]")
# One JSON type per field, as Foxglove and Lichtblick read schemas (a field
# without a type makes them drop the channel); a null or an ALL window's list
# still travels in "value".
_SCHEMA = json.dumps(
    {
        "type": "object",
        "properties": {
            "value": {"type": "number"},
            "start_ns": {"type": "integer"},
            "end_ns": {"type": "integer"},
            "backfilled": {"type": "boolean"},
        },
    }
).encode()


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
        self.dropped = 0  # values not recorded after a write error
        self._failed_at: float | None = None  # monotonic time of the last write error

    def begin(self, mission: str, epoch_ns: int) -> None:
        """Record into the file of ``mission`` (a new one when the mission changes)."""
        with self._lock:
            if self._mission is not None and self._mission[0] == mission:
                return
            self._close()
            self._failed_at = None
            try:
                self._open(mission, epoch_ns)
            except OSError as exc:
                self._fail(exc, (mission, epoch_ns))

    def _open(self, mission: str, epoch_ns: int) -> None:
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
        # Small chunks: a chunk reaches the disk when full, so a record being
        # written is readable (replay, `modd dataset --received`) up to a few
        # seconds ago, and a crash loses at most one chunk (was 1 MiB: minutes).
        self._writer = Writer(self._file, compression=CompressionType.ZSTD, chunk_size=RECORD_CHUNK)
        self._writer.start(profile="", library="modd-subbroker")
        self._schema = self._writer.register_schema("modd.DeliveredValue", "jsonschema", _SCHEMA)
        self._channels = {}
        self._mission = (mission, epoch_ns)
        log.info("base-station record: %s", self.path)

    def put(self, subscriber: str, payload: bytes) -> None:
        with self._lock:
            if self._failed_at is not None and not self._retry():
                self.dropped += 1
                return
            writer = self._writer
            if writer is None:
                return
            try:
                ch = self._channels.get(subscriber)
                if ch is None:
                    ch = self._channels[subscriber] = writer.register_channel(
                        sub_key(self.drone, subscriber), "json", self._schema
                    )
                data: dict[str, Any] = json.loads(payload)
                end = int(data.get("end_ns", 0))
                writer.add_message(ch, end, payload, int(data.get("delivered_ns", end)))
                self.messages += 1
            except OSError as exc:
                self.dropped += 1
                self._fail(exc, self._mission)

    def _fail(self, exc: OSError, mission: tuple[str, int] | None) -> None:
        """A write error: the file is dropped (left as written), recording paused."""
        if self._failed_at is None:
            log.error(
                "base-station record: write failed (%s): values not recorded, live "
                "delivery goes on; a new file is tried every %.0f s",
                exc,
                RETRY_S,
            )
        self._failed_at = time.monotonic()
        if self._file is not None:
            with contextlib.suppress(OSError):  # what the file system kept stays
                self._file.close()
        self._writer, self._file, self._mission = None, None, mission

    def _retry(self) -> bool:
        """True when recording resumed (a new file of the mission is open)."""
        if self._failed_at is None or time.monotonic() - self._failed_at < RETRY_S:
            return False
        mission = self._mission
        if mission is None:
            self._failed_at = None
            return False
        try:
            self._open(*mission)
        except OSError as exc:
            self._fail(exc, mission)
            return False
        self._failed_at = None
        log.warning(
            "base-station record: writing again (%s; %d values not recorded)",
            self.path,
            self.dropped,
        )
        return True

    def _close(self) -> None:
        try:
            if self._writer is not None:
                self._writer.finish()  # type: ignore[no-untyped-call]
        except OSError as exc:
            log.error("base-station record: %s not finished: %s", self.path, exc)
        finally:
            if self._file is not None:
                with contextlib.suppress(OSError):
                    self._file.close()
            self._writer, self._file, self._mission = None, None, None

    def close(self) -> None:
        with self._lock:
            self._close()

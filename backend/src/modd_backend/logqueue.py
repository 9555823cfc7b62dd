"""The service's log lines written by a thread of their own: the event loop
formats a line and queues it, never waiting for a slow terminal or pipe
(the access log was one of what held the loop under load, issue 41). The
queue is bounded: past ``MAX_QUEUED`` lines waiting, new ones are dropped and
counted (the count is written with the next line that gets through).

uvicorn's log configuration names it as its handlers' class (cli.log_config).
"""

from __future__ import annotations

import atexit
import logging
import queue
from logging.handlers import QueueHandler, QueueListener
from typing import IO

#: Lines waiting to be written at most.
MAX_QUEUED = 10_000


class QueuedStreamHandler(QueueHandler):
    """A StreamHandler on ``stream`` behind a bounded queue and a writer thread."""

    def __init__(self, stream: IO[str] | None = None) -> None:
        super().__init__(queue.Queue(MAX_QUEUED))
        self.dropped = 0
        target = logging.StreamHandler(stream)
        target.setFormatter(logging.Formatter("%(message)s"))
        self.listener = QueueListener(self.queue, target)
        self.listener.start()
        self._stopped = False
        atexit.register(self.stop)

    def stop(self) -> None:
        """Write what waits and end the writer thread (once)."""
        if not self._stopped:
            self._stopped = True
            self.listener.stop()

    def prepare(self, record: logging.LogRecord) -> logging.LogRecord:
        """The record as it is: the writer thread formats it (QueueHandler's
        own prepare formats on the caller's thread, the event loop). The
        service's log arguments are strings and numbers, read once."""
        return record

    def enqueue(self, record: logging.LogRecord) -> None:
        if self.dropped and self.queue.qsize() < MAX_QUEUED // 2:  # type: ignore[attr-defined]
            record.msg = f"{record.msg} ({self.dropped} log lines dropped before this one)"
            self.dropped = 0
        try:
            self.queue.put_nowait(record)
        except queue.Full:
            self.dropped += 1

    def close(self) -> None:
        self.stop()
        super().close()

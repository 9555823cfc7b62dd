"""The service's log lines written by a thread of their own: the event loop
appends a record to a bounded deque and goes on, never waiting for a slow
terminal or pipe, nor waking a thread per line (the access log was one of
what held the loop under load, issue 41: a queue.Queue's put woke its writer
for every line). The writer takes what waits every ``FLUSH_S`` and formats
and writes it. Past ``MAX_QUEUED`` records waiting, new ones are dropped and
counted (the count is written with the next line that gets through).

uvicorn's log configuration names it as its handlers' class (cli.log_config).

>>> import io
>>> out = io.StringIO()
>>> h = QueuedStreamHandler(out)
>>> h.handle(logging.makeLogRecord({"msg": "%s %d", "args": ("GET /", 200)}))
True
>>> h.stop(); out.getvalue()
'GET / 200\\n'
"""

from __future__ import annotations

import atexit
import logging
import sys
import threading
from collections import deque
from typing import IO

#: Records waiting to be written at most.
MAX_QUEUED = 10_000
#: How often the writer thread writes what waits (seconds).
FLUSH_S = 0.05


class _CurrentStderr:
    """``sys.stderr`` as it is at each write: the writer thread outlives whoever
    replaced it meanwhile (a test's captured stream, closed after the test)."""

    def write(self, text: str) -> int:
        return sys.stderr.write(text)

    def flush(self) -> None:
        sys.stderr.flush()


class QueuedStreamHandler(logging.Handler):
    """A StreamHandler on ``stream`` behind a bounded deque and a writer thread."""

    def __init__(self, stream: IO[str] | None = None) -> None:
        super().__init__()
        self.dropped = 0
        self.waiting: deque[logging.LogRecord] = deque()
        self.target = logging.StreamHandler(stream or _CurrentStderr())
        self.target.setFormatter(logging.Formatter("%(message)s"))
        self._stop = threading.Event()
        self._writer = threading.Thread(target=self._run, name="modd-log-writer", daemon=True)
        self._writer.start()
        atexit.register(self.stop)

    def emit(self, record: logging.LogRecord) -> None:
        """Queued as it is (its arguments are strings and numbers, formatted
        by the writer); a deque's append needs no lock and wakes no thread."""
        if len(self.waiting) >= MAX_QUEUED:
            self.dropped += 1
            return
        if self.dropped:
            record.msg = f"{record.msg} ({self.dropped} log lines dropped before this one)"
            self.dropped = 0
        self.waiting.append(record)

    def _run(self) -> None:
        while not self._stop.wait(FLUSH_S):
            self._write()
        self._write()

    def _write(self) -> None:
        while self.waiting:
            self.target.handle(self.waiting.popleft())

    def stop(self) -> None:
        """Write what waits and end the writer thread (once)."""
        if not self._stop.is_set():
            self._stop.set()
            self._writer.join(10)

    def close(self) -> None:
        self.stop()
        super().close()

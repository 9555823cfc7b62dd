"""SIGTERM and Ctrl-C as a ``threading.Event``, without a lock in the signal handler.

Python runs a signal handler in the main thread between two bytecodes, so a handler
that calls ``Event.set()`` deadlocks when the signal lands while the main thread holds
that event's lock (inside its own ``wait(tick)``, ``is_set()`` or ``set()``): the
process then never stops and systemd or a supervisor kills it, unflushed. The Python
docs warn against locks in handlers (``signal``, "Note on Signal Handlers and
Exceptions"). Here the handler only writes a byte to a pipe (async-signal-safe, no
lock) and a thread of its own sets the event.

Example::

    stop = threading.Event()
    stop_on_signals(stop)
    while not stop.wait(0.25):
        ...
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from types import FrameType

STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT)


def stop_on_signals(
    event: threading.Event, signals: tuple[signal.Signals, ...] = STOP_SIGNALS
) -> None:
    """Sets ``event`` (from a thread of its own) when one of ``signals`` arrives.
    Call from the main thread, as ``signal.signal`` requires."""
    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)  # a full pipe already says "stop"

    def relay() -> None:
        while os.read(read_end, 1):
            event.set()

    threading.Thread(target=relay, name="stop-signals", daemon=True).start()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        with contextlib.suppress(BlockingIOError):
            os.write(write_end, b"s")

    for s in signals:
        signal.signal(s, on_signal)

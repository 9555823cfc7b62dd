"""SIGTERM stops a process whatever its main thread holds (modd.shutdown).

A handler that calls ``Event.set()`` itself deadlocks when the signal lands while the
main thread holds the event's lock, as it does inside ``stop.wait(tick)``: a
modd-sensors stopped by SIGTERM then hung until it was killed. Each case runs in a
process of its own that sends itself SIGTERM at that moment."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "modd"

SCRIPT = """
import os, signal, sys, threading
from modd.shutdown import stop_on_signals

stop = threading.Event()
if sys.argv[1] == "handler-sets-event":
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
else:
    stop_on_signals(stop)
with stop._cond:  # the main thread holds the event's lock, as inside stop.wait(tick)
    os.kill(os.getpid(), signal.SIGTERM)
    held = True  # the handler runs at the next bytecode, under the lock
print("stopped" if stop.wait(10) else "never stopped", flush=True)
"""


def _run(how: str, timeout_s: float) -> subprocess.CompletedProcess[str] | None:
    try:
        return subprocess.run(
            [sys.executable, "-c", SCRIPT, how], capture_output=True, text=True, timeout=timeout_s
        )
    except subprocess.TimeoutExpired:
        return None  # deadlocked (the child is killed by subprocess.run)


def test_a_signal_under_the_events_lock_stops_the_process() -> None:
    done = _run("stop_on_signals", 20)
    assert done is not None, "the process deadlocked in its signal handler"
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "stopped"


def test_the_case_is_the_one_that_deadlocks_a_handler_setting_the_event() -> None:
    """The power of the test above: the same moment deadlocks the naive handler."""
    assert _run("handler-sets-event", 3) is None  # it would say "stopped" within 0.1 s


def test_no_signal_handler_takes_a_lock() -> None:
    naive = re.compile(r"signal\.signal\([^)]*\.set\(\)")
    offenders = [str(p.relative_to(SRC)) for p in SRC.rglob("*.py") if naive.search(p.read_text())]
    assert offenders == [], f"Event.set() in a handler; use stop_on_signals: {offenders}"

"""Restarting the processes of a local run (``modd up``) that die, as systemd
restarts each service on a drone (``Restart=on-failure``, ``RestartSec``,
``StartLimitBurst``): each death is logged, the process started again after a
backoff (1 s, doubling to 30 s; back to 1 s once it has run 60 s), and after
5 restarts within 5 minutes ``modd up`` gives up and stops the whole run.

>>> r = Restarts(RestartPolicy())
>>> [r.on_exit("pubbroker", now=t, ran_s=1.0) for t in (0.0, 10.0, 20.0)]
[1.0, 12.0, 24.0]
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol


@dataclass(frozen=True)
class RestartPolicy:
    backoff_s: float = 1.0  # the first restart's delay, doubled at each death
    backoff_max_s: float = 30.0
    stable_s: float = 60.0  # a process that ran this long starts again from backoff_s
    max_restarts: int = 5  # within window_s; one more death stops the run
    window_s: float = 300.0


@dataclass
class Restarts:
    """When to restart each process that died, or None to give up."""

    policy: RestartPolicy
    _delay: dict[str, float] = field(default_factory=dict)
    _history: dict[str, list[float]] = field(default_factory=dict)

    def on_exit(self, name: str, now: float, ran_s: float) -> float | None:
        p = self.policy
        recent = [t for t in self._history.get(name, []) if now - t < p.window_s]
        if len(recent) >= p.max_restarts:
            return None
        delay = p.backoff_s if ran_s >= p.stable_s else self._delay.get(name, p.backoff_s)
        self._delay[name] = min(delay * 2, p.backoff_max_s)
        self._history[name] = [*recent, now]
        return now + delay

    def count(self, name: str) -> int:
        return len(self._history.get(name, []))


DEFAULT_POLICY = RestartPolicy()

PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def tied_to_parent(sig: int = signal.SIGTERM) -> Callable[[], None] | None:
    """A ``preexec_fn`` for ``subprocess.Popen`` that makes the child receive ``sig``
    when the process that starts it dies, even by SIGKILL (Linux ``PR_SET_PDEATHSIG``),
    so that no process of a supervisor outlives it; None where the system has no such
    call. SIGTERM lets each child stop cleanly (the PubBroker closes its archive).

    The kernel sends it when the *thread* that forked exits: start children from the
    supervisor's main thread. A parent that died between the fork and the ``prctl``
    is caught by comparing the parent's pid.

    >>> import subprocess
    >>> subprocess.run(["true"], preexec_fn=tied_to_parent(), check=True).returncode
    0
    """
    if not sys.platform.startswith("linux"):
        return None
    libc = ctypes.CDLL(None, use_errno=True)  # loaded before the fork, not in the child
    parent = os.getpid()

    def preexec() -> None:
        libc.prctl(PR_SET_PDEATHSIG, sig, 0, 0, 0)
        if os.getppid() != parent:  # the parent is already gone: follow it at once
            os.kill(os.getpid(), sig)

    return preexec


class Child(Protocol):
    """A process of the run (``modd_launch.drone.Process``)."""

    name: str
    log: Path
    restartable: bool

    def start(self, env: dict[str, str]) -> None: ...

    def exit_code(self) -> int | None: ...

    def pid(self) -> int | None: ...


def watch(
    children: Sequence[Child],
    env: Mapping[str, str],
    stopping: Callable[[], bool],
    policy: RestartPolicy = DEFAULT_POLICY,
    say: Callable[[str], None] = print,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
    gave_up: Callable[[dict[str, Any]], None] | None = None,
) -> int:
    """Restarts each child that dies (when it is restartable) until ``stopping()``
    (0) or until one dies more often than ``policy`` allows (1): then ``gave_up``
    is told which process, its exit code, why and its log (what ``modd up`` puts
    on the zenoh status). The caller stops them all after it returns."""
    restarts = Restarts(policy)
    started = {c.name: clock() for c in children}
    due: dict[str, float] = {}
    while not stopping():
        now = clock()
        for c in children:
            if c.name in due:
                if now < due[c.name]:
                    continue
                del due[c.name]
                c.start(dict(env))
                started[c.name] = now
                say(
                    f"modd up: restarted {c.name} (pid {c.pid()}), "
                    f"restart {restarts.count(c.name)} of at most {policy.max_restarts}"
                )
            code = c.exit_code()
            if code is None:
                continue
            at = restarts.on_exit(c.name, now, now - started[c.name]) if c.restartable else None
            if at is None:
                why = (
                    "it cannot be restarted"
                    if not c.restartable
                    else (f"{policy.max_restarts} restarts within {policy.window_s:.0f} s")
                )
                say(f"modd up: {c.name} exited ({code}); see {c.log}; stopping the run: {why}")
                if gave_up is not None:
                    gave_up(
                        {
                            "state": "GAVE_UP",
                            "process": c.name,
                            "exit_code": code,
                            "reason": f"{c.name} exited ({code}); stopping the run: {why}",
                            "log": str(c.log),
                            "at_ns": time.time_ns(),
                        }
                    )
                return 1
            due[c.name] = at
            say(
                f"modd up: {c.name} exited ({code}); see {c.log}; restarting it in {at - now:.0f} s"
            )
        sleep(0.2)
    return 0

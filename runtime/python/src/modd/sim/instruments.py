"""Simulated instruments for the model's ``nmea``, ``ascii`` and ``modbus``
sensors: each gets a pseudo-terminal whose slave is linked at the sensor's
device path, and writes its wire format there (``wire.py``) at its
publisher's period, NMEA and ASCII sensors by themselves, a Modbus device in
answer to each read request. ``modd-sensors`` reads them as real devices.

A device path is only ever made a symbolic link to a pseudo-terminal: an
existing file that is not a symbolic link is refused (``modd up --simulate``
points the model's devices into its run directory).

Example::

    threads = start_instruments(model, start=time.time(), stop=stop_event, log=print)
"""

from __future__ import annotations

import contextlib
import os
import random
import select
import threading
import time
import tty
from collections.abc import Callable
from pathlib import Path
from typing import Any

from modd_model.query import topics

from ..sensors.plan import SensorPlan, plan_sensors
from .faults import FaultFile
from .sensors import topic_signal
from .track import survey_pose
from .wire import ascii_lines, modbus_reply, nmea_lines, registers


def open_device(path: Path) -> int:
    """A raw pseudo-terminal with its slave linked at ``path``; the master fd (non-blocking)."""
    if path.exists() and not path.is_symlink():
        raise FileExistsError(f"{path} exists and is not a link: not replaced by a simulation")
    master, slave = os.openpty()
    tty.setraw(slave)
    tmp = path.with_name(path.name + ".sim")
    with contextlib.suppress(FileNotFoundError):
        tmp.unlink()
    path.parent.mkdir(parents=True, exist_ok=True)
    os.symlink(os.ttyname(slave), tmp)
    os.replace(tmp, path)
    os.set_blocking(master, False)
    return master


def _send(master: int, data: bytes) -> None:
    with contextlib.suppress(BlockingIOError):  # nobody reads: an instrument talks anyway
        os.write(master, data)


class Instrument:
    def __init__(
        self,
        plan: SensorPlan,
        model: dict[str, Any],
        start: float,
        seed: int,
        faults: FaultFile | None = None,
    ) -> None:
        rng = random.Random(seed)
        self.faults = faults or FaultFile(None)
        tops = topics(model)
        self.plan = plan
        self.start = start
        self.signals = {m.topic: topic_signal(tops[m.topic], rng) for m in plan.mappings}
        self.master = open_device(Path(plan.device.path))

    def values(self, now: float) -> dict[str, float]:
        t = now - self.start
        pose = survey_pose(t)
        return {
            name: float(self.faults.apply(name, now, sig(t, pose)))
            for name, sig in self.signals.items()
        }

    def run(self, stop: threading.Event) -> None:
        try:
            if self.plan.kind == "modbus":
                self._serve(stop)
            else:
                self._talk(stop)
        finally:
            os.close(self.master)

    def _talk(self, stop: threading.Event) -> None:
        end = self.plan.line_end
        first, tick = time.monotonic(), 0
        while not stop.wait(max(0.0, first + tick * self.plan.poll_s - time.monotonic())):
            now = time.time()
            with contextlib.suppress(OSError):
                os.read(self.master, 4096)  # a start command: the simulation is always on
            if self.plan.kind == "nmea":
                text = "".join(
                    line + "\r\n" for line in nmea_lines(self.plan, self.values(now), now)
                )
            else:
                text = "".join(
                    line + end.decode() for line in ascii_lines(self.plan, self.values(now))
                )
            _send(self.master, text.encode())
            tick += 1

    def _serve(self, stop: threading.Event) -> None:
        buf = b""
        while not stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.1)
            if not ready:
                buf = b""  # an RTU frame ends with a silence
                continue
            with contextlib.suppress(BlockingIOError):
                buf += os.read(self.master, 256)
            if len(buf) >= 8:
                reply = modbus_reply(buf[:8], registers(self.plan, self.values(time.time())))
                buf = buf[8:]
                if reply is not None:
                    _send(self.master, reply)


def start_instruments(
    model: dict[str, Any],
    start: float,
    stop: threading.Event,
    log: Callable[[str], None],
    faults: FaultFile | None = None,
) -> list[threading.Thread]:
    """A thread per instrument sensor of ``model``, started (``faults`` injected: faults.py)."""
    threads = []
    for i, plan in enumerate(plan_sensors(model)):
        if plan.kind == "ascii" and plan.line.pattern is not None:
            log(f"{plan.name}: a pattern is not simulated (write its lines to {plan.device.path})")
            continue
        inst = Instrument(plan, model, start, 1000 + i, faults)
        th = threading.Thread(
            target=inst.run, args=(stop,), name=f"instrument-{plan.name}", daemon=True
        )
        th.start()
        threads.append(th)
        log(f"instrument {plan.name} ({plan.kind}) on {plan.device.path}")
    return threads


def simulated_devices(model: dict[str, Any], directory: Path) -> dict[str, Any]:
    """A copy of ``model`` whose instrument sensors' devices are links in ``directory``
    (made by the simulator), never the real devices the model names."""
    local: dict[str, Any] = {**model, "drone": {**model["drone"], "sensors": []}}
    for s in model["drone"]["sensors"]:
        if "device" in s:
            s = {**s, "device": {**s["device"], "path": str(directory / s["name"])}}
        local["drone"]["sensors"].append(s)
    return local

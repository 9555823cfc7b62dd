"""The reader's I/O: one thread per sensor (so a device that floods or hangs
delays no other), reading the device, feeding the decoder and handing the
samples to the model's publishers; the device reopened after any loss.

Example::

    runner = Runner(plans, {"gnss": Publisher("gnss", ingress)}, log=print)
    runner.run(stop_event)     # returns when stop_event is set, publishers flushed
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Protocol

import serial

from modd.link.frames import SensorHealth

from . import modbus
from .decode import Block, LineDecoder, Sample, block_samples, blocks
from .device import RETRY_S, DeviceBusy, Errors, open_port, read_some
from .health import Health, status_line
from .plan import SensorPlan

MODBUS_TIMEOUT_S = 0.5
HEALTH_PERIOD_S = 1.0  # how often the PubBroker hears of the sensors' health
SILENT_PERIODS, SILENT_MIN_S = 3, 2.0
STOP_BUDGET_S = 1.0  # SIGTERM to exit, whatever the PubBroker's state (systemd waits longer)


class Sink(Protocol):
    """What the reader needs of a publisher (``modd.publisher.Publisher`` is one)."""

    def declare(self, topic: str, vtype: str) -> None: ...

    def publish(self, topic: str, timestamp_ns: int, value: float) -> bool: ...

    def flush(self, timeout: float = 5.0) -> bool: ...

    def close(self, timeout: float = 2.0) -> None: ...


class SensorThread:
    def __init__(
        self, plan: SensorPlan, sinks: Mapping[str, Sink], log: Callable[[str], None]
    ) -> None:
        self.plan = plan
        self.sinks = sinks
        self.log = log
        self.health = Health()
        self.thread = threading.Thread(target=self._run, name=f"sensor-{plan.name}", daemon=True)
        self._stop = threading.Event()
        self._starting = threading.Lock()
        self._opened = False
        self.absent = False  # the device path is not there (waiting for it)
        self.started_ns = 0  # when reading began: silence is counted from there

    def start(self) -> None:
        """Starts reading, once (a deploy and the runner's start may both ask), never after stop."""
        with self._starting:
            if self.thread.ident is not None or self._stop.is_set():
                return
            self.started_ns = time.time_ns()
            self.thread.start()

    def join(self, timeout: float) -> None:
        if self.thread.ident is not None:
            self.thread.join(timeout)

    def stop(self) -> None:
        """Asks the reader to end (it closes its device within its read timeout)."""
        self._stop.set()

    def publish(self, samples: list[Sample]) -> None:
        h = self.health
        for m, stamp, value in samples:
            if self.sinks[m.publisher].publish(m.topic, stamp, value):
                h.values += 1
                h.last_value_ns = time.time_ns()
                h.silent = False
            else:
                h.refused += 1

    def _run(self) -> None:
        waiting = False  # said once per absence, not every RETRY_S
        while not self._stop.is_set():
            try:
                port = open_port(self.plan.device)
            except DeviceBusy as exc:
                self._busy(str(exc))
                self._stop.wait(RETRY_S)
                continue
            self.health.busy = ""
            self.absent = port is None
            if port is None:
                if not waiting:
                    self.log(
                        f"{self.plan.name}: waiting for {self.plan.device.path} "
                        f"(retried every {RETRY_S} s)"
                    )
                waiting = True
                self._stop.wait(RETRY_S)
                continue
            waiting = False
            if self._opened:
                self.health.reconnects += 1
                self.log(f"{self.plan.name}: {self.plan.device.path} reopened")
            self._opened = True
            self.health.connected = True
            try:
                if self.plan.kind == "modbus":
                    self._poll(port)
                else:
                    self._read(port)
            except Errors as exc:
                self.log(f"{self.plan.name}: {self.plan.device.path} lost ({exc}); reopening")
            finally:
                self.health.connected = False
                port.close()

    def _busy(self, why: str) -> None:
        """Another process holds the device: said once per holder, and in the health
        (busy, not silent: the instrument may be fine)."""
        if self.health.busy != why:
            self.log(f"{self.plan.name}: {self.plan.device.path} is busy, {why}; retrying")
        self.health.busy = why

    def _read(self, port: serial.Serial) -> None:
        decoder = LineDecoder(self.plan, self.health)
        if self.plan.start_command:
            port.write(self.plan.start_command.encode() + self.plan.line_end)
        while not self._stop.is_set():
            data = read_some(port)
            if data:
                self.publish(decoder.feed(data, time.time_ns()))

    def _poll(self, port: serial.Serial) -> None:
        reads = blocks(self.plan)
        due = time.monotonic()
        while not self._stop.wait(max(0.0, due - time.monotonic())):
            for block in reads:
                self._ask(port, block)
            due = max(due + self.plan.poll_s, time.monotonic())

    def _ask(self, port: serial.Serial, block: Block) -> None:
        port.reset_input_buffer()  # what came late for an earlier request
        port.write(block.request())
        reply, deadline = b"", time.monotonic() + MODBUS_TIMEOUT_S
        while time.monotonic() < deadline:
            reply += read_some(port)
            need = modbus.reply_length(reply, block.function)
            if need is not None and len(reply) >= need:
                break
        stamp = time.time_ns()
        need = modbus.reply_length(reply, block.function)
        h = self.health
        if need is None or len(reply) < need:
            h.timeouts += 1
            h.last_bad = f"unit {block.unit}: no reply in {MODBUS_TIMEOUT_S} s"
            return
        try:
            words = modbus.parse_reply(reply[:need], block.unit, block.function, block.count)
        except modbus.ExceptionReply as exc:
            h.exceptions += 1
            h.last_bad = f"unit {block.unit} register {block.address}: {exc}"
            return
        except modbus.BadReply as exc:
            h.bad(f"unit {block.unit}: {exc}")
            return
        h.lines_ok += 1
        self.publish(block_samples(block, words, stamp))

    def watch(self, now_ns: int) -> None:
        """Marks the sensor silent when no value came for SILENT_PERIODS periods
        (at least SILENT_MIN_S), counting each silence once."""
        h = self.health
        since = h.last_value_ns or self.started_ns
        limit = max(SILENT_MIN_S, SILENT_PERIODS * self.plan.poll_s) * 1e9
        if not h.silent and not h.busy and now_ns - since > limit:
            h.silent = True
            h.silences += 1
            self.log(f"{self.plan.name}: silent for {(now_ns - since) / 1e9:.1f} s")


class Runner:
    def __init__(
        self,
        plans: list[SensorPlan],
        sinks: Mapping[str, Sink],
        log: Callable[[str], None] = print,
        status_file: Path | None = None,
        status_period_s: float = 10.0,
        report_health: Callable[[list[SensorHealth]], None] | None = None,
        health_period_s: float = HEALTH_PERIOD_S,
    ) -> None:
        self.sinks = dict(sinks)
        self.report_health = report_health
        self.health_period_s = health_period_s
        self.log = log
        self.sensors = [SensorThread(p, self.sinks, log) for p in plans]
        self.status_file = status_file
        self.status_period_s = status_period_s
        for p in plans:
            for m in p.mappings:
                sinks[m.publisher].declare(m.topic, m.type)

    def health(self) -> dict[str, dict[str, object]]:
        now = time.time_ns()
        return {s.plan.name: s.health.as_dict(now) for s in list(self.sensors)}

    def send_health(self) -> None:
        """Every sensor's health to the PubBroker (HEALTH), which forwards it in STATUS."""
        if self.report_health is not None:
            self.report_health([s.health.report(s.plan.name) for s in list(self.sensors)])

    def write_status(self) -> None:
        if self.status_file is None:
            return
        tmp = self.status_file.with_name(self.status_file.name + ".tmp")
        tmp.write_text(json.dumps({"sensors": self.health()}, indent=1) + "\n")
        os.replace(tmp, self.status_file)

    def run(self, stop: threading.Event, tick_s: float = 0.25) -> None:
        for s in self.sensors:
            s.start()
        next_status = time.monotonic() + self.status_period_s
        next_health = time.monotonic()
        try:
            while not stop.wait(tick_s):
                now = time.time_ns()
                for s in list(self.sensors):
                    s.watch(now)
                self.write_status()
                if time.monotonic() >= next_health:
                    next_health = time.monotonic() + self.health_period_s
                    self.send_health()
                if time.monotonic() >= next_status:
                    next_status += self.status_period_s
                    for s in list(self.sensors):
                        self.log(status_line(s.plan.name, s.health, now))
        finally:
            self._stop_within(STOP_BUDGET_S)

    def _stop_within(self, budget_s: float) -> None:
        """Joins the readers and flushes the publishers within one budget for all of
        them: with the PubBroker gone, a flush per publisher would otherwise wait its
        own timeout, one after the other (20 s for ten publishers); what is left
        unsent then is what the PubBroker could not take anyway."""
        deadline = time.monotonic() + budget_s

        def left() -> float:
            return max(0.0, deadline - time.monotonic())

        for s in self.sensors:
            s.stop()
        for s in self.sensors:
            s.join(left())
        self.send_health()  # the last counts, before the publishers close
        for sink in self.sinks.values():
            sink.flush(left())
        for sink in self.sinks.values():
            sink.close(left())
        self.write_status()
        for s in self.sensors:
            self.log(status_line(s.plan.name, s.health, time.time_ns()))

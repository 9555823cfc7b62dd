"""Instruments for the modd-sensors tests: pseudo-terminals the test writes
the device side of (unplugged and plugged back in by closing the pair and
pointing the device's link at a new one, as udev does for a renumbered USB
adapter), and a Modbus RTU device served by pymodbus (a library we did not
write) on a pty pair relayed to the reader's, with faults injected in the
relay."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import select
import threading
import time
import tty
from collections.abc import Callable
from pathlib import Path
from typing import Any


def _pty() -> tuple[int, str, int]:
    master, slave = os.openpty()
    tty.setraw(slave)
    return master, os.ttyname(slave), slave


def point(link: Path, target: str) -> None:
    """Make ``link`` lead to ``target`` in one step (as udev moves a by-id link)."""
    tmp = link.with_name(link.name + ".new")
    with contextlib.suppress(FileNotFoundError):
        tmp.unlink()
    os.symlink(target, tmp)
    os.replace(tmp, link)


class PtyDevice:
    """An instrument on a pseudo-terminal reached through the link ``path``."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.master = -1
        self.slave = -1
        self.plug()

    def plug(self) -> None:
        self.master, slave_path, self.slave = _pty()
        point(self.path, slave_path)

    def unplug(self) -> None:
        for fd in (self.master, self.slave):
            with contextlib.suppress(OSError):
                os.close(fd)
        self.master = self.slave = -1

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            try:
                n = os.write(self.master, view)
            except BlockingIOError:
                time.sleep(0.001)
                continue
            view = view[n:]

    def read(self, timeout: float = 0.0) -> bytes:
        ready, _, _ = select.select([self.master], [], [], timeout)
        return os.read(self.master, 4096) if ready else b""

    def close(self) -> None:
        self.unplug()
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()


def nmea(body: str) -> bytes:
    """``$body*hh\\r\\n`` with its checksum computed by pynmea2."""
    import pynmea2  # type: ignore[import-untyped]

    return f"${body}*{pynmea2.NMEASentence.checksum(body):02X}\r\n".encode()


def gga(lat: float) -> bytes:
    """A GNSS fix (GNGGA) at latitude ``lat`` degrees north, 3°21' W."""
    minutes = (lat - int(lat)) * 60
    return nmea(f"GNGGA,101500.00,{int(lat):02d}{minutes:07.4f},N,00321.0000,W,1,09,0.9,4.2,M,,M,,")


class ModbusDevice:
    """pymodbus's RTU server (unit 1, holding registers from address 0 = ``registers``)
    on one pty pair, relayed to the pty pair the reader opens at ``path``.
    ``mute`` swallows the requests (a device that does not answer)."""

    def __init__(self, path: Path, registers: list[int], baud: int = 19200) -> None:
        from pymodbus.datastore import (
            ModbusDeviceContext,
            ModbusSequentialDataBlock,
            ModbusServerContext,
        )

        self.mute = False
        self.reader_side = PtyDevice(path)
        self.server_master, server_path, self.server_slave = _pty()
        # address 1 of the block is register 0 on the wire (FIELD_NOTES, pymodbus 3.16)
        self.block = ModbusSequentialDataBlock(1, registers)  # type: ignore[no-untyped-call]
        context = ModbusServerContext(devices={1: ModbusDeviceContext(hr=self.block)}, single=False)
        self._stop = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._server: Any = None
        self._threads = [
            threading.Thread(target=self._serve, args=(context, server_path, baud), daemon=True),
            threading.Thread(target=self._relay, daemon=True),
        ]
        for th in self._threads:
            th.start()

    def _serve(self, context: Any, port: str, baud: int) -> None:
        from pymodbus.server import ModbusSerialServer

        async def main() -> None:
            self._loop = asyncio.get_running_loop()
            self._server = ModbusSerialServer(context, port=port, baudrate=baud)
            await self._server.serve_forever()

        with contextlib.suppress(Exception):
            asyncio.run(main())

    def _relay(self) -> None:
        while not self._stop.is_set():
            reader = self.reader_side.master
            fds = [self.server_master] + ([reader] if reader >= 0 else [])
            try:
                ready, _, _ = select.select(fds, [], [], 0.05)
                for fd in ready:
                    data = os.read(fd, 4096)
                    if fd == self.server_master and reader >= 0:
                        self.reader_side.write(data)
                    elif fd != self.server_master and not self.mute:
                        os.write(self.server_master, data)
            except OSError:
                time.sleep(0.01)  # the reader's side is unplugged

    def close(self) -> None:
        self._stop.set()
        if self._loop is not None and self._server is not None:
            with contextlib.suppress(RuntimeError):
                asyncio.run_coroutine_threadsafe(self._server.shutdown(), self._loop).result(5)
        for th in self._threads:
            th.join(5)
        for fd in (self.server_master, self.server_slave):
            with contextlib.suppress(OSError):
                os.close(fd)
        self.reader_side.close()


def run_health(run: Path) -> dict[str, Any]:
    """Each sensor's health in ``modd up``'s ``<run>/sensors.json`` ({} before it is written)."""
    try:
        sensors: dict[str, Any] = json.loads((run / "sensors.json").read_text())["sensors"]
        return sensors
    except (FileNotFoundError, ValueError, KeyError):
        return {}


def wait_until(cond: Callable[[], bool], timeout: float, what: str) -> float:
    """Seconds until ``cond()`` held; fails naming ``what`` after ``timeout``."""
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        if cond():
            return time.monotonic() - start
        time.sleep(0.02)
    raise AssertionError(f"{what}: not within {timeout} s")

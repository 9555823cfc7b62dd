"""A sensor's serial device: opened by path at each attempt (so a
``/dev/serial/by-id/...`` link that udev points at a renumbered adapter is
followed), closed on any error, reopened every ``RETRY_S`` until it is back.
A device another process holds (pyserial's exclusive lock) is told apart from an
absent one: :class:`DeviceBusy` names the holder when ``/proc`` shows it.

Example::

    port = open_port(Device("/dev/ttyUSB0", 9600))   # None while unplugged
"""

from __future__ import annotations

import errno
import os
import select

import serial

from .plan import Device

RETRY_S = 0.2
READ_TIMEOUT_S = 0.1
PARITY = {"none": serial.PARITY_NONE, "even": serial.PARITY_EVEN, "odd": serial.PARITY_ODD}
Errors = (serial.SerialException, OSError, ValueError)


PROC_SCAN_LIMIT = 4096  # processes looked at to name a holder: bounded on a busy machine


class DeviceBusy(Exception):
    """The device is there but locked by another process (``str()`` says which, if known)."""


def holder_of(path: str, proc: str = "/proc", limit: int = PROC_SCAN_LIMIT) -> str:
    """``pid N (name)`` of another process that has ``path`` open, or "" when none can be
    seen (another user's process, no ``/proc``)."""
    target = os.path.realpath(path)
    try:
        pids = [d for d in os.listdir(proc) if d.isdigit()][:limit]
    except OSError:
        return ""
    for pid in pids:
        if int(pid) == os.getpid():
            continue
        try:
            fds = os.listdir(f"{proc}/{pid}/fd")
            if any(os.readlink(f"{proc}/{pid}/fd/{fd}") == target for fd in fds):
                with open(f"{proc}/{pid}/comm") as comm:
                    return f"pid {pid} ({comm.read().strip()})"
        except OSError:
            continue  # gone, or not ours to look at
    return ""


def open_port(device: Device, timeout: float = READ_TIMEOUT_S) -> serial.Serial | None:
    """The open port, or None when the device is not there (or not a serial port);
    raises :class:`DeviceBusy` when another process holds it."""
    try:
        return serial.Serial(
            device.path,
            device.baud,
            parity=PARITY[device.parity],
            stopbits=device.stop_bits,
            timeout=timeout,
            write_timeout=1.0,
            exclusive=True,
        )
    except serial.SerialException as exc:
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):  # flock: another process holds it
            holder = holder_of(device.path)
            raise DeviceBusy(f"held by {holder}" if holder else "held by another process") from exc
        return None
    except Errors:
        return None


def read_some(port: serial.Serial) -> bytes:
    """What the device sent, waiting at most the port's timeout for the first byte;
    raises one of ``Errors`` when the device is gone (ready with no data: a pty whose
    other end closed, an adapter pulled out).

    One ``select`` and one ``read`` of the descriptor per burst: pyserial's own
    ``read(in_waiting or 1)`` takes a byte, then the rest on a second wake-up, and
    costs a third of the reader's CPU at 20 devices × 10 Hz."""
    fd = port.fileno()
    ready, _, _ = select.select([fd], [], [], port.timeout)
    if not ready:
        return b""
    data = os.read(fd, 65536)
    if not data:
        raise serial.SerialException("the device is ready to read but gives no data (unplugged?)")
    return data

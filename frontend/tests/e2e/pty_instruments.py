"""Two instruments on pseudo-terminals for the browser journey (instruments.mjs):
``python pty_instruments.py DIR`` links ``DIR/gps2`` (NMEA GGA, 5 Hz, made by
pynmea2) and ``DIR/ctd2`` (ASCII ``temperature,C=conductivity`` lines, 2 Hz) to
the terminals' device ends and writes until SIGTERM. Nobody reading is fine:
what the terminal cannot hold is dropped, as a serial line drops it."""

from __future__ import annotations

import contextlib
import fcntl
import os
import signal
import sys
import time
import tty
from pathlib import Path

import pynmea2  # type: ignore[import-untyped]


def device(link: Path) -> int:
    master, slave = os.openpty()
    tty.setraw(slave)
    fcntl.fcntl(master, fcntl.F_SETFL, fcntl.fcntl(master, fcntl.F_GETFL) | os.O_NONBLOCK)
    tmp = link.with_name(link.name + ".new")
    os.symlink(os.ttyname(slave), tmp)
    os.replace(tmp, link)
    return master


def gga(i: int) -> bytes:
    """A GGA with a fix, its checksum and form by pynmea2."""
    lat = f"{4742.0 + (i % 600) * 0.001:.4f}"
    stamp = time.strftime("%H%M%S.00", time.gmtime())
    fields = (stamp, lat, "N", "00321.0000", "W", "1", "09", "0.9", "4.2", "M", "50.1", "M", "", "")
    return (str(pynmea2.GGA("GP", "GGA", fields)) + "\r\n").encode()


def write(fd: int, data: bytes) -> None:
    with contextlib.suppress(OSError):  # a full terminal (BlockingIOError): nobody reads it now
        os.write(fd, data)


def main() -> int:
    folder = Path(sys.argv[1])
    gps, ctd = device(folder / "gps2"), device(folder / "ctd2")
    stopping: list[int] = []  # a plain flag: a lock in a signal handler can deadlock
    signal.signal(signal.SIGTERM, lambda signum, _: stopping.append(signum))
    print("ready", flush=True)
    i = 0
    while not stopping:
        time.sleep(0.2)
        write(gps, gga(i))
        if i % 5 == 0:
            write(ctd, f"{12.0 + (i % 50) * 0.01:.2f},C={45000 + i % 100}\r\n".encode())
        i += 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

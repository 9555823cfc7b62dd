"""``modd-sensors``: the model's plug-and-play instruments read on board with
no driver code (docs/sensors.md). Sensors of ``kind nmea`` (NMEA 0183
sentences), ``ascii`` (one text line per sample) and ``modbus`` (Modbus RTU
registers, polled) are read from their serial devices, every line or reply
checked (``nmea``, ``ascii``, ``modbus``), stamped on receive and published
through the PubBroker's ingress by the model's publishers.

The logic is apart from the I/O: ``decode`` turns bytes into samples and
counts every refusal in the sensor's ``Health``; ``run`` owns the devices
(``device``), one thread per sensor, reopened after any loss.
"""

from __future__ import annotations

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """``modd-sensors`` (cli.py; imported here on call, so that ``python -m
    modd.sensors.check`` loads no reader)."""
    from .cli import main as run

    return run(argv)

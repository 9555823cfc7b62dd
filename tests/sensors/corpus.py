"""Real receivers' output (captures/, gpsd's regression logs, BSD-2) and what a
reference decoder independent of modd-sensors says of it: pynmea2 (a library we
did not write) parses each line, and NMEA 0183's validity rules, applied to
pynmea2's fields, say which positions were measured.

Lines are split as a serial reader sees them (at LF, a CR before it dropped);
gpsd's ``#`` comment lines are left out of the replay.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import pynmea2  # type: ignore[import-untyped]

CAPTURES = Path(__file__).parent / "captures"
MAX_LINE = 512  # modd-sensors' documented bound on an NMEA line
POSITION_SENTENCES = ("GGA", "RMC", "GLL", "GNS")
BARE = {"hp58534a.log"}  # the receiver that sends no checksums: checksum = optional


def captures() -> list[Path]:
    return sorted(CAPTURES.glob("*.log"))


def replay_bytes(path: Path) -> bytes:
    """The capture as the receiver sent it (gpsd's # comments left out)."""
    return b"".join(
        line + b"\n" for line in path.read_bytes().split(b"\n") if not line.startswith(b"#")
    )


def lines(data: bytes) -> Iterator[bytes]:
    for raw in data.split(b"\n"):
        line = raw.rstrip(b"\r")
        if line.strip():
            yield line


@dataclasses.dataclass
class Reference:
    bad: int = 0  # lines failing checksum, framing or form
    positions: dict[str, list[tuple[float, float]]] = dataclasses.field(default_factory=dict)
    no_fix: int = 0  # position sentences that say no fix


def _valid(msg: object) -> bool:
    """NMEA 0183's validity fields, read from pynmea2's attributes."""
    kind = type(msg).__name__
    if kind == "GGA":
        return str(msg.gps_qual) not in ("", "0", "None") and str(msg.gps_qual) in "123459"  # type: ignore[attr-defined]
    if kind == "GNS":
        mode = msg.mode_indicator or ""  # type: ignore[attr-defined]
        return bool(set(mode) & set("ADPRF"))
    status = getattr(msg, "status", "A")
    mode = getattr(msg, "mode_indicator", None) if kind == "RMC" else getattr(msg, "faa_mode", None)
    return status == "A" and mode in (None, "", "A", "D", "P", "R", "F")


def _good_form(text: str, bare_ok: bool) -> bool:
    if not text.startswith(("$", "!")) or not text.isprintable():
        return False
    if "*" not in text:
        try:
            return bare_ok and pynmea2.parse(text, check=False) is not None
        except (pynmea2.ParseError, ValueError):
            return False
    body, _, given = text[1:].rpartition("*")
    try:
        return int(given, 16) == pynmea2.NMEASentence.checksum(body) and len(given) == 2
    except ValueError:
        return False


def reference(data: bytes, bare_ok: bool = False) -> Reference:
    ref = Reference()
    for line in lines(data):
        try:
            text = line.decode("ascii")
        except UnicodeDecodeError:
            ref.bad += 1
            continue
        if len(line) > MAX_LINE or not _good_form(text, bare_ok):
            ref.bad += 1
            continue
        try:
            msg = pynmea2.parse(text, check=not bare_ok)
        except (pynmea2.ParseError, ValueError, TypeError):
            continue
        kind = type(msg).__name__
        if kind not in POSITION_SENTENCES:
            continue
        if not _valid(msg):
            ref.no_fix += 1
            continue
        try:
            if msg.lat and msg.lon and msg.lat_dir in ("N", "S") and msg.lon_dir in ("E", "W"):
                ref.positions.setdefault(kind, []).append((msg.latitude, msg.longitude))
        except (ValueError, AttributeError):
            continue
    return ref


def model_text(devices: dict[str, Path], port: int = 7171) -> str:
    """One nmea sensor per capture, reading every position sentence's lat and lon."""
    vars_ = " ".join(
        f'{s.lower()}_{c}("deg", float64) from sentence {s}.{c};'
        for s in POSITION_SENTENCES
        for c in ("lat", "lon")
    )
    sensors = "\n".join(
        f'Sensor {name} kind nmea on "{path}"'
        + (" { checksum = optional; }" if name in {_name(b) for b in BARE} else "")
        + f" measures {{ {vars_} }}"
        for name, path in devices.items()
    )
    publishers = " ".join(
        f"Publisher p_{name}(0.1, "
        + ", ".join(
            f'"c.{name}.{s.lower()}_{c}"' for s in POSITION_SENTENCES for c in ("lat", "lon")
        )
        + ");"
        for name in devices
    )
    return (
        f"Drone c {{ Sensors {{ {sensors} }} }}\n"
        f'PubBroker("127.0.0.1":{port}, "/tmp/unused"); '
        f'SubBroker("127.0.0.1":{port + 1}, "/tmp/unused");\n'
        f"Publishers {{ {publishers} }}\n"
    )


def _name(file: str) -> str:
    return "r_" + "".join(c if c.isalnum() else "_" for c in file.removesuffix(".log")).lower()


def sensor_name(path: Path) -> str:
    return _name(path.name)

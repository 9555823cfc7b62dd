"""``modd up --link tcp|udp|serial --radio SPEC``: the transport of a local
run and the emulated radio in its path (docs/operations.md, "Rehearsing a
mission over an emulated radio").

- ``--link`` overrides the model's transport. Over udp the PubBroker listens
  on the model's PubBroker endpoint (UDP); over serial ``modd up`` starts
  ``modd-radio --serial``, which creates the two pseudo-terminals (the base
  station's and the drone's) and relays between them, and the generated
  configs name those devices.
- ``--radio "rate=3600,loss=0.05,latency_ms=80"`` puts the emulator in the
  path: over udp as a relay on a free loopback port that the SubBroker sends
  to; over serial between the two pseudo-terminals.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from .ports import free_port
from .radio.channel import RadioSpec

RADIO_START_S = 10.0


class LinkSetupError(ValueError):
    """A --link / --radio combination that cannot run; the message says why."""


def check(link: str | None, radio: str | None, model: dict[str, Any]) -> str:
    """The transport of the run; LinkSetupError for a bad combination."""
    transport = link or model.get("link", {}).get("transport", "tcp")
    if radio is not None:
        try:
            RadioSpec.parse(radio)
        except ValueError as exc:
            raise LinkSetupError(f"--radio: {exc}") from None
        if transport == "tcp":
            raise LinkSetupError(
                "--radio emulates a radio of datagrams: use it with --link udp or --link serial"
            )
    return str(transport)


def apply(model: dict[str, Any], transport: str, devices: tuple[str, str] | None) -> None:
    """Set the run's transport (and, over serial, the two devices) in ``model``."""
    link = model.setdefault("link", {})
    link["transport"] = transport
    if transport != "serial":
        for key in ("device", "droneDevice", "baud"):
            link.pop(key, None)
    if devices is not None:
        link["device"], link["droneDevice"] = devices


def radio_argv(
    bin_dir: Path, transport: str, radio: str | None, target: tuple[str, int]
) -> tuple[list[str], tuple[str, int] | None]:
    """The emulator's command line and, over udp, the relay endpoint the
    SubBroker sends to (None over serial)."""
    argv = [str(bin_dir / "modd-radio"), "--report", "10"]
    if radio:
        argv += ["--radio", radio]
    if transport == "serial":
        return [*argv, "--serial"], None
    relay = ("127.0.0.1", free_port("udp"))
    return [*argv, "--udp", f"{relay[0]}:{relay[1]}", "--to", f"{target[0]}:{target[1]}"], relay


def wait_devices(log: Path, timeout_s: float = RADIO_START_S) -> tuple[str, str]:
    """The (base, drone) pseudo-terminals the serial emulator prints first."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if log.exists():
            for line in log.read_text(errors="replace").splitlines():
                if line.startswith("base=") and " drone=" in line:
                    base, drone = line.split()
                    return base.partition("=")[2], drone.partition("=")[2]
        time.sleep(0.05)
    raise LinkSetupError(f"modd-radio printed no pseudo-terminals in {timeout_s:g} s; see {log}")

"""The MAVLink dialect the bridge and the simulated autopilot speak: pymavlink's
generated ``ardupilotmega`` module for MAVLink 2 (a superset of ``common``, so
both ArduPilot and PX4 messages decode; MAVLink 1 frames decode too).

Kept in one place so that every module names messages the same way.

Example::

    >>> message_class("ATTITUDE").fieldnames[:2]
    ['time_boot_ms', 'roll']
"""

from __future__ import annotations

from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # type: ignore[import-untyped]

#: The generated module itself (constants such as ``mavlink.MAV_CMD_SET_MESSAGE_INTERVAL``).
MAV: Any = mavlink

_BY_NAME: dict[str, Any] = {cls.msgname: cls for cls in mavlink.mavlink_map.values()}


def message_class(name: str) -> Any | None:
    """The pymavlink message class for a message name such as ``GLOBAL_POSITION_INT``."""
    return _BY_NAME.get(name)


def message_id(name: str) -> int:
    cls = message_class(name)
    if cls is None:
        raise KeyError(f"unknown MAVLink message {name}")
    return int(cls.id)


def result_name(result: int) -> str:
    """``MAV_RESULT_DENIED`` for 2, ``MAV_RESULT_17`` for a value outside the enum."""
    entry = mavlink.enums["MAV_RESULT"].get(result)
    return str(entry.name) if entry is not None else f"MAV_RESULT_{result}"


def parser(source_system: int = 0, source_component: int = 0) -> Any:
    """A MAVLink parser/packer that never raises on bad input: bad frames come out as
    ``BAD_DATA`` messages and frames of unknown ids as ``UNKNOWN_<id>`` messages."""
    mav = mavlink.MAVLink(None, srcSystem=source_system, srcComponent=source_component)
    mav.robust_parsing = True
    return mav

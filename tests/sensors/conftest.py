"""The instrument tests import their harness (devices.py) from this folder, and the
MAVLink tests' one (processes, the PubBroker, the archive read with the official
MCAP reader) from tests/mavlink, and the runtime tests' base station."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "mavlink"))
sys.path.insert(0, str(HERE.parent / "runtime"))  # pubbroker_harness: a base station

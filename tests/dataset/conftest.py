"""The dataset tests import their shared checks (checkers.py) from this folder and
the instruments' pseudo-terminals (devices.py) from tests/sensors."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "sensors"))

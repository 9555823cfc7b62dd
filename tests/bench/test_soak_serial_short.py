"""The serial soak (tests/bench/soak_serial.py), shortened to 60 s: scenario 1 over
serial through modd-radio at 10 % loss; every window of every subscriber delivered
live or by backfill and equal to the archive (the official mcap reader), the samples
sent = the archive's, `--gaps` again finds nothing, and every process's RSS flat
over the last half. The one-hour run is `make bench SOAK=1`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@pytest.mark.slow
def test_soak_serial_short() -> None:
    out = subprocess.run(
        [sys.executable, str(HERE / "soak_serial.py"), "--seconds", "60", "--every", "2"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    print(out.stdout[-4000:])
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-4000:]
    assert "all checks held" in out.stdout
    assert "--gaps again: 0 windows; --from/--to again: 0" in out.stdout
    sent = next(ln for ln in out.stdout.splitlines() if ln.startswith("samples: sent"))
    n = sent.split()[2].rstrip(",")
    assert int(n) > 0 and f"archived {n} " in sent, sent

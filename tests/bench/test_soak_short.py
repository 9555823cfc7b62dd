"""The soak (tests/bench/soak.py), shortened to 75 s: every fault of its
schedule once (link cut and stall, kill -9 of the SubBroker, the PubBroker and
the backend, a backend killed mid-deploy, a lying and a flooding publisher),
then its checks: counters that reconcile (those of every PubBroker run, kill -9 included,
against what its files hold), every archive read completely by
python mcap and @mcap/core, no deploy record pending and the drone running
what the last acked one says. The 30-minute run is `make bench SOAK=1`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@pytest.mark.slow
def test_soak_short() -> None:
    out = subprocess.run(
        [sys.executable, str(HERE / "soak.py"), "--seconds", "75"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    print(out.stdout[-4000:])
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-4000:]
    assert "all checks held" in out.stdout
    assert "deploy records:" in out.stdout and "0 pending" in out.stdout
    assert "read completely by python mcap and @mcap/core: yes" in out.stdout
    assert "every PubBroker run (2, 1 ended by kill -9)" in out.stdout

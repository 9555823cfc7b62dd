"""`modd up MODEL --simulate --link udp|serial --radio SPEC`: the run's link
over a datagram transport through the emulated radio; every subscription of
scenario 1 is delivered at its rate, and the processes stop by PID."""

from __future__ import annotations

import re
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import pytest

# scenario 1's subscriptions and their periods (ns)
PERIODS = {
    "sub_1": 2_000_000_000,
    "sub_2": 2_000_000_000,
    **{f"sub_{i}": 250_000_000 for i in range(3, 8)},
}
WATCH_S = 9.0


@pytest.mark.parametrize("link", ["udp", "serial"])
def test_up_over_a_datagram_link_through_the_radio(
    link: str,
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    import modd

    model = tmp_path / "model.modd"
    port = free_port()
    model.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{port}')
    )
    zenoh_port = free_port()
    run = tmp_path / "run"
    up = subprocess.Popen(
        [
            modd_cmd,
            "up",
            str(model),
            "--simulate",
            "--link",
            link,
            "--radio",
            "rate=3600,loss=0.05,latency_ms=80,seed=3",
            "--workdir",
            str(run),
            "--zenoh-listen",
            f"tcp/127.0.0.1:{zenoh_port}",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    ends: dict[str, set[int]] = {name: set() for name in PERIODS}
    try:
        wait_for(run / "logs" / "subbroker.log", "running", 60)
        viewer = run / "credentials" / "viewer.cred"
        subs = {
            name: modd.subscribe(
                "usv", name, connect=f"tcp/127.0.0.1:{zenoh_port}", credentials=viewer
            )
            for name in PERIODS
        }
        time.sleep(2.0)  # the simulator's first samples, the first datagram
        for sub in subs.values():
            sub.collect(duration_s=0.01)
        start = time.monotonic()
        while time.monotonic() - start < WATCH_S:
            for name, sub in subs.items():
                ends[name] |= {
                    v.end_ns for v in sub.collect(duration_s=0.05) if v.value is not None
                }
        for sub in subs.values():
            sub.close()
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
    assert up.returncode == 0, out
    # every subscription at its rate: its windows one period apart, no hole between the
    # first and the last (the radio loses 5 %, the NACKs repair it), as many as the
    # watch holds (a window at either edge may fall outside it)
    for name, period in PERIODS.items():
        got = sorted(ends[name])
        assert got, (name, out)
        assert all(b - a == period for a, b in zip(got, got[1:], strict=False)), (name, got)
        assert len(got) >= WATCH_S * 1e9 // period - 2, (name, len(got), out)
    pb_config = (run / "generated" / "operator" / "pubbroker.json").read_text()
    assert f'"transport": "{link}"' in pb_config
    assert "started radio" in out and "stopped radio" in out
    assert len(re.findall(r"\(pid (\d+)\)", out)) >= 4, out
    assert "passed" in (run / "logs" / "radio.log").read_text()

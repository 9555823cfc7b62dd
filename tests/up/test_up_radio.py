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

RATE_SUBS = ("sub_3", "sub_4", "sub_5", "sub_6", "sub_7")  # every 0.25 s in scenario 1


@pytest.mark.parametrize("link", ["udp", "serial"])
def test_up_over_a_datagram_link_through_the_radio(link: str, scenarios_dir: Path,
                                                   tmp_path: Path, modd_cmd: str,
                                                   free_port: Callable[[], int],
                                                   wait_for: Callable[..., None]) -> None:
    import modd

    model = tmp_path / "model.modd"
    port = free_port()
    model.write_text((scenarios_dir / "scenario1.modd").read_text()
                     .replace('"127.0.0.1":7171', f'"127.0.0.1":{port}'))
    zenoh_port = free_port()
    run = tmp_path / "run"
    up = subprocess.Popen([modd_cmd, "up", str(model), "--simulate", "--link", link,
                           "--radio", "rate=3600,loss=0.05,latency_ms=80,seed=3",
                           "--workdir", str(run), "--zenoh-listen",
                           f"tcp/127.0.0.1:{zenoh_port}"],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    counts = dict.fromkeys(RATE_SUBS, 0)
    try:
        wait_for(run / "logs" / "subbroker.log", "running", 60)
        viewer = run / "credentials" / "viewer.cred"
        subs = {name: modd.subscribe("usv", name, connect=f"tcp/127.0.0.1:{zenoh_port}",
                                     credentials=viewer) for name in RATE_SUBS}
        time.sleep(2.0)  # the simulator's first samples, the first datagram
        for sub in subs.values():
            sub.collect(duration_s=0.01)
        start = time.monotonic()
        while time.monotonic() - start < 6.0:
            for name, sub in subs.items():
                counts[name] += len([v for v in sub.collect(duration_s=0.05)
                                     if v.value is not None])
        for sub in subs.values():
            sub.close()
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
    assert up.returncode == 0, out
    # 4 values/s each; the radio loses 5 %, the NACKs repair it within ~2 s
    assert all(n >= 4 * 6.0 * 0.75 for n in counts.values()), (counts, out)
    pb_config = (run / "generated" / "operator" / "pubbroker.json").read_text()
    assert f'"transport": "{link}"' in pb_config
    assert "started radio" in out and "stopped radio" in out
    assert len(re.findall(r"\(pid (\d+)\)", out)) >= 4, out
    assert "passed" in (run / "logs" / "radio.log").read_text()

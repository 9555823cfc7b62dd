"""A `modd up` killed hard (SIGKILL, no chance to stop its children) leaves no
process of its run behind: each child is tied to it (PR_SET_PDEATHSIG) and stops
on SIGTERM; an orphaned instrument reader would otherwise keep the devices of the
next run (docs/operations.md, "modd up restarts")."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from support.processes import pid_alive  # noqa: E402

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"


def _running(pid: int) -> bool:
    """Alive and not a zombie waiting for a parent to reap it."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            state = f.read().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, IndexError):
        return False
    return pid_alive(pid) and state != "Z"


def test_kill_9_of_modd_up_leaves_no_process_after_2_s(
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model = tmp_path / "demo.modd"
    model.write_text(DEMO.read_text().replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}'))
    out_path = tmp_path / "up.out"
    with out_path.open("w") as out:
        up = subprocess.Popen(
            [
                modd_cmd,
                "up",
                str(model),
                "--simulate",
                "--workdir",
                str(tmp_path / "run"),
                "--zenoh-listen",
                f"tcp/127.0.0.1:{free_port()}",
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    pids: dict[str, int] = {}
    try:
        wait_for(tmp_path / "run" / "logs" / "subbroker.log", "config 1 running", 30)
        text = out_path.read_text()
        pids = {name: int(pid) for name, pid in re.findall(r"started (\w+) \(pid (\d+)\)", text)}
        assert {"pubbroker", "subbroker", "sensors", "simulator", "bridge"} <= set(pids), text
        os.kill(up.pid, signal.SIGKILL)
        up.wait(5)
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline and any(_running(p) for p in pids.values()):
            time.sleep(0.05)
        left = {name: pid for name, pid in pids.items() if _running(pid)}
        assert not left, f"still running 2 s after kill -9 of modd up: {left}"
    finally:
        if up.poll() is None:
            up.kill()
            up.wait()
        for pid in pids.values():  # whatever the test found left, it stops
            if _running(pid):
                os.kill(pid, signal.SIGKILL)

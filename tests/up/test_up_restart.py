"""`modd up` restarts a process that dies (kill -9 of the SubBroker) with a backoff, logged,
while the others keep running; Ctrl-C (SIGINT) still stops every process, the restarted one
included (docs/operations.md, "modd up restarts")."""

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

from support.processes import pid_alive as _alive  # noqa: E402


def _log_count(path: Path, text: str) -> int:
    return path.read_text(errors="replace").count(text) if path.exists() else 0


def test_a_killed_subbroker_is_restarted_and_ctrl_c_stops_everything(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model = tmp_path / "model.modd"
    model.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}')
    )
    out_path = tmp_path / "up.out"
    sub_log = tmp_path / "run" / "logs" / "subbroker.log"
    with open(out_path, "w") as out:
        up = subprocess.Popen(
            [
                modd_cmd,
                "up",
                str(model),
                "--workdir",
                str(tmp_path / "run"),
                "--zenoh-listen",
                f"tcp/127.0.0.1:{free_port()}",
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
            text=True,
        )
    restarted = 0
    pids: dict[str, int] = {}
    try:
        wait_for(sub_log, "config 1 running", 30)
        text = out_path.read_text()
        pids = {name: int(pid) for name, pid in re.findall(r"started (\w+) \(pid (\d+)\)", text)}
        os.kill(pids["subbroker"], signal.SIGKILL)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and _log_count(sub_log, " running (epoch") < 2:
            time.sleep(0.1)
        # the restarted SubBroker authenticated again and sent the PubBroker its config
        assert _log_count(sub_log, " running (epoch") == 2, out_path.read_text()
        text = out_path.read_text()
        assert "subbroker exited (-9)" in text and "restarting it in 1 s" in text, text
        [restarted] = [int(p) for p in re.findall(r"restarted subbroker \(pid (\d+)\)", text)]
        assert _alive(restarted) and _alive(pids["pubbroker"]) and up.poll() is None
    finally:
        up.send_signal(signal.SIGINT)
        up.wait(60)
    text = out_path.read_text()
    assert up.returncode == 0, text
    assert "stopped pubbroker" in text and "stopped subbroker" in text
    assert not _alive(restarted) and not _alive(pids["pubbroker"])

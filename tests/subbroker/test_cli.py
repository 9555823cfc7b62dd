"""The modd-subbroker command: bad configurations exit 2 naming the cause;
SIGTERM stops it cleanly (exit 0) even while the link is down; SIGUSR1
prints the threads' stacks and leaves it running."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from subbroker_harness import SCENARIOS, free_port, wait_port

CLI = [sys.executable, "-m", "modd.subbroker.cli"]


def run(args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, *args], capture_output=True, text=True, timeout=30, env={**os.environ, **env}
    )


def test_bad_config_and_missing_key_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "sb.toml"
    bad.write_text('model = "nowhere.modd"\n')
    r = run(["--config", str(bad)], {})
    assert r.returncode == 2 and "nowhere.modd" in r.stderr
    env = {k: v for k, v in os.environ.items() if k != "MODD_LINK_KEY"}
    r = subprocess.run(
        [*CLI, "--model", str(SCENARIOS / "scenario1.modd")],
        capture_output=True,
        text=True,
        timeout=30,
        env=env,
    )
    assert r.returncode == 2 and "MODD_LINK_KEY" in r.stderr
    r = run(["--model", str(SCENARIOS / "scenario1.modd"), "--link", "nope"], {})
    assert r.returncode == 2 and "--link" in r.stderr


def test_model_mode_runs_and_stops_on_sigterm(tmp_path: Path) -> None:
    zport = free_port()
    p = subprocess.Popen(
        [
            *CLI,
            "--model",
            str(SCENARIOS / "scenario1.modd"),
            "--link",
            f"127.0.0.1:{free_port()}",
            "--zenoh-listen",
            f"tcp/127.0.0.1:{zport}",
            "--no-tcp-delivery",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "MODD_LINK_KEY": "a-test-link-key-of-16+"},
    )
    try:
        wait_port(zport)
        time.sleep(0.5)
        os.kill(p.pid, signal.SIGUSR1)  # prints the threads' stacks and goes on
        time.sleep(0.3)
        os.kill(p.pid, signal.SIGTERM)
        out, _ = p.communicate(timeout=10)
    finally:
        if p.poll() is None:
            os.kill(p.pid, signal.SIGKILL)
            p.wait(5)
    assert p.returncode == 0, out
    assert "Connection refused" in out and "stopping" in out
    assert "most recent call first" in out and "_run" in out  # the link thread's stack


def test_client_mode_listens_nowhere_unless_told() -> None:
    from modd.subbroker.cli import _parser, build_config

    model = str(SCENARIOS / "scenario1.modd")
    client = build_config(
        _parser().parse_args(
            ["--model", model, "--zenoh-mode", "client", "--zenoh-connect", "tcp/127.0.0.1:7999"]
        )
    )
    assert client.zenoh.listen == () and client.zenoh.connect == ("tcp/127.0.0.1:7999",)
    told = build_config(
        _parser().parse_args(
            ["--model", model, "--zenoh-mode", "client", "--zenoh-listen", "tcp/127.0.0.1:7998"]
        )
    )
    assert told.zenoh.listen == ("tcp/127.0.0.1:7998",)
    peer = build_config(_parser().parse_args(["--model", model]))
    assert peer.zenoh.listen == ("tcp/127.0.0.1:7447",)  # the embedded default

"""`modd up MODEL` runs MODEL: a deployment a workbench made in an earlier
run of the same drone (kept in the run directory's state/) is resumed only
with ``--resume``, and both cases are said on the terminal and on the
SubBroker's first lines (issue 23: a scenario run silently ran a stale
deployment)."""

from __future__ import annotations

import signal
import subprocess
from collections.abc import Callable
from pathlib import Path

from modd.subbroker.kept import Deployment, StateDir
from modd_model import load_model


def _up(modd_cmd: str, model: Path, run: Path, port: int, *more: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [
            modd_cmd,
            "up",
            str(model),
            "--workdir",
            str(run),
            "--zenoh-listen",
            f"tcp/127.0.0.1:{port}",
            *more,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def _stop(up: subprocess.Popen[str]) -> str:
    up.send_signal(signal.SIGTERM)
    out, _ = up.communicate(timeout=60)
    assert up.returncode == 0, out
    return out


def test_up_runs_model_and_resumes_a_kept_deployment_only_when_told(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model = tmp_path / "model.modd"
    port = free_port()
    model.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{port}')
    )
    run = tmp_path / "run"
    # an earlier run's deployment: scenario 2 (19 streams), revision 5 by "operator"
    kept = load_model(scenarios_dir / "scenario2.modd")
    meta = Deployment("deploy", 3, 5, "n-1", "operator", 1_700_000_000_000_000_000)
    StateDir(run / "state").save_deployment(kept, meta)
    log = run / "logs" / "subbroker.log"

    up = _up(modd_cmd, model, run, free_port())
    try:
        wait_for(log, "config 1 running", 30)
        text = log.read_text()
        assert "NOT resuming the deployment kept in" in text and "revision 5" in text
        assert "the configured model" in text and "19 streams" not in text
    finally:
        out = _stop(up)
    assert "is not resumed (--resume resumes it)" in out, out

    log.unlink()
    up = _up(modd_cmd, model, run, free_port(), "--resume")
    try:
        wait_for(log, "19 streams sent", 30)
        first = "\n".join(log.read_text().splitlines()[:3])
        assert "RESUMING the deployment kept in" in first, first
        assert "revision 5 of project 3" in first and "by operator" in first
        assert "DIFFERS from the configured model" in first
    finally:
        out = _stop(up)
    assert "--resume: the SubBroker resumes the deployment kept in" in out, out

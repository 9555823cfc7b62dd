"""`modd link cut|restore|status` (a rehearsed outage on a `modd up --simulate`
run): the run's rehearsal folder gets or loses its link-cut file; a directory
with no such run is said, with how to name the run."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from modd_launch.drone import rehearsal_dir


def _modd(
    modd_cmd: str, *args: str, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [modd_cmd, "link", *args], capture_output=True, text=True, timeout=60, env=env
    )


def test_cut_restore_status(tmp_path: Path, modd_cmd: str) -> None:
    folder = rehearsal_dir(tmp_path)  # what modd up --simulate makes
    assert folder.stat().st_mode & 0o777 == 0o700
    res = _modd(modd_cmd, "cut", "--workdir", str(tmp_path))
    assert res.returncode == 0 and "is cut" in res.stdout, res.stderr
    assert (folder / "link-cut").exists()
    assert "is cut" in _modd(modd_cmd, "status", "--workdir", str(tmp_path)).stdout
    res = _modd(modd_cmd, "restore", "--workdir", str(tmp_path))
    assert res.returncode == 0 and "is up" in res.stdout
    assert not (folder / "link-cut").exists()
    (folder / "link-cut").touch()
    rehearsal_dir(tmp_path)  # the next modd up starts with the link restored
    assert not (folder / "link-cut").exists()


def test_default_run_of_a_drone_and_no_run(tmp_path: Path, modd_cmd: str) -> None:
    env = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}
    res = _modd(modd_cmd, "cut", "--drone", "usv", env=env)
    assert res.returncode == 1
    assert f"{tmp_path}/modd-up/usv/rehearsal is not there" in res.stderr
    assert "--workdir DIR" in res.stderr and not (tmp_path / "modd-up").exists()
    rehearsal_dir(tmp_path / "modd-up" / "usv")
    assert _modd(modd_cmd, "cut", "--drone", "usv", env=env).returncode == 0

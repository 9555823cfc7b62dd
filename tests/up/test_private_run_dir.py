"""`modd up`'s run directory is private (docs/security.md, "Local surfaces"):
made 0700 under the user's runtime directory; one owned by another user or
reached through a symbolic link is refused, and nothing is written there."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest
from modd_launch.drone import run_dir

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"


def test_default_run_dir_is_private(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    d = run_dir(None, "usv")
    assert d == tmp_path / "modd-up" / "usv"
    for p in (d, d.parent):
        assert p.stat().st_mode & 0o777 == 0o700 and p.stat().st_uid == os.getuid()


def test_symlinked_run_dir_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, modd_cmd: str
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    victim = tmp_path / "victim"
    victim.mkdir()
    (tmp_path / "modd-up").mkdir(mode=0o700)
    (tmp_path / "modd-up" / "usv").symlink_to(victim)  # planted by someone else
    with pytest.raises(ValueError, match="symbolic link"):
        run_dir(None, "usv")
    env = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}
    res = subprocess.run(
        [modd_cmd, "up", str(DEMO)], env=env, capture_output=True, text=True, timeout=60
    )
    assert res.returncode == 1 and "symbolic link" in res.stderr, res.stderr
    assert list(victim.iterdir()) == []
    link = tmp_path / "link"
    link.symlink_to(victim)
    with pytest.raises(ValueError, match="symbolic link"):
        run_dir(str(link), "usv")


@pytest.mark.skipif(os.getuid() != 0, reason="giving a directory to another user needs root")
def test_run_dir_of_another_user_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    theirs = tmp_path / "modd-up"
    theirs.mkdir(mode=0o755)
    os.chown(theirs, 65534, 65534)
    with pytest.raises(ValueError, match="owned by uid 65534"):
        run_dir(None, "usv")
    assert not (theirs / "usv").exists()

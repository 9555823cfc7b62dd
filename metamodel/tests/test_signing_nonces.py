"""Deploy nonces kept across restarts (docs/security.md, "Signed deploys"):
a signed request accepted once is refused when replayed to a new
NonceGuard reading the same file; the file stays private and bounded."""

from __future__ import annotations

import os
import stat
import time
from pathlib import Path

from modd_model.signing import NonceGuard, sign_request

KEY = b"k" * 32


def test_replay_refused_after_a_restart(tmp_path: Path) -> None:
    path = tmp_path / "deploy-nonces"
    request = sign_request(KEY, {"model": {"drone": {"name": "usv"}}, "revision": 3})
    assert NonceGuard(path=path).verify(KEY, request) is None
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    restarted = NonceGuard(path=path)  # a new process reading the same file
    reason = restarted.verify(KEY, request)
    assert reason is not None and "replayed" in reason
    other = sign_request(KEY, {"model": {"drone": {"name": "usv"}}, "revision": 4})
    assert restarted.verify(KEY, other) is None
    # in memory only (the old behaviour): the replay would pass
    assert NonceGuard().verify(KEY, request) is None


def test_expired_nonces_leave_the_file(tmp_path: Path) -> None:
    path = tmp_path / "deploy-nonces"
    old = f"{time.time_ns() - 10**12}-{'a' * 32}"  # 1000 s ago
    path.write_text(old + "\nnot a nonce\n")
    guard = NonceGuard(path=path)
    assert path.read_text() == ""
    for revision in range(200):
        guard.verify(KEY, sign_request(KEY, {"revision": revision}))
    assert len(path.read_text().splitlines()) <= 2 * 200 + 64


def test_unrecordable_nonce_refuses(tmp_path: Path) -> None:
    path = tmp_path / "deploy-nonces"
    guard = NonceGuard(path=path)
    path.unlink()
    os.symlink(tmp_path / "elsewhere", path)  # O_NOFOLLOW: not written through a link
    reason = guard.verify(KEY, sign_request(KEY, {"revision": 1}))
    assert reason is not None and "cannot be recorded" in reason
    assert not (tmp_path / "elsewhere").exists()


def test_malformed_nonce_refused() -> None:
    request = {"revision": 1, "nonce": "1\n2"}
    from modd_model.signing import signature

    request["signature"] = signature(KEY, request)
    assert NonceGuard().verify(KEY, request) == "the deploy request's nonce is malformed"

"""The credentials directory: made at the first start, kept afterwards; a file deleted
by hand is made anew with a new secret and announced (``remade``, a warning), never
re-created in silence, since copies handed out before stop working."""

from __future__ import annotations

import logging
import stat
from pathlib import Path

import pytest
from modd.zenoh_auth import CredentialStore


def test_first_start_makes_every_file_private_and_announces_nothing(tmp_path: Path) -> None:
    store = CredentialStore(tmp_path / "cred").ensure()
    assert store.remade == []
    for name in ("subbroker.cred", "backend.cred", "viewer.cred", "deploy.key"):
        assert stat.S_IMODE((tmp_path / "cred" / name).stat().st_mode) == 0o600


def test_a_deleted_viewer_credential_is_made_anew_and_announced(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    CredentialStore(tmp_path / "cred").ensure()
    old = (tmp_path / "cred" / "viewer.cred").read_text()
    (tmp_path / "cred" / "viewer.cred").unlink()
    with caplog.at_level(logging.WARNING, logger="modd.zenoh"):
        store = CredentialStore(tmp_path / "cred").ensure()
    assert store.remade == ["viewer.cred"]
    assert (tmp_path / "cred" / "viewer.cred").read_text() != old
    assert "viewer.cred" in caplog.text and "no longer work" in caplog.text
    assert CredentialStore(tmp_path / "cred").ensure().remade == []  # kept from then on

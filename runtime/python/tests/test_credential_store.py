"""The credentials directory: made at the first start, kept afterwards; a file deleted
by hand is made anew with a new secret and announced (``remade``, a warning), never
re-created in silence, since copies handed out before stop working."""

from __future__ import annotations

import logging
import stat
from pathlib import Path

import pytest
from modd.zenoh_auth import CredentialStore, remade_notes


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


def test_a_remade_file_is_noted_with_its_time_for_the_downloads_panel(tmp_path: Path) -> None:
    CredentialStore(tmp_path / "cred").ensure()
    assert remade_notes(tmp_path / "cred") == {}  # a first start is no re-creation
    (tmp_path / "cred" / "viewer.cred").unlink()
    CredentialStore(tmp_path / "cred").ensure()
    notes = remade_notes(tmp_path / "cred")
    assert list(notes) == ["viewer.cred"]
    assert notes["viewer.cred"].endswith("Z") and notes["viewer.cred"][:2] == "20"
    assert stat.S_IMODE((tmp_path / "cred" / "remade.json").stat().st_mode) == 0o600
    (tmp_path / "cred" / "deploy.key").unlink()
    CredentialStore(tmp_path / "cred").ensure()
    assert sorted(remade_notes(tmp_path / "cred")) == ["deploy.key", "viewer.cred"]  # kept, added


def test_an_unreadable_note_reads_as_none(tmp_path: Path) -> None:
    (tmp_path / "remade.json").write_text("{not json")
    assert remade_notes(tmp_path) == {}
    (tmp_path / "remade.json").write_text(
        '{"../etc/passwd": "x", "viewer.cred": 5, "backend.cred": "t"}'
    )
    assert remade_notes(tmp_path) == {"backend.cred": "t"}

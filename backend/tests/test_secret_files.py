"""Secrets given by file (the first admin's password, ``modd push``'s
password) are read like every key file: a small regular file, not through a
final symlink, a warning when others may read it (``--admin-password-file
/dev/zero`` read without a bound before). A database URL with a password
in argv warns, as ``--admin-password`` does: the process list shows argv to
every local user (docs/security.md, "Sessions")."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import pytest
from modd_backend.cli import parse_args
from modd_backend.push import PushError, _password


def _files(tmp_path: Path) -> tuple[Path, list[Path]]:
    good = tmp_path / "pw"
    good.write_text("the-password-123\n")
    good.chmod(0o600)
    link = tmp_path / "link"
    link.symlink_to(good)
    big = tmp_path / "big"
    big.write_bytes(b"p" * (64 * 1024 + 1))
    return good, [Path("/dev/zero"), link, big, tmp_path]


def test_admin_password_file_is_a_small_regular_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.delenv("MODD_ADMIN_PASSWORD", raising=False)
    good, bad = _files(tmp_path)
    args = ["--data", str(tmp_path)]
    assert (
        parse_args([*args, "--admin-password-file", str(good)]).initial_admin_password
        == "the-password-123"
    )
    for path in bad:
        with pytest.raises(SystemExit):
            parse_args([*args, "--admin-password-file", str(path)])
    good.chmod(0o644)
    with caplog.at_level(logging.WARNING):
        parse_args([*args, "--admin-password-file", str(good)])
    assert "read by group or others" in caplog.text


def test_push_password_file_is_a_small_regular_file(tmp_path: Path) -> None:
    good, bad = _files(tmp_path)
    assert _password(argparse.Namespace(password_file=str(good))) == "the-password-123"
    for path in bad:
        with pytest.raises(PushError, match="password.file"):
            _password(argparse.Namespace(password_file=str(path)))


def test_database_url_with_a_password_in_argv_warns(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("MODD_DATABASE_URL", raising=False)
    url = "postgresql+psycopg://modd:s3cret@127.0.0.1/modd"
    parse_args(["--data", str(tmp_path), "--database-url", url])
    assert "--database-url shows the database password" in capsys.readouterr().err
    parse_args(["--data", str(tmp_path), "--database-url", "postgresql+psycopg://modd@/modd"])
    monkeypatch.setenv("MODD_DATABASE_URL", url)
    parse_args(["--data", str(tmp_path)])  # from the environment: no warning
    assert "warning" not in capsys.readouterr().err

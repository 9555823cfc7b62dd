"""Restore is safe (docs/security.md, "Restore"): a file that is not an
intact store of this schema is refused before anything is replaced, and a
running backend keeps answering; a restore ends every session, those of
the backup's time included (a session logged out after the backup stays
out); what a restore writes is 0600 in a 0700 directory."""

from __future__ import annotations

import io
import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app
from modd_backend.backup import backup, restore

from .conftest import ADMIN_PASSWORD, login
from .test_postgres import postgres_url  # noqa: F401  (the fixture)


def _settings(data: Path) -> Settings:
    return Settings(data_dir=data, zenoh_enabled=False, initial_admin_password=ADMIN_PASSWORD)


@pytest.fixture
def copy(tmp_path: Path) -> Path:
    """A backup of a store with one project."""
    settings = _settings(tmp_path / "origin")
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        assert c.post(
            "/api/projects", headers=h, json={"name": "kept", "model": {"text": "model m"}}
        ).status_code in (201, 422)
    out = tmp_path / "store.backup"
    backup(settings.effective_database_url, out)
    return out


def _hostile(copy: Path, tmp_path: Path, sql: str) -> Path:
    bad = tmp_path / "bad.backup"
    bad.write_bytes(copy.read_bytes())
    with sqlite3.connect(bad) as db:
        db.executescript(sql)
    db.close()
    return bad


@pytest.mark.parametrize(
    "case", ["empty", "not sqlite", "other schema", "trigger", "view", "unknown migration"]
)
def test_a_bad_copy_is_refused_and_the_running_store_kept(
    case: str, copy: Path, tmp_path: Path
) -> None:
    bad = {
        "empty": lambda: _write(tmp_path / "empty.backup", b""),
        "not sqlite": lambda: _write(tmp_path / "x.backup", b"PGDMP" + bytes(range(256)) * 8),
        "other schema": lambda: _hostile(copy, tmp_path, "CREATE TABLE notes (x TEXT);"),
        "trigger": lambda: _hostile(
            copy,
            tmp_path,
            "CREATE TRIGGER t AFTER INSERT ON users BEGIN DELETE FROM projects; END;",
        ),
        "view": lambda: _hostile(copy, tmp_path, "CREATE VIEW v AS SELECT * FROM users;"),
        "unknown migration": lambda: _hostile(
            copy, tmp_path, "UPDATE alembic_version SET version_num='9999';"
        ),
    }[case]()
    settings = _settings(tmp_path / "live")
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        with pytest.raises(SystemExit, match="nothing restored"):
            restore(settings.effective_database_url, bad)
        assert c.get("/api/projects", headers=h).status_code == 200  # untouched, same session


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def test_restore_revokes_every_session(tmp_path: Path) -> None:
    settings = _settings(tmp_path / "data")
    out = tmp_path / "store.backup"
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        before = login(c, "admin", ADMIN_PASSWORD)  # a session inside the backup
        backup(settings.effective_database_url, out)
        assert c.post("/api/auth/logout", headers=before).status_code == 204
        assert c.get("/api/auth/me", headers=before).status_code == 401
        during = login(c, "admin", ADMIN_PASSWORD)  # live at restore time
        restore(settings.effective_database_url, out)
        assert c.get("/api/auth/me", headers=before).status_code == 401  # not resurrected
        assert c.get("/api/auth/me", headers=during).status_code == 401  # revoked
        assert c.get("/api/auth/me", headers=login(c, "admin", ADMIN_PASSWORD)).status_code == 200


def test_restore_into_a_new_directory_is_private(copy: Path, tmp_path: Path) -> None:
    data = tmp_path / "fresh" / "data"
    res = subprocess.run(
        [sys.executable, "-m", "modd_backend.cli", "restore", "--data", str(data), str(copy)],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=lambda: os.umask(0o022),
    )  # an operator's usual umask
    assert res.returncode == 0, res.stderr
    assert data.stat().st_mode & 0o777 == 0o700
    for f in data.iterdir():
        assert f.stat().st_mode & 0o077 == 0, f"{f} is readable by others"
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "modd_backend.cli",
            "restore",
            "--data",
            str(data),
            str(tmp_path / "nothing"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode != 0 and "no backup at" in res.stderr


def _psql(url: str, sql: str) -> None:
    subprocess.run(
        ["psql", "--dbname", url.replace("+psycopg", ""), "-v", "ON_ERROR_STOP=1", "-c", sql],
        check=True,
        capture_output=True,
    )


def test_a_hostile_postgresql_dump_runs_nothing(
    postgres_url: str,  # noqa: F811
    tmp_path: Path,
) -> None:
    """A dump of this schema plus a function that runs a program on the
    server (called when its materialised view is refreshed, as pg_restore
    does): restoring it runs nothing and changes nothing. A clean dump
    restores its rows, without its sessions."""
    marker = Path(tempfile.mkdtemp(prefix="modd-pwn-")) / "ran"
    os.chmod(marker.parent, 0o777)  # the server runs as postgres
    base = postgres_url.rsplit("/", 1)[0]
    for name in ("hostile", "target"):
        _psql(postgres_url, f"CREATE DATABASE {name}")
    hostile, target = f"{base}/hostile", f"{base}/target"
    for url in (hostile, target):
        settings = Settings(
            data_dir=tmp_path / url.rsplit("/", 1)[1],
            database_url=url,
            zenoh_enabled=False,
            initial_admin_password=ADMIN_PASSWORD,
        )
        with TestClient(create_app(settings, out=io.StringIO())) as c:
            login(c, "admin", ADMIN_PASSWORD)
    clean = tmp_path / "clean.dump"
    backup(hostile, clean)
    _psql(
        hostile,
        f"""
        CREATE TABLE pwn_out (x text);
        CREATE FUNCTION pwn() RETURNS int LANGUAGE plpgsql AS $$
        BEGIN
          IF current_database() <> 'hostile' THEN
            EXECUTE 'COPY pwn_out FROM PROGRAM ''touch {marker}''';
          END IF;
          RETURN 1;
        END $$;
        CREATE MATERIALIZED VIEW pwn_view AS SELECT pwn() AS v;""",
    )
    bad = tmp_path / "hostile.dump"
    backup(hostile, bad)
    with pytest.raises(SystemExit, match="nothing restored"):
        restore(target, bad)
    assert not marker.exists(), "the dump ran a program on the server"
    restore(target, clean)
    settings = Settings(data_dir=tmp_path / "again", database_url=target, zenoh_enabled=False)
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        login(c, "admin", ADMIN_PASSWORD)  # the dump's admin, its password
    shutil.rmtree(marker.parent, ignore_errors=True)

"""A store several backends share: N backends starting together on an empty
database (SQLite file, PostgreSQL) all start, with exactly one first admin;
backup and restore give back exactly what was backed up."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app
from modd_backend.backup import backup, restore
from modd_backend.db import Store
from modd_backend.tables import User
from sqlalchemy import func, select

from .conftest import ADMIN_PASSWORD, login
from .test_postgres import postgres_url  # noqa: F401  (the fixture)

STARTERS = 6

# One backend's start-up (migrations, first admin) in its own process.
_START = """
import io, sys
from pathlib import Path
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app
s = Settings(data_dir=Path(sys.argv[1]), database_url=sys.argv[2] or None,
             zenoh_enabled=False, initial_admin_password="pw-" + "x" * 12)
with TestClient(create_app(s, out=io.StringIO()), base_url="http://127.0.0.1") as c:
    r = c.get("/api/health")
    assert r.status_code == 200, r.text
"""


def _start_together(data: Path, url: str) -> list[subprocess.CompletedProcess[str]]:
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _START, str(data), url],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for _ in range(STARTERS)
    ]
    out = []
    try:
        for p in procs:  # each imports the whole backend: minutes on a loaded machine
            stdout, stderr = p.communicate(timeout=300)
            out.append(subprocess.CompletedProcess(p.args, p.returncode, stdout, stderr))
    finally:
        for p in procs:  # a test that fails stops what it started
            if p.poll() is None:
                p.kill()
                p.communicate()
    return out


def _admins(url: str) -> int:
    store = Store.open(url)
    try:
        with store.session() as db:
            return int(db.scalar(select(func.count()).select_from(User)) or 0)
    finally:
        store.close()


def test_backends_start_together_on_an_empty_sqlite_store(tmp_path: Path) -> None:
    results = _start_together(tmp_path, "")
    assert [r.returncode for r in results] == [0] * STARTERS, [r.stderr[-800:] for r in results]
    assert _admins(f"sqlite:///{tmp_path / 'modd.sqlite3'}") == 1


def test_backends_start_together_on_an_empty_postgresql(postgres_url: str, tmp_path: Path) -> None:  # noqa: F811
    url = postgres_url.rsplit("/", 1)[0] + "/together"
    subprocess.run(
        [
            "psql",
            "--dbname",
            postgres_url.replace("+psycopg", ""),
            "-c",
            "CREATE DATABASE together",
        ],
        check=True,
        capture_output=True,
    )
    results = _start_together(tmp_path, url)
    assert [r.returncode for r in results] == [0] * STARTERS, [r.stderr[-800:] for r in results]
    assert _admins(url) == 1


def _project_names(c: TestClient, h: dict[str, str]) -> list[str]:
    return sorted(p["name"] for p in c.get("/api/projects", headers=h).json())


@pytest.mark.parametrize("database", ["sqlite", "postgresql"])
def test_backup_then_restore(
    database: str, request: pytest.FixtureRequest, tmp_path: Path, scenario1: str
) -> None:
    url = None if database == "sqlite" else request.getfixturevalue("postgres_url")
    settings = Settings(
        data_dir=tmp_path / "data",
        database_url=url,
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
    )
    copy = tmp_path / "store.backup"
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        for name in (f"kept_{database}", f"also_kept_{database}"):
            r = c.post(
                "/api/projects", headers=h, json={"name": name, "model": {"text": scenario1}}
            )
            assert r.status_code == 201, r.text
        before = _project_names(c, h)
        # a consistent copy while the service runs
        backup(settings.effective_database_url, copy)
        assert copy.stat().st_mode & 0o777 == 0o600
        c.post(
            "/api/projects",
            headers=h,
            json={"name": f"after_{database}", "model": {"text": scenario1}},
        )
        assert _project_names(c, h) != before
    restore(settings.effective_database_url, copy)
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        assert _project_names(c, h) == before


def test_backup_cli_reports_a_missing_database(tmp_path: Path) -> None:
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "modd_backend.cli",
            "backup",
            "--data",
            str(tmp_path / "nothing"),
            str(tmp_path / "out.backup"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode != 0 and "no database at" in res.stderr
    assert not (tmp_path / "out.backup").exists()

"""The store on a real PostgreSQL server (Debian's postgresql package),
started by this test on a loopback port in a temporary directory and stopped
with pg_ctl: migrations, versions with optimistic concurrency, deployments.
Skipped, saying so, when the server binaries are not installed."""

from __future__ import annotations

import io
import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from modd.ports import free_port
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, login

PG_BINS = sorted(Path("/usr/lib/postgresql").glob("*/bin"))


def _as_postgres(cmd: list[str]) -> list[str]:
    """initdb refuses to run as root: run as the package's ``postgres`` user."""
    if os.geteuid() == 0:
        return ["runuser", "-u", "postgres", "--", *cmd]
    return cmd


@pytest.fixture(scope="module")
def postgres_url() -> Iterator[str]:
    if not PG_BINS or not (PG_BINS[-1] / "initdb").exists():
        # scripts/setup.sh installs postgresql; without it this is a setup bug, not a skip.
        pytest.fail(
            "PostgreSQL server binaries are missing: run make setup (apt-get install postgresql)"
        )
    bins = PG_BINS[-1]
    # Not under pytest's tmp tree: that is private to root, and the server runs
    # as postgres.
    root = Path(tempfile.mkdtemp(prefix="modd-pg-"))
    data = root / "data"
    if os.geteuid() == 0:
        shutil.chown(root, "postgres")
    port = free_port()
    subprocess.run(
        _as_postgres(
            [str(bins / "initdb"), "-D", str(data), "-U", "modd", "--auth=trust", "-E", "UTF8"]
        ),
        check=True,
        capture_output=True,
    )
    opts = f"-h 127.0.0.1 -p {port} -k {root}"
    subprocess.run(
        _as_postgres(
            [
                str(bins / "pg_ctl"),
                "-D",
                str(data),
                "-o",
                opts,
                "-w",
                "-l",
                str(root / "pg.log"),
                "start",
            ]
        ),
        check=True,
        capture_output=True,
    )
    try:
        yield f"postgresql+psycopg://modd@127.0.0.1:{port}/postgres"
    finally:
        subprocess.run(
            _as_postgres([str(bins / "pg_ctl"), "-D", str(data), "-m", "fast", "-w", "stop"]),
            capture_output=True,
        )
        shutil.rmtree(root, ignore_errors=True)


def test_store_on_postgresql(postgres_url: str, tmp_path: Path, scenario1: str) -> None:
    settings = Settings(
        data_dir=tmp_path,
        database_url=postgres_url,
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        pid = c.post(
            "/api/projects", headers=h, json={"name": "pg", "model": {"text": scenario1}}
        ).json()["id"]
        model = c.get(f"/api/projects/{pid}/model", headers=h).json()["model"]
        model["link"] = {"maxBuffer": 500}
        ok = c.put(
            f"/api/projects/{pid}/model",
            headers=h,
            json={"base_revision": 1, "model": model, "message": "on pg"},
        )
        assert ok.status_code == 200 and ok.json()["revision"] == 2
        stale = c.put(
            f"/api/projects/{pid}/model", headers=h, json={"base_revision": 1, "model": model}
        )
        assert stale.status_code == 409 and stale.json()["current_revision"] == 2
        versions = c.get(f"/api/projects/{pid}/versions", headers=h).json()
        assert [v["message"] for v in versions] == ["on pg", "created"]
        assert c.get(f"/api/projects/{pid}/deployed-diff", headers=h).json()["deployed"] is None
    assert not (tmp_path / "modd.sqlite3").exists()  # the URL was used, not the default file
    # A second start on the same database: migrations are idempotent, no second admin.
    out = io.StringIO()
    with TestClient(create_app(settings, out=out)) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        assert len(c.get("/api/projects", headers=h).json()) == 1
    assert out.getvalue() == ""


def test_concurrent_saves_on_postgresql(postgres_url: str, tmp_path: Path, scenario1: str) -> None:
    """Same race as test_saverace.py on PostgreSQL (read committed)."""
    from .saverace import race_saves

    settings = Settings(
        data_dir=tmp_path,
        database_url=postgres_url,
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        for name, role in (("des", "designer"), ("sci", "scientist")):
            c.post(
                "/api/users",
                headers=h,
                json={"username": name, "password": f"pw-{name}-12345", "roles": [role]},
            )
        designer = login(c, "des", "pw-des-12345")
        scientist = login(c, "sci", "pw-sci-12345")
        bad, statuses = race_saves(c, h, designer, scientist, scenario1, rounds=30)
        assert bad == [], f"unauthorised revisions stored: {bad}"
        assert set(statuses) <= {"attack 403", "attack 409", "honest 200", "honest 409"}, statuses

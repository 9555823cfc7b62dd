"""The application shell: OpenAPI, first admin, settings, the CLI's loopback
default, migrations."""

from __future__ import annotations

import asyncio
import io
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import httpx2 as httpx
import pytest
from fastapi.testclient import TestClient
from modd.ports import free_port
from modd_backend import Settings, create_app
from modd_backend.cli import parse_args
from modd_backend.tables import Base
from sqlalchemy import create_engine, inspect


def test_openapi_lists_every_router(client: TestClient) -> None:
    spec = client.get("/openapi.json").json()
    paths = set(spec["paths"])
    for p in (
        "/api/auth/login",
        "/api/users",
        "/api/projects",
        "/api/projects/{project_id}/model",
        "/api/plan",
        "/api/validate",
    ):
        assert p in paths
    assert "HTTPBearer" in spec["components"]["securitySchemes"]


def test_first_admin_password_is_drawn_and_printed_once(tmp_path: Path) -> None:
    settings = Settings(data_dir=tmp_path, zenoh_enabled=False)
    out = io.StringIO()
    with TestClient(create_app(settings, out=out)) as c:
        printed = re.search(r"password (\S+) \(shown once", out.getvalue())
        assert printed, out.getvalue()
        r = c.post("/api/auth/login", json={"username": "admin", "password": printed.group(1)})
        assert r.status_code == 200
        assert r.json()["user"]["roles"] == ["admin"]
    again = io.StringIO()
    with TestClient(create_app(settings, out=again)):
        pass
    assert again.getvalue() == ""  # second start: the admin exists, nothing printed


def test_migrations_match_the_tables(settings: Settings, client: TestClient) -> None:
    engine = create_engine(settings.effective_database_url)
    insp = inspect(engine)
    for table in Base.metadata.sorted_tables:
        migrated = {c["name"] for c in insp.get_columns(table.name)}
        assert migrated == {c.name for c in table.columns}, table.name
    assert "alembic_version" in insp.get_table_names()
    engine.dispose()


def test_background_loops_end_on_the_stop_flag_without_a_cancellation() -> None:
    # Python 3.11's wait_for can swallow a cancellation; the flag alone must end
    # the loops, or the app's shutdown waits on them (a CI run hung 600 s).
    from types import SimpleNamespace

    from modd_backend.app import _ping_database

    pings: list[int] = []

    class Store:
        def session(self) -> object:
            pings.append(1)
            raise RuntimeError("no store here")

    async def run() -> None:
        stop = asyncio.Event()
        state = SimpleNamespace(store=Store(), database="?")
        task = asyncio.create_task(_ping_database(state, stop, every_s=0.01))  # type: ignore[arg-type]
        await asyncio.sleep(0.05)
        stop.set()
        await asyncio.wait_for(task, 2)  # never cancelled: ends by the flag
        assert state.database == "error" and pings

    asyncio.run(run())


def test_cli_defaults_to_loopback(tmp_path: Path) -> None:
    s = parse_args(["--data", str(tmp_path)])
    assert s.host == "127.0.0.1"
    assert s.data_dir == tmp_path
    assert s.zenoh_connect == ("tcp/127.0.0.1:7447",)
    assert s.tile_origins == ()


def test_cli_viewer_origins(tmp_path: Path) -> None:
    s = parse_args(["--data", str(tmp_path), "--viewer-origin", "http://127.0.0.1:8123"])
    assert s.cors_origins == ("http://127.0.0.1:8123",)
    with pytest.raises(SystemExit):
        parse_args(["--data", str(tmp_path), "--viewer-origin", "http://x/path"])


def test_cli_tile_origins(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("MODD_TILE_ORIGINS", raising=False)
    s = parse_args(
        [
            "--data",
            str(tmp_path),
            "--tile-origin",
            "https://tile.openstreetmap.org",
            "--tile-origin",
            "http://127.0.0.1:8123",
        ]
    )
    assert s.tile_origins == ("https://tile.openstreetmap.org", "http://127.0.0.1:8123")
    monkeypatch.setenv("MODD_TILE_ORIGINS", "https://a.tile.example https://b.tile.example")
    assert parse_args(["--data", str(tmp_path)]).tile_origins == (
        "https://a.tile.example",
        "https://b.tile.example",
    )
    with pytest.raises(SystemExit):
        parse_args(["--data", str(tmp_path), "--tile-origin", "https://t.example/{z}/{x}/{y}.png"])
    assert "--tile-origin" in capsys.readouterr().err


@pytest.mark.slow
def test_console_script_serves_the_api(tmp_path: Path) -> None:
    port = free_port()
    exe = Path(sys.executable).with_name("modd-backend")
    log = tmp_path / "backend.log"
    with log.open("w") as out:
        proc = subprocess.Popen(
            [
                str(exe),
                "--host",
                "127.0.0.1",
                "--port",
                str(port),
                "--data",
                str(tmp_path),
                "--no-zenoh",
                "--admin-password",
                "cli-admin-pw",
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    try:
        deadline = time.monotonic() + 20
        while True:
            try:
                r = httpx.post(
                    f"http://127.0.0.1:{port}/api/auth/login",
                    json={"username": "admin", "password": "cli-admin-pw"},
                )
                break
            except httpx.TransportError:
                assert proc.poll() is None, log.read_text()
                assert time.monotonic() < deadline, "the backend did not start"
                time.sleep(0.1)
        assert r.status_code == 200
        assert (tmp_path / "modd.sqlite3").is_file()
    finally:
        os.kill(proc.pid, signal.SIGTERM)
        proc.wait(timeout=10)


def test_health_needs_no_login_and_checks_the_database(client: TestClient) -> None:
    r = client.get("/api/health")
    assert r.status_code == 200, r.text
    assert r.json() == {
        "status": "ok",
        "database": "ok",
        "zenoh": "disabled",
        "scene": False,
        "ready": True,
        "saturated": False,
        "heavy_in_flight": 0,
        "heavy_limit": 8,
    }


def test_admin_password_from_file_or_environment_not_argv(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The first admin's password need not be in argv (/proc/PID/cmdline is
    readable by every local user): a file or $MODD_ADMIN_PASSWORD; the
    argv option still works but warns."""
    secret = tmp_path / "admin.pw"
    secret.write_text("from-a-file-123\n")
    monkeypatch.delenv("MODD_ADMIN_PASSWORD", raising=False)
    s = parse_args(["--data", str(tmp_path), "--admin-password-file", str(secret)])
    assert s.initial_admin_password == "from-a-file-123"
    monkeypatch.setenv("MODD_ADMIN_PASSWORD", "from-the-env-123")
    assert parse_args(["--data", str(tmp_path)]).initial_admin_password == "from-the-env-123"
    monkeypatch.setenv("MODD_DATABASE_URL", "postgresql+psycopg://u:pw@127.0.0.1/modd")
    assert "pw@" in str(parse_args(["--data", str(tmp_path)]).database_url)  # not in argv
    assert "warning" not in capsys.readouterr().err
    parse_args(["--data", str(tmp_path), "--admin-password", "in-argv-123"])
    assert "process list" in capsys.readouterr().err

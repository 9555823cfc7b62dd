"""``modd push`` against a real workbench served by uvicorn on loopback (no
zenoh: deploy answers 503 here; tests/run covers an acked deploy)."""

from __future__ import annotations

import io
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import uvicorn
from modd.ports import free_port
from modd_backend import Settings, create_app
from modd_model.cli import main as modd

from .conftest import ADMIN_PASSWORD

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("push"),
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
    )
    port = free_port()
    config = uvicorn.Config(
        create_app(settings, out=io.StringIO()), host="127.0.0.1", port=port, log_level="warning"
    )
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not srv.started:
        assert time.monotonic() < deadline, "uvicorn did not start"
        time.sleep(0.05)
    yield f"http://127.0.0.1:{port}"
    srv.should_exit = True
    thread.join(10)


def push(server: str, *args: str) -> int:
    return modd(["push", *args, "--server", server])


def test_push_creates_then_revises_only_on_change(
    server: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MODD_PASSWORD", ADMIN_PASSWORD)
    model = tmp_path / "mission.modd"
    model.write_text(DEMO.read_text())
    assert push(server, str(model)) == 0
    assert "project 'mission' (id 1) at revision 1" in capsys.readouterr().out
    assert push(server, str(model)) == 0  # same content: no new revision
    assert "at revision 1" in capsys.readouterr().out
    model.write_text(DEMO.read_text().replace("1.0, AVERAGE);", "2.0, AVERAGE);"))
    assert push(server, str(model), "--message", "slower water") == 0
    assert "at revision 2" in capsys.readouterr().out


def test_push_reports_refusals_with_where(
    server: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MODD_PASSWORD", "not-the-password")
    assert push(server, str(DEMO), "--project", "x") == 1
    assert "HTTP 401" in capsys.readouterr().err

    monkeypatch.setenv("MODD_PASSWORD", ADMIN_PASSWORD)
    broken = tmp_path / "broken.modd"
    broken.write_text(DEMO.read_text().replace("Publishers {", "Publishers {{", 1))
    assert push(server, str(broken)) == 1
    err = capsys.readouterr().err
    assert "HTTP 422" in err and "broken.modd:" in err

    assert push(server, str(DEMO), "--project", "demo", "--deploy") == 1
    assert "HTTP 503" in capsys.readouterr().err  # no zenoh session: no deploy

    monkeypatch.delenv("MODD_PASSWORD")
    assert push(server, str(DEMO)) == 1
    assert "no password" in capsys.readouterr().err


def test_push_to_nothing_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    port = free_port()  # closed again: nothing listens there
    monkeypatch.setenv("MODD_PASSWORD", "x")
    assert push(f"http://127.0.0.1:{port}", str(DEMO)) == 1
    assert "cannot reach" in capsys.readouterr().err


def test_push_if_new_keeps_an_existing_project(
    server: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`make run` restarted: the user's revisions stay the head."""
    monkeypatch.setenv("MODD_PASSWORD", ADMIN_PASSWORD)
    model = tmp_path / "restart.modd"
    model.write_text(DEMO.read_text())
    assert push(server, str(model), "--if-new") == 0
    out = capsys.readouterr().out
    assert "project 'restart'" in out and "at revision 1" in out
    model.write_text(DEMO.read_text().replace("1.0, AVERAGE);", "2.0, AVERAGE);"))
    assert push(server, str(model)) == 0  # the user's own revision 2
    model.write_text(DEMO.read_text())  # the stock model again
    assert push(server, str(model), "--if-new") == 0
    assert "exists: kept as it is, running revision 2" in capsys.readouterr().out
    assert push(server, str(model)) == 0  # without --if-new: the stock model is revision 3
    assert "at revision 3" in capsys.readouterr().out

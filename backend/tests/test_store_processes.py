"""The hot routes' store work in store processes (storeproc.py, issue 41):
the same answers as in the service's own threads (every status, the saved
event), none of it in the service's threads, and a killed store process
answered 503 with Retry-After and replaced."""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Iterator
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend import storeproc
from modd_backend.errors import ApiError
from modd_backend.tables import Session, utcnow
from sqlalchemy import update

from .conftest import ADMIN_PASSWORD, app_client, login


def _journey(client: TestClient, text: str) -> list[tuple[int, Any]]:
    """Every answer of the hot routes' statuses, the saved events included."""
    admin = login(client, "admin", ADMIN_PASSWORD)
    state = client.app.state.modd  # type: ignore[attr-defined]
    client.post(
        "/api/users",
        headers=admin,
        json={"username": "op", "password": "pw-op-123456", "roles": ["operator"]},
    )
    operator = login(client, "op", "pw-op-123456")
    pid = client.post("/api/projects", headers=admin, json={"name": "p", "model": {"text": text}})
    pid = pid.json()["id"]
    heard: list[dict[str, Any]] = []
    state.project_events.add(pid, heard.append)
    url = f"/api/projects/{pid}/model"
    head = client.get(url, headers=admin).json()
    broken = {**head["model"], "link": {**(head["model"].get("link") or {}), "maxBuffer": -5}}
    calls = [
        ("get", url, admin, None),
        ("put", url, admin, {"model": broken, "base_revision": 1, "message": "m"}),
        ("put", url, admin, {"model": broken, "base_revision": 1}),  # 409: stale
        ("put", url, admin, {"model": broken}),  # 422: no base revision
        ("put", url, operator, {"model": broken, "base_revision": 2}),  # 403
        ("get", url + "?revision=1", admin, None),
        ("get", url + "?revision=99", admin, None),  # 404
        ("get", f"/api/projects/{pid + 99}/model", admin, None),  # 404
        ("get", f"/api/projects/{pid}/versions", admin, None),
        ("get", url, {"Authorization": "Bearer nope"}, None),  # 401
    ]
    answers: list[tuple[int, Any]] = []
    for method, path, who, body in calls:
        r = client.request(method, path, headers=who, json=body)
        answers.append((r.status_code, r.json()))
    with state.store.session() as db:
        db.execute(update(Session).values(expires_at=utcnow() - timedelta(seconds=1)))
        db.commit()
    answers.append((client.get(url, headers=admin).status_code, None))  # 401: expired
    return [*answers, (0, heard)]


def _without_times(answers: list[tuple[int, Any]]) -> list[tuple[int, Any]]:
    def strip(v: Any) -> Any:
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if k not in ("created_at", "saved_at")}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v

    return [(s, strip(a)) for s, a in answers]


@pytest.fixture(scope="module")
def procs_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    with app_client(tmp_path_factory.mktemp("procs"), store_processes=2) as c:
        yield c


def test_store_processes_answer_as_the_threads_do(
    procs_client: TestClient, tmp_path: Path, scenario1: str
) -> None:
    state = procs_client.app.state.modd  # type: ignore[attr-defined]
    assert state.store_procs is not None and state.store_procs.processes == 2
    in_procs = _journey(procs_client, scenario1)
    with app_client(tmp_path) as threads_client:
        assert threads_client.app.state.modd.store_procs is None  # type: ignore[attr-defined]
        in_threads = _journey(threads_client, scenario1)
    assert [s for s, _ in in_procs] == [200, 200, 409, 422, 403, 200, 404, 404, 200, 401, 401, 0]
    assert _without_times(in_procs) == _without_times(in_threads)
    heard = in_procs[-1][1]
    assert heard == [
        {"type": "saved", "project": heard[0]["project"], "revision": 2}
        | {"author": "admin", "message": "m"}
    ]
    # none of it ran in the service's own store threads
    assert not state.store_threads._threads


def test_a_killed_store_process_is_503_then_replaced(
    procs_client: TestClient, scenario1: str
) -> None:
    admin = login(procs_client, "admin", ADMIN_PASSWORD)
    pid = procs_client.post(
        "/api/projects", headers=admin, json={"name": "k", "model": {"text": scenario1}}
    ).json()["id"]
    url = f"/api/projects/{pid}/model"
    assert procs_client.get(url, headers=admin).status_code == 200
    pool = procs_client.app.state.modd.store_procs._pool  # type: ignore[attr-defined]
    for child in list(pool._processes.values()):
        os.kill(child.pid, signal.SIGKILL)
    deadline = time.monotonic() + 30
    statuses = []
    while time.monotonic() < deadline:
        r = procs_client.get(url, headers=admin)
        statuses.append(r.status_code)
        if r.status_code == 200:
            break
        assert r.status_code == 503 and r.headers["retry-after"] == "1", r.text
        assert "store process stopped" in r.json()["detail"]
    assert statuses[-1] == 200 and 503 in statuses, statuses
    assert procs_client.app.state.modd.store_procs._pool is not pool  # type: ignore[attr-defined]


def test_store_processes_need_a_shared_store() -> None:
    assert storeproc.usable("sqlite:////tmp/x.sqlite3", 2)
    assert storeproc.usable("postgresql://u@h/db", 1)
    assert not storeproc.usable("sqlite:///:memory:", 2)
    assert not storeproc.usable("sqlite:////tmp/x.sqlite3", 0)
    with pytest.raises(ValueError, match="store_processes must be 0..16"):
        storeproc.StoreProcesses("sqlite:////tmp/x.sqlite3", 17)


def test_api_errors_cross_processes_whole() -> None:
    import pickle

    exc = ApiError(409, "stale", headers={"Retry-After": "1"}, current=3)
    back = pickle.loads(pickle.dumps(exc))
    assert (back.status, back.body, back.headers) == (409, exc.body, exc.headers)
    assert back.body == {"detail": "stale", "current": 3}


def test_the_cli_runs_2_store_processes_and_refuses_a_bad_count(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from modd_backend.cli import parse_args

    monkeypatch.delenv("MODD_STORE_PROCESSES", raising=False)
    assert parse_args([]).store_processes == 2
    assert parse_args(["--store-processes", "0"]).store_processes == 0
    monkeypatch.setenv("MODD_STORE_PROCESSES", "5")
    assert parse_args([]).store_processes == 5
    for bad in (["--store-processes", "17"], ["--store-processes", "two"]):
        with pytest.raises(SystemExit):
            parse_args(bad)
        assert "is not a count 0..16" in capsys.readouterr().err
    monkeypatch.setenv("MODD_STORE_PROCESSES", "-1")
    with pytest.raises(SystemExit):
        parse_args([])
    assert "'-1' is not a count 0..16" in capsys.readouterr().err


def _store_children(pid: int) -> set[int]:
    out = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            name, rest = stat.read_text().split("(", 1)[1].rsplit(")", 1)
        except (OSError, IndexError):
            continue
        if name == "modd-store" and rest.split()[1] == str(pid) and rest.split()[0] != "Z":
            out.add(int(stat.parent.name))
    return out


def _alive(pids: set[int]) -> set[int]:
    out = set()
    for p in pids:
        try:
            if Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z":
                out.add(p)
        except OSError:
            continue
    return out


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="Linux /proc")
def test_the_cli_starts_2_named_store_processes_that_end_when_it_is_killed(
    tmp_path: Path,
) -> None:
    """``modd-backend`` (as deployed): 2 children named ``modd-store`` once
    it answers; SIGKILLed, with no chance to stop them, they end within 5 s."""
    import subprocess
    import sys

    from modd.ports import free_port

    port = free_port()
    exe = Path(sys.executable).with_name("modd-backend")
    argv = [str(exe), "--port", str(port), "--data", str(tmp_path / "data"), "--no-zenoh"]
    argv += ["--scene-port", "-1", "--foxglove-port", "0", "--foxglove-replay-port", "0"]
    env = {**os.environ, "MODD_ADMIN_PASSWORD": ADMIN_PASSWORD}
    env.pop("MODD_STORE_PROCESSES", None)
    with (tmp_path / "backend.log").open("wb") as log:
        proc = subprocess.Popen(argv, env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 120
        while len(children := _store_children(proc.pid)) < 2:
            assert proc.poll() is None and time.monotonic() < deadline, "no store processes"
            time.sleep(0.2)
        assert len(children) == 2, children
        proc.kill()
        proc.wait(10)
        deadline = time.monotonic() + 5
        while _alive(children):
            assert time.monotonic() < deadline, f"store processes outlived the service: {children}"
            time.sleep(0.1)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)


def test_a_service_closed_while_its_store_processes_start_leaves_none(tmp_path: Path) -> None:
    """Closed at once (the processes still importing): none is left behind,
    none waits on a queue lock (the exit of the test process would hang)."""
    with app_client(tmp_path, store_processes=2) as c:
        pool = c.app.state.modd.store_procs._pool  # type: ignore[attr-defined]
        pids = {p.pid for p in pool._processes.values()}
    assert len(pids) == 2
    deadline = time.monotonic() + 10
    while _alive(pids):
        assert time.monotonic() < deadline, f"store processes left: {_alive(pids)}"
        time.sleep(0.1)

"""Every archive request is bounded (issue 41): a file named twice, a
resampling period under 1 ms or one giving more points than the cap, more
bytes than a request reads: a clear 4xx before any worker reads; notes name
no server path; an export whose client went away stops its worker within 2 s."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from fastapi.testclient import TestClient
from modd.ports import free_port
from modd_backend import archive_work

from .conftest import ADMIN_PASSWORD, Headers
from .served import serve
from .test_archive_export import URL, _model, archive_settings, client  # noqa: F401  (the fixture)
from .test_archives import write_archive

Client = tuple[TestClient, Headers, Path]


def test_an_export_naming_one_file_1000_times_is_refused(client: Client) -> None:  # noqa: F811
    c, h, _ = client
    body = {"model": _model(), "format": "csv", "files": ["run-0000.mcap"] * 1000}
    t0 = time.monotonic()
    r = c.post(URL, json=body, headers=h)
    assert r.status_code == 422, r.text
    assert "run-0000.mcap" in r.json()["detail"] and "once" in r.json()["detail"]
    assert time.monotonic() - t0 < 5


def test_a_file_reached_twice_through_a_link_is_refused(client: Client) -> None:  # noqa: F811
    c, h, root = client
    (root / "usv" / "alias.mcap").symlink_to(root / "usv" / "run-0000.mcap")
    body = {"model": _model(), "format": "csv", "files": ["run-0000.mcap", "alias.mcap"]}
    r = c.post(URL, json=body, headers=h)
    assert r.status_code == 422 and "same file" in r.json()["detail"]


@pytest.mark.parametrize("period", [1e-12, 1e-9, 0.0009])
def test_a_resampling_period_under_1_ms_is_refused(client: Client, period: float) -> None:  # noqa: F811
    c, h, _ = client
    r = c.post(URL, json={"model": _model(), "format": "csv", "resample_s": period}, headers=h)
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"] == ["body", "resample_s"]


def test_a_period_giving_more_points_than_the_cap_is_refused(
    client: Client,  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    c, h, _ = client
    monkeypatch.setattr(archive_work, "MAX_EXPORT_SAMPLES", 1000)
    # 500 samples at 25 Hz span 19.96 s: 19,960 points at 1 ms
    r = c.post(URL, json={"model": _model(), "format": "csv", "resample_s": 0.001}, headers=h)
    assert r.status_code == 422 and "points" in r.json()["detail"], r.text
    ok = c.post(URL, json={"model": _model(), "format": "csv", "resample_s": 0.1}, headers=h)
    assert ok.status_code == 200, ok.text


def test_more_bytes_than_a_request_reads_is_413(
    client: Client,  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    c, h, root = client
    size = (root / "usv" / "run-0000.mcap").stat().st_size
    monkeypatch.setattr(archive_work, "MAX_ARCHIVE_BYTES", size - 1)
    topic = "usv.accelerometer.accel_x"
    base = "/api/drones/usv/archives/run-0000.mcap"
    for r in (
        c.post(URL, json={"model": _model(), "format": "csv"}, headers=h),
        c.get(f"{base}/series", params={"topic": topic}, headers=h),
        c.get(f"{base}/csv", params={"topic": topic}, headers=h),
    ):
        assert r.status_code == 413 and f"{size - 1:,}" in r.json()["detail"], r.text


def test_more_samples_than_a_topic_request_holds_is_413(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_archive(tmp_path / "a.mcap", 101)
    topic = "usv.accelerometer.accel_x"
    monkeypatch.setattr(archive_work, "MAX_TOPIC_SAMPLES", 101)
    assert archive_work.series(tmp_path / "a.mcap", topic, None, None, 2000)[0] == 101
    monkeypatch.setattr(archive_work, "MAX_TOPIC_SAMPLES", 100)
    for work in (
        lambda: archive_work.series(tmp_path / "a.mcap", topic, None, None, 2000),
        lambda: archive_work.csv_text(tmp_path / "a.mcap", topic, None, None),
    ):
        with pytest.raises(archive_work.Refused) as caught:
            work()
        assert caught.value.status == 413 and "100" in str(caught.value)


def test_notes_and_errors_name_no_server_path(client: Client, tmp_path: Path) -> None:  # noqa: F811
    c, h, _ = client
    r = c.post(URL, json={"model": _model(), "format": "csv"}, headers=h)
    assert r.status_code == 200
    assert str(tmp_path) not in r.headers["x-modd-notes"]
    bad = c.post(URL, json={"model": _model(), "format": "csv", "start_ns": 1}, headers=h)
    assert str(tmp_path) not in bad.text


def _login(base: str, name: str, password: str) -> dict[str, str]:
    r = httpx.post(f"{base}/api/auth/login", json={"username": name, "password": password})
    assert r.status_code == 200, r.text
    return {"Authorization": f"Bearer {r.json()['token']}"}


@pytest.mark.slow
def test_one_users_100_requests_do_not_delay_anothers_series_past_30_s(tmp_path: Path) -> None:
    from concurrent.futures import ThreadPoolExecutor

    settings, root = archive_settings(tmp_path, 100_000, "big.mcap")
    csv = "/api/drones/usv/archives/big.mcap/csv"
    series = "/api/drones/usv/archives/big.mcap/series"
    params = {"topic": "usv.accelerometer.accel_x"}
    with serve(settings) as base:
        admin = _login(base, "admin", ADMIN_PASSWORD)
        r = httpx.post(
            f"{base}/api/users",
            headers=admin,
            json={"username": "bea", "password": "pw-bea-12345", "roles": ["scientist"]},
        )
        assert r.status_code == 201, r.text
        bea = _login(base, "bea", "pw-bea-12345")

        def burst(_: int) -> int:
            return httpx.get(f"{base}{csv}", params=params, headers=admin, timeout=120).status_code

        with ThreadPoolExecutor(100) as threads:
            codes = threads.map(burst, range(100))
            time.sleep(2.0)  # the burst is in: its share runs, the rest waits or is refused
            t0 = time.monotonic()
            mine = httpx.get(f"{base}{series}", params=params, headers=bea, timeout=120)
            waited = time.monotonic() - t0
            statuses = list(codes)
    assert mine.status_code == 200, mine.text
    assert mine.json()["total"] == 100_000
    assert waited < 30, waited
    assert set(statuses) <= {200, 429, 503} and 200 in statuses


def _workers(pid: int) -> set[int]:
    """The running archive worker processes of process ``pid`` (multiprocessing's
    spawned children; its resource tracker is not one, nor are its store
    processes, named ``modd-store``)."""
    out = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            name, rest = stat.read_text().split("(", 1)[1].rsplit(")", 1)
            fields = rest.split()
            argv = (stat.parent / "cmdline").read_bytes()
        except OSError:
            continue
        spawned = b"multiprocessing.spawn" in argv and name != "modd-store"
        if fields[1] == str(pid) and fields[0] != "Z" and spawned:
            out.add(int(stat.parent.name))
    return out


@contextmanager
def _backend(tmp: Path, archives: Path) -> Iterator[tuple[subprocess.Popen[bytes], str, str]]:
    """A real ``modd-backend`` process (uvicorn, as deployed) on loopback: the
    process, its base URL and the admin's token."""
    port = free_port()
    exe = Path(sys.executable).with_name("modd-backend")
    argv = [str(exe), "--port", str(port), "--data", str(tmp / "data"), "--no-zenoh"]
    argv += ["--scene-port", "-1", "--foxglove-port", "0", "--foxglove-replay-port", "0"]
    argv += ["--archives", str(archives), "--frontend", str(tmp / "none")]
    # no store processes: spawned children too, unnamed until their start-up ends
    argv += ["--store-processes", "0"]
    with (tmp / "backend.log").open("wb") as log:
        env = {**os.environ, "MODD_ADMIN_PASSWORD": ADMIN_PASSWORD}
        proc = subprocess.Popen(argv, env=env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            try:
                token = _login(base, "admin", ADMIN_PASSWORD)["Authorization"][7:]
                break
            except httpx.TransportError:
                assert proc.poll() is None and time.monotonic() < deadline, "no backend"
                time.sleep(0.2)
        yield proc, base, token
    finally:
        proc.terminate()
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


def _post(base: str, token: str, body: dict[str, Any]) -> socket.socket:
    """The export POSTed whole on a raw socket, its answer never read."""
    data = json.dumps(body).encode()
    host, port = base.removeprefix("http://").split(":")
    sock = socket.create_connection((host, int(port)))
    sock.sendall(
        f"POST {URL} HTTP/1.1\r\nHost: {host}:{port}\r\nAuthorization: Bearer {token}\r\n"
        f"Content-Type: application/json\r\nContent-Length: {len(data)}\r\n\r\n".encode()
        + data
    )
    return sock


def _running(pid: int, within_s: float) -> set[int]:
    deadline = time.monotonic() + within_s
    while not (found := _workers(pid)) and time.monotonic() < deadline:
        time.sleep(0.05)
    return found


@pytest.mark.slow
def test_an_abandoned_export_stops_its_worker_within_2_s(tmp_path: Path) -> None:
    """Over real HTTP (the ``modd-backend`` process): while the client holds
    its socket the export's worker reads on (the control: seconds of work);
    once it closes the socket, having sent the whole body and read nothing,
    the worker is gone within 2 s and the service answers."""
    _settings, root = archive_settings(tmp_path, 100_000, "big.mcap")
    for i in range(6):  # six more names of one large file: about 10 s of export
        os.link(root / "usv" / "big.mcap", root / "usv" / f"copy-{i}.mcap")
    files = ["big.mcap", *(f"copy-{i}.mcap" for i in range(6))]
    body = {"model": _model(), "format": "netcdf", "files": files}
    with _backend(tmp_path, root) as (proc, base, token):
        sock = _post(base, token, body)
        workers = _running(proc.pid, within_s=30)
        assert workers, "no archive worker started"
        time.sleep(2.0)
        assert _workers(proc.pid) & workers, "the export ended before the client left"
        sock.close()
        left_at = time.monotonic()
        while _workers(proc.pid) & workers:
            assert time.monotonic() - left_at < 2.0, "the abandoned export's worker still runs"
            time.sleep(0.05)
        assert httpx.get(f"{base}/api/health", timeout=10).status_code == 200
        time.sleep(1.0)  # the pool restarts no abandoned job: no worker reads again
        assert not _workers(proc.pid) - workers or _idle(_workers(proc.pid) - workers)


def _idle(pids: set[int]) -> bool:
    """The processes used (almost) no CPU over 0.5 s: a fresh, waiting worker."""

    def ticks() -> int:
        total = 0
        for pid in pids:
            try:
                f = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            total += int(f[11]) + int(f[12])  # utime + stime
        return total

    before = ticks()
    time.sleep(0.5)
    return ticks() - before <= 5  # clock ticks (1/100 s)

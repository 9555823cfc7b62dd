"""A backend killed (kill -9) in the middle of two deploys, against a real
base station (PubBroker, SubBroker): after its restart both records are
settled with what the drone runs within 10 s (issue 23, "backend kill -9
mid-deploy"): the one the drone took is acked, the one it refused is failed
and names what the drone runs; deployed-diff compares with the drone's report.

The deploys are held in the middle by stopping the PubBroker (SIGSTOP) while
the backend waits for the answers; the oracle is the SubBroker's status."""

from __future__ import annotations

import contextlib
import copy
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from modd.ports import free_port
from modd_model import load_model

from .station import Station
from .test_postgres import postgres_url  # noqa: F401  (the fixture)

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"
PASSWORD = "reconcile-admin-pw"

pytestmark = pytest.mark.slow


class Backend:
    """``modd-backend`` as its own process, so that it can be killed."""

    def __init__(self, tmp: Path, station: Station, database_url: str | None = None) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.cmd = [
            str(Path(sys.executable).with_name("modd-backend")),
            "--port",
            str(self.port),
            "--data",
            str(tmp / "data"),
            "--zenoh-connect",
            station.zenoh,
            "--zenoh-credentials",
            str(station.credentials.cred_file("backend")),
            "--deploy-key",
            str(station.credentials.deploy_key_file),
            "--deploy-timeout",
            "3",
            "--scene-port",
            "-1",
            "--foxglove-port",
            "0",
            "--frontend",
            str(tmp / "nofrontend"),
        ]
        if database_url:
            self.cmd += ["--database-url", database_url]
        self.log = tmp / "backend.log"
        self.proc: subprocess.Popen[bytes] | None = None
        self.headers: dict[str, str] = {}

    def start(self) -> float:
        """Start and log in; the monotonic time it first answered."""
        with self.log.open("ab") as out:
            self.proc = subprocess.Popen(
                self.cmd,
                stdout=out,
                stderr=subprocess.STDOUT,
                env={**os.environ, "MODD_ADMIN_PASSWORD": PASSWORD},
            )
        deadline = time.monotonic() + 60
        while True:
            try:
                r = httpx.post(
                    f"{self.url}/api/auth/login",
                    json={"username": "admin", "password": PASSWORD},
                    timeout=5,
                )
                break
            except httpx.TransportError:
                assert self.proc.poll() is None, self.log.read_text()
                assert time.monotonic() < deadline, "the backend did not start"
                time.sleep(0.05)
        up = time.monotonic()
        assert r.status_code == 200, r.text
        self.headers = {"Authorization": f"Bearer {r.json()['token']}"}
        return up

    def call(self, method: str, path: str, **kw: Any) -> httpx.Response:
        return httpx.request(method, self.url + path, headers=self.headers, timeout=30, **kw)

    def kill9(self) -> None:
        assert self.proc is not None
        os.kill(self.proc.pid, signal.SIGKILL)
        self.proc.wait(10)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                os.kill(self.proc.pid, signal.SIGKILL)
                self.proc.wait(5)


@pytest.fixture
def station(tmp_path: Path) -> Iterator[Station]:
    (tmp_path / "station").mkdir()
    st = Station(tmp_path / "station", load_model(DEMO))
    try:
        st.start()
        yield st
    finally:
        st.stop()


def _post_in_background(backend: Backend, path: str, body: dict[str, Any]) -> threading.Thread:
    def post() -> None:
        # the backend is killed while it waits: no answer is expected
        with contextlib.suppress(httpx.TransportError):
            backend.call("POST", path, json=body)

    t = threading.Thread(target=post, daemon=True)
    t.start()
    return t


def _wait(pred: Any, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not pred():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


@pytest.mark.parametrize("database", ["sqlite", "postgresql"])
def test_a_backend_killed_mid_deploy_settles_its_records_with_the_drone(
    tmp_path: Path, station: Station, database: str, request: pytest.FixtureRequest
) -> None:
    url = None
    if database == "postgresql":  # the store several backends share (issue 23)
        pg = request.getfixturevalue("postgres_url")
        url = pg.rsplit("/", 1)[0] + "/reconcile"
        subprocess.run(
            ["psql", "--dbname", pg.replace("+psycopg", ""), "-c", "CREATE DATABASE reconcile"],
            check=True,
            capture_output=True,
        )
    backend = Backend(tmp_path, station, url)
    backend.start()
    pubbroker, subbroker = station.procs[0], station.procs[1]
    try:
        model = copy.deepcopy(station.model)
        pid = backend.call(
            "POST", "/api/projects", json={"name": "mission", "model": {"model": model}}
        ).json()["id"]
        rev2 = copy.deepcopy(model)
        rev2["subscribers"][0]["periodS"] = "4"
        r = backend.call(
            "PUT", f"/api/projects/{pid}/model", json={"base_revision": 1, "model": rev2}
        )
        assert r.status_code == 200, r.text
        # revision 3 the PubBroker refuses: a topic it knows as float32 declared float64
        rev3 = copy.deepcopy(rev2)
        rev3["drone"]["sensors"][0]["variables"][0]["type"] = "float64"
        r = backend.call(
            "PUT", f"/api/projects/{pid}/model", json={"base_revision": 2, "model": rev3}
        )
        assert r.status_code == 200, r.text

        os.kill(pubbroker.p.pid, signal.SIGSTOP)  # CONFIG waits in its socket
        try:
            _post_in_background(backend, f"/api/projects/{pid}/deployments", {"revision": 2})
            assert subbroker.wait_log("deploy of revision 2 signed", 10), subbroker.log()
            _post_in_background(backend, f"/api/projects/{pid}/deployments", {"revision": 3})
            # (the SubBroker serves deploys one at a time: revision 3 waits for 2 there)
            _wait(
                lambda: len(backend.call("GET", f"/api/projects/{pid}/deployments").json()) == 2,
                10,
                "the second deploy was not recorded",
            )
            time.sleep(0.3)  # its query is on its way
            backend.kill9()
        finally:
            os.kill(pubbroker.p.pid, signal.SIGCONT)

        up = backend.start()

        def settled() -> bool:
            rows = backend.call("GET", f"/api/projects/{pid}/deployments").json()
            return len(rows) == 2 and all(d["status"] != "pending" for d in rows)

        _wait(settled, 10, "records still pending 10 s after the restart")
        took = time.monotonic() - up
        rows = {
            d["revision"]: d for d in backend.call("GET", f"/api/projects/{pid}/deployments").json()
        }
        assert rows[2]["status"] == "acked", rows[2]
        assert rows[3]["status"] == "failed", rows[3]
        assert "the drone runs revision 2" in rows[3]["error"], rows[3]
        print(f"\nreconciled {took:.2f} s after the restart")

        # the record equals what the drone reports, and the diff compares with it
        diff = backend.call("GET", f"/api/projects/{pid}/deployed-diff").json()
        assert diff["source"] == "drone", diff
        assert diff["drone_reports"]["revision"] == 2
        assert diff["drone_reports"]["project_id"] == pid
        assert diff["deployed"]["id"] == rows[2]["id"]
        assert [c["pointer"] for c in diff["changes"]] == ["/drone/sensors/0/variables/0/type"]
        assert "accepted" in pubbroker.log_path.read_text()
    finally:
        backend.stop()

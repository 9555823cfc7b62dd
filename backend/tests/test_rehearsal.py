"""The Monitor's *Cut the link* (a rehearsed outage): the rehearsal folder of the
`modd up --simulate` run whose archive the backend reads gets or loses its
link-cut file; operators and admins only; none without such a run."""

from __future__ import annotations

from pathlib import Path

from fastapi.testclient import TestClient
from modd.subbroker.rehearsal import is_cut
from modd_launch.drone import rehearsal_dir

from .conftest import ADMIN_PASSWORD, Headers, app_client, login


def _app(tmp_path: Path) -> TestClient:
    return app_client(tmp_path, archive_dir=tmp_path / "run" / "archive")


def _user(c: TestClient, admin: Headers, name: str, role: str) -> Headers:
    pw = f"pw-{name}-123456"
    r = c.post(
        "/api/users", headers=admin, json={"username": name, "password": pw, "roles": [role]}
    )
    assert r.status_code in (200, 201), r.text
    return login(c, name, pw)


def test_the_operator_cuts_and_restores_the_simulated_link(tmp_path: Path) -> None:
    (tmp_path / "run" / "archive").mkdir(parents=True)
    with _app(tmp_path) as c:
        admin = login(c, "admin", ADMIN_PASSWORD)
        url = "/api/drones/usv/rehearsal"
        assert c.get(url, headers=admin).json() == {"available": False, "cut": False}
        refused = c.post(url, headers=admin, json={"cut": True})
        assert refused.status_code == 409 and "modd up --simulate" in refused.text
        folder = rehearsal_dir(tmp_path / "run")  # modd up --simulate's
        op, sci = _user(c, admin, "op1", "operator"), _user(c, admin, "sci1", "scientist")
        assert c.get(url, headers=sci).json() == {"available": True, "cut": False}
        assert c.post(url, headers=sci, json={"cut": True}).status_code == 403
        assert not is_cut(folder)
        assert c.post(url, headers=op, json={"cut": True}).json() == {
            "available": True,
            "cut": True,
        }
        assert is_cut(folder) and c.get(url, headers=sci).json()["cut"] is True
        assert c.post(url, headers=admin, json={"cut": False}).json()["cut"] is False
        assert not is_cut(folder)
        assert c.post(url, headers=op, json={"cut": "yes"}).status_code == 422
        assert c.get(url).status_code == 401

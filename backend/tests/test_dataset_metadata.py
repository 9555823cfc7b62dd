"""A project's dataset metadata: saved as revisions beside the model (409 when
stale), checked with located errors (``key`` names the field), and carried by
an export that names the project (read back with netCDF4, not our writer)."""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend import create_app

from .conftest import ADMIN_PASSWORD, Headers, login
from .test_archive_export import MODEL, URL, _model, archive_settings

GOOD = {
    "title": "Bay survey",
    "creator_name": "Ana Example",
    "creator_email": "ana@marine.example.org",
    "naming_authority": "org.example.marine",
    "license": "CC-BY-4.0",
    "keywords": ["ocean", "motion"],
    "platform": {
        "name": "Survey boat",
        "id": "usv01",
        "vocabulary": "https://mmisw.org/ont/ioos/platform",
    },
    "instruments": {"accelerometer": {"make": "Bosch", "model": "BMI088", "serial_number": "42"}},
}


@pytest.fixture
def project(tmp_path: Path) -> Iterator[tuple[TestClient, Headers, str]]:
    settings, _ = archive_settings(tmp_path, 200, "run-0000.mcap")
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        r = c.post("/api/projects", headers=h, json={"name": "bay", "model": {"text": MODEL}})
        assert r.status_code in (200, 201), r.text
        yield c, h, f"/api/projects/{r.json()['id']}/dataset-metadata"


def _put(c: TestClient, h: Headers, url: str, doc: dict[str, Any], base: int) -> Any:
    return c.put(url, headers=h, json={"base_revision": base, "metadata": doc})


def test_none_saved_is_empty_and_names_what_is_asked(
    project: tuple[TestClient, Headers, str],
) -> None:
    c, h, url = project
    got = c.get(url, headers=h).json()
    assert got["revision"] == 0 and got["metadata"] == {} and got["author"] is None
    assert "creator_name" in got["missing"] and "license" in got["missing"]


@pytest.mark.parametrize(
    ("doc", "key", "words"),
    [
        ({"naming_authority": "modd"}, "naming_authority", "not reversed DNS"),
        ({"creator_email": "ana at example"}, "creator_email", "not an e-mail address"),
        ({"publisher_url": "data.example.org"}, "publisher_url", "not an http(s) URL"),
        ({"platform": {"colour": "red"}}, "platform.colour", "unknown key"),
        ({"instruments": {"ctd": {"make": "SBE"}}}, "instruments.ctd", "no sensor 'ctd'"),
        ({"qc": {"usv.accelerometer.accel_x": {"spike": {}}}}, "qc", "unknown test"),
    ],
)
def test_faults_are_located(
    project: tuple[TestClient, Headers, str], doc: dict[str, Any], key: str, words: str
) -> None:
    c, h, url = project
    r = _put(c, h, url, doc, 0)
    assert r.status_code == 422, r.text
    assert r.json()["key"] == key and words in r.json()["detail"], r.text
    assert c.get(url, headers=h).json()["revision"] == 0  # nothing stored


def test_revisions_and_a_stale_save(project: tuple[TestClient, Headers, str]) -> None:
    c, h, url = project
    first = _put(c, h, url, GOOD, 0)
    assert first.status_code == 200, first.text
    assert first.json()["revision"] == 1 and first.json()["author"] == "admin"
    assert "creator_name" not in first.json()["missing"]
    second = _put(c, h, url, GOOD | {"title": "Bay survey, day 2"}, 1)
    assert second.json()["revision"] == 2
    stale = _put(c, h, url, GOOD, 1)
    assert stale.status_code == 409 and stale.json()["current_revision"] == 2
    assert c.get(url, headers=h, params={"revision": 1}).json()["metadata"]["title"] == "Bay survey"
    assert c.get(url, headers=h).json()["metadata"]["title"] == "Bay survey, day 2"
    versions = c.get(f"{url}/versions", headers=h).json()
    assert [v["revision"] for v in versions] == [2, 1]
    assert c.get(url, headers=h, params={"revision": 9}).status_code == 404


def test_an_export_naming_the_project_carries_its_metadata(
    project: tuple[TestClient, Headers, str], tmp_path: Path
) -> None:
    import netCDF4

    c, h, url = project
    assert _put(c, h, url, GOOD, 0).status_code == 200
    pid = int(url.split("/")[3])
    r = c.post(URL, headers=h, json={"model": _model(), "format": "netcdf", "project": pid})
    assert r.status_code == 200, r.text
    assert 'filename="usv-dataset-' in r.headers["content-disposition"]
    (tmp_path / "p.nc").write_bytes(r.content)
    with netCDF4.Dataset(tmp_path / "p.nc") as ds:
        assert ds.getncattr("creator_email") == "ana@marine.example.org"
        assert ds.getncattr("naming_authority") == "org.example.marine"
        assert ds.getncattr("keywords") == "ocean, motion"
        inst = ds.variables["instrument_accelerometer"]
        assert inst.getncattr("make_model") == "Bosch BMI088"
        assert inst.getncattr("serial_number") == "42"
    plain = c.post(URL, headers=h, json={"model": _model(), "format": "netcdf"})
    (tmp_path / "q.nc").write_bytes(plain.content)
    with netCDF4.Dataset(tmp_path / "q.nc") as ds:
        assert "creator_email" not in ds.ncattrs()  # nothing invented

"""Archives: MCAP files written with the official ``mcap`` writer in the
PubBroker's layout (one channel per topic, JSON ``{"value": v}``), complete
or cut short; reading, reduction, CSV, download, and no way out of the
archive directory."""

from __future__ import annotations

import io
import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from mcap.writer import Writer
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, Headers, login

TOPICS = ("usv.accelerometer.accel_x", "usv.accelerometer.accel_z")
T0 = 1_700_000_000_000_000_000
STEP = 40_000_000  # 25 Hz


def write_archive(path: Path, samples: int) -> None:
    with path.open("wb") as f:
        w = Writer(f, chunk_size=4096)
        w.start(profile="", library="backend-tests")
        schema = w.register_schema(
            name="modd.float32",
            encoding="jsonschema",
            data=b'{"type":"object","properties":{"value":{"type":"number"}}}',
        )
        chans = {
            t: w.register_channel(topic=t, message_encoding="json", schema_id=schema)
            for t in TOPICS
        }
        for i in range(samples):
            for k, t in enumerate(TOPICS):
                value = float(i % 50) if k == 0 else -float(i)
                w.add_message(
                    chans[t],
                    log_time=T0 + i * STEP,
                    publish_time=T0 + i * STEP,
                    data=json.dumps({"value": value}).encode(),
                )
        w.finish()  # type: ignore[no-untyped-call]


@pytest.fixture
def archive_client(tmp_path: Path) -> Iterator[tuple[TestClient, Headers, Path]]:
    root = tmp_path / "archives"
    (root / "usv").mkdir(parents=True)
    write_archive(root / "usv" / "run-0000.mcap", 1000)
    full = (root / "usv" / "run-0000.mcap").read_bytes()
    (root / "usv" / "cut-0001.mcap").write_bytes(full[: len(full) * 2 // 3])  # a crash
    (tmp_path / "secret.mcap").write_bytes(full)
    (root / "usv" / "link.mcap").symlink_to(tmp_path / "secret.mcap")
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=root,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        yield c, login(c, "admin", ADMIN_PASSWORD), root


def test_list_complete_and_cut_files(archive_client: tuple[TestClient, Headers, Path]) -> None:
    c, h, _ = archive_client
    files = {f["name"]: f for f in c.get("/api/drones/usv/archives", headers=h).json()}
    # link.mcap leads outside the archive directory: not listed (nor served)
    assert set(files) == {"run-0000.mcap", "cut-0001.mcap"}
    run = files["run-0000.mcap"]
    assert run["complete"] and run["start_ns"] == T0
    assert run["topics"] == [{"topic": t, "messages": 1000} for t in TOPICS]
    cut = files["cut-0001.mcap"]
    assert not cut["complete"]
    assert 0 < cut["topics"][0]["messages"] < 1000  # what was flushed before the cut


def test_single_drone_layout(tmp_path: Path) -> None:
    """``modd up`` writes the MCAP files straight into the archive directory."""
    root = tmp_path / "archive"
    root.mkdir()
    write_archive(root / "modd-0000.mcap", 10)
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=root,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        files = c.get("/api/drones/usv/archives", headers=h).json()
        assert [f["name"] for f in files] == ["modd-0000.mcap"]
        s = c.get(
            "/api/drones/usv/archives/modd-0000.mcap/series", headers=h, params={"topic": TOPICS[0]}
        ).json()
        assert s["total"] == 10
        assert (
            c.get("/api/drones/usv/archives/../archive/modd-0000.mcap", headers=h).status_code
            == 404
        )


def test_series_range_and_reduction(archive_client: tuple[TestClient, Headers, Path]) -> None:
    c, h, _ = archive_client
    url = "/api/drones/usv/archives/run-0000.mcap/series"
    params: dict[str, str | int] = {
        "topic": TOPICS[0],
        "start_ns": T0 + 10 * STEP,
        "end_ns": T0 + 20 * STEP,
    }
    s = c.get(url, headers=h, params=params).json()
    assert s["total"] == 10 and not s["reduced"]
    assert [p[0] for p in s["points"]] == [T0 + i * STEP for i in range(10, 20)]
    assert [p[1] for p in s["points"]] == [float(i) for i in range(10, 20)]
    r = c.get(url, headers=h, params={"topic": TOPICS[0], "max_points": 40}).json()
    assert r["total"] == 1000 and r["reduced"] and len(r["points"]) <= 40
    values = [p[1] for p in r["points"]]
    assert max(values) == 49.0 and min(values) == 0.0  # peaks survive
    cut = c.get(
        "/api/drones/usv/archives/cut-0001.mcap/series", headers=h, params={"topic": TOPICS[1]}
    ).json()
    assert cut["total"] > 0 and cut["points"][0] == [T0, -0.0]


def test_csv_and_download(archive_client: tuple[TestClient, Headers, Path]) -> None:
    c, h, root = archive_client
    r = c.get(
        "/api/drones/usv/archives/run-0000.mcap/csv",
        headers=h,
        params={"topic": TOPICS[1], "end_ns": T0 + 3 * STEP},
    )
    assert r.headers["content-type"].startswith("text/csv")
    assert r.text.splitlines() == [
        "log_time_ns,topic,value",
        f"{T0},{TOPICS[1]},-0.0",
        f"{T0 + STEP},{TOPICS[1]},-1.0",
        f"{T0 + 2 * STEP},{TOPICS[1]},-2.0",
    ]
    d = c.get("/api/drones/usv/archives/run-0000.mcap", headers=h)
    assert d.content == (root / "usv" / "run-0000.mcap").read_bytes()


@pytest.mark.parametrize(
    "path",
    [
        "/api/drones/usv/archives/..%2Fsecret.mcap",
        "/api/drones/usv/archives/%2E%2E%2F%2E%2E%2Fsecret.mcap/series?topic=x",
        "/api/drones/usv/archives/link.mcap",  # a symlink leading outside
        "/api/drones/usv/archives/link.mcap/csv?topic=x",  # the same through the other routes
        "/api/drones/usv/archives/link.mcap/series?topic=x",
        "/api/drones/usv/archives/../../secret.mcap",
        "/api/drones/usv/archives/notes.txt",
        "/api/drones/..%2Fusv/archives",
    ],
)
def test_no_path_escapes(archive_client: tuple[TestClient, Headers, Path], path: str) -> None:
    c, h, _ = archive_client
    r = c.get(path, headers=h)
    assert r.status_code in (404, 422), (path, r.status_code)
    assert (
        r.content
        != (
            Path(c.app.state.modd.settings.effective_archive_dir).parent  # type: ignore[attr-defined]
            / "secret.mcap"
        ).read_bytes()
    )


def test_archives_need_a_token(archive_client: tuple[TestClient, Headers, Path]) -> None:
    c, _, _ = archive_client
    assert c.get("/api/drones/usv/archives").status_code == 401


def test_drone_folder_symlink_out_is_404(tmp_path: Path) -> None:
    """A drone folder that is a symlink out of the archive directory is
    neither listed nor served (it was followed)."""
    root = tmp_path / "archives"
    root.mkdir()
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "run-0000.mcap").write_bytes(b"\x89MCAP0\r\n")
    (root / "other").mkdir()
    (root / "usv").symlink_to(outside, target_is_directory=True)
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=root,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        assert c.get("/api/drones/usv/archives", headers=h).status_code == 404
        assert c.get("/api/drones/usv/archives/run-0000.mcap", headers=h).status_code == 404


def test_csv_name_is_rfc6266_and_non_latin1_topics_work(
    archive_client: tuple[TestClient, Headers, Path],
) -> None:
    c, h, _ = archive_client
    r = c.get(
        "/api/drones/usv/archives/run-0000.mcap/csv", headers=h, params={"topic": 'températur"e/水'}
    )
    assert r.status_code == 200, r.text
    cd = r.headers["content-disposition"]
    assert cd.startswith('attachment; filename="run-0000-temp_ratur_e__.csv"')  # no "/"
    assert "filename*=UTF-8''run-0000-temp%C3%A9ratur%22e%2F%E6%B0%B4.csv" in cd

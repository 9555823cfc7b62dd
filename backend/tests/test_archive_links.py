"""Symbolic links and special files at every level of the two file trees the
workbench serves (the drones' archives and the base-station records), through
every route that reads a file: nothing outside ``<root>/<drone>/`` is listed
or served, whatever the link points at (docs/security.md, "HTTP and
WebSocket")."""

from __future__ import annotations

import io
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, Headers, login
from .test_archives import write_archive

SECRET = b"outside the archive"


@pytest.fixture(scope="module")
def trees(
    tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[tuple[TestClient, Headers, dict[str, Path]]]:
    tmp = tmp_path_factory.mktemp("links")
    outside = tmp / "outside"
    outside.mkdir()
    write_archive(outside / "run-0000.mcap", 10)
    (outside / "secret.mcap").write_bytes(SECRET)
    roots = {"archives": tmp / "archives", "records": tmp / "records"}
    for root in roots.values():
        (root / "usv").mkdir(parents=True)
        (root / "other").mkdir()
        write_archive(root / "other" / "mine-0000.mcap", 10)
        usv = root / "usv"
        (usv / "out.mcap").symlink_to(outside / "secret.mcap")  # a file link out
        (usv / "rel.mcap").symlink_to("../../outside/secret.mcap")  # relative
        (usv / "sibling.mcap").symlink_to(root / "other" / "mine-0000.mcap")  # another folder
        (usv / "dangling.mcap").symlink_to(tmp / "nothing.mcap")
        (usv / "zero.mcap").symlink_to("/dev/zero")
        os.mkfifo(usv / "fifo.mcap")
        (usv / "dir.mcap").mkdir()
        (root / "away").symlink_to(outside, target_is_directory=True)  # a drone folder out
        (root / "self").symlink_to(root, target_is_directory=True)  # the root itself
        (root / "chain").symlink_to(root / "away", target_is_directory=True)  # link to a link
    settings = Settings(
        data_dir=tmp / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=roots["archives"],
        record_dir=roots["records"],
        foxglove_replay_port=0,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        yield c, login(c, "admin", ADMIN_PASSWORD), roots


FILES = (
    "out.mcap",
    "rel.mcap",
    "sibling.mcap",
    "dangling.mcap",
    "zero.mcap",
    "fifo.mcap",
    "dir.mcap",
)


@pytest.mark.parametrize("tree", ["archives", "records"])
def test_no_link_or_special_file_is_listed(
    trees: tuple[TestClient, Headers, dict[str, Path]], tree: str
) -> None:
    c, h, _ = trees
    r = c.get(f"/api/drones/usv/{tree}", headers=h)
    assert r.status_code == 200 and r.json() == [], r.text
    for drone in ("away", "self", "chain"):
        r = c.get(f"/api/drones/{drone}/{tree}", headers=h)
        assert r.status_code == 404, (drone, r.status_code, r.text[:200])


@pytest.mark.parametrize("tree", ["archives", "records"])
@pytest.mark.parametrize(
    "where",
    [f"usv/{{tree}}/{f}" for f in FILES]
    + [
        "away/{tree}/run-0000.mcap",
        "away/{tree}/secret.mcap",
        "self/{tree}/x.mcap",
        "chain/{tree}/secret.mcap",
        "self/{tree}/..%2Foutside%2Fsecret.mcap",
    ],
)
def test_no_link_or_special_file_is_served(
    trees: tuple[TestClient, Headers, dict[str, Path]], tree: str, where: str
) -> None:
    c, h, _ = trees
    base = "/api/drones/" + where.format(tree=tree)
    urls = [base] + (
        [f"{base}/csv?topic=x", f"{base}/series?topic=x"] if tree == "archives" else []
    )
    for url in urls:
        r = c.get(url, headers=h)
        assert r.status_code in (404, 422), (url, r.status_code, r.text[:200])
        assert SECRET not in r.content

"""Map tiles from a local folder (--tiles): served to signed-in users from the
workbench's own origin, the bytes of the file; nothing outside the folder; none
without the option."""

from __future__ import annotations

from pathlib import Path

from fastapi.testclient import TestClient
from modd_backend.cli import parse_args

from .conftest import ADMIN_PASSWORD, app_client, login

PNG = b"\x89PNG\r\n\x1a\n" + b"tile-bytes"


def _client(tmp_path: Path, tile_dir: Path | None) -> TestClient:
    return app_client(tmp_path, tile_dir=tile_dir)


def test_a_tile_of_the_folder_is_served_and_nothing_else(tmp_path: Path) -> None:
    tiles = tmp_path / "tiles"
    (tiles / "15" / "10305").mkdir(parents=True)
    (tiles / "15" / "10305" / "11752.png").write_bytes(PNG)
    (tmp_path / "secret.png").write_bytes(b"secret")
    (tiles / "15" / "10305" / "1.png").symlink_to(tmp_path / "secret.png")
    with _client(tmp_path, tiles) as c:
        assert c.get("/api/tiles/15/10305/11752.png").status_code == 401
        h = login(c, "admin", ADMIN_PASSWORD)
        assert c.get("/api/tiles", headers=h).json() == {
            "available": True,
            "url": "/api/tiles/{z}/{x}/{y}.png",
        }
        got = c.get("/api/tiles/15/10305/11752.png", headers=h)
        assert got.status_code == 200 and got.content == PNG
        assert got.headers["content-type"] == "image/png"
        assert c.get("/api/tiles/15/10305/1.png", headers=h).status_code == 404  # a link out
        missing = c.get("/api/tiles/15/10305/11753.png", headers=h)
        assert missing.status_code == 404 and "no tile 15/10305/11753.png" in missing.text
        assert c.get("/api/tiles/2/4/0.png", headers=h).status_code == 404  # x beyond zoom 2
        assert c.get("/api/tiles/15/..%2F..%2Fsecret/1.png", headers=h).status_code in (404, 422)
        assert c.get("/api/tiles/15/10305/11752.svg", headers=h).status_code == 422


def test_no_tiles_without_the_option(tmp_path: Path) -> None:
    with _client(tmp_path, None) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        assert c.get("/api/tiles", headers=h).json() == {"available": False, "url": None}
        assert c.get("/api/tiles/1/0/0.png", headers=h).status_code == 404


def test_the_option_names_the_folder(tmp_path: Path) -> None:
    settings = parse_args(["--tiles", str(tmp_path), "--no-zenoh"])
    assert settings.tile_dir == tmp_path.absolute()

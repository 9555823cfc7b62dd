"""The built frontend is served at / when its dist folder exists; client-side
routes get index.html; /api stays the API's."""

from __future__ import annotations

import io
from pathlib import Path

from fastapi.testclient import TestClient
from modd_backend import Settings, create_app


def test_serves_dist_with_spa_fallback(tmp_path: Path) -> None:
    dist = tmp_path / "dist"
    (dist / "assets").mkdir(parents=True)
    (dist / "index.html").write_text("<!doctype html><title>MoDD</title>")
    (dist / "assets" / "app.js").write_text("console.log('modd')")
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        frontend_dist=dist,
        initial_admin_password="x" * 12,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        assert "MoDD" in c.get("/").text
        assert c.get("/assets/app.js").text == "console.log('modd')"
        assert "MoDD" in c.get("/projects/3/plan").text  # a client-side route
        api = c.get("/api/nothing-here")
        assert api.status_code == 404
        assert "MoDD" not in api.text
        assert c.get("/openapi.json").json()["info"]["title"] == "MoDD workbench"


def test_no_dist_no_frontend(tmp_path: Path) -> None:
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        frontend_dist=tmp_path / "missing",
        initial_admin_password="x" * 12,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        assert c.get("/").status_code == 404
        assert c.get("/openapi.json").status_code == 200

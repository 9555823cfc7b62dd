"""Serving the built frontend (frontend/dist) at ``/``: files as they are,
``index.html`` for any other path outside ``/api`` (client-side routes)."""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from starlette.exceptions import HTTPException
from starlette.responses import Response
from starlette.staticfiles import StaticFiles
from starlette.types import Scope


class SpaFiles(StaticFiles):
    async def get_response(self, path: str, scope: Scope) -> Response:
        try:
            return await super().get_response(path, scope)
        except HTTPException as exc:
            if exc.status_code != 404 or path.startswith("api/") or path == "api":
                raise
            return await super().get_response("index.html", scope)


def mount_frontend(app: FastAPI, dist: Path) -> bool:
    """Mount when ``dist/index.html`` exists; say whether it was mounted."""
    if not (dist / "index.html").is_file():
        return False
    app.mount("/", SpaFiles(directory=dist, html=True), name="frontend")
    return True

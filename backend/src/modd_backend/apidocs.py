"""The API's own page, ``/docs`` (Swagger UI 5, which reads FastAPI's OpenAPI
3.1), served with Swagger UI's files from the backend itself (those the
fastapi-offline package carries) rather than a CDN, so it works on a ship or
in a field station without Internet."""

from __future__ import annotations

from pathlib import Path

import fastapi_offline
from fastapi import FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse
from starlette.staticfiles import StaticFiles

#: Where Swagger UI's files are served.
ASSETS = "/docs-assets"


def install_docs(app: FastAPI) -> None:
    """``/docs`` and its assets under ``/docs-assets`` (create the app with ``docs_url=None``)."""
    static = Path(fastapi_offline.__file__).parent / "static"
    app.mount(ASSETS, StaticFiles(directory=static), name="docs-assets")
    openapi_url = app.openapi_url or "/openapi.json"

    @app.get("/docs", include_in_schema=False)
    def docs() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=openapi_url,
            title=f"{app.title} — API",
            swagger_js_url=f"{ASSETS}/swagger-ui-bundle.js",
            swagger_css_url=f"{ASSETS}/swagger-ui.css",
            swagger_favicon_url=f"{ASSETS}/favicon.png",
        )

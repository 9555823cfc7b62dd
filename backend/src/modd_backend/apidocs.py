"""The API's own page, ``/docs`` (Swagger UI), served with Swagger UI's files
from the backend itself (the swagger-ui-bundle package) rather than a CDN,
so it works on a ship or in a field station without Internet."""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse
from starlette.staticfiles import StaticFiles
from swagger_ui_bundle import swagger_ui_path  # type: ignore[import-untyped]

#: Where Swagger UI's files are served.
ASSETS = "/docs-assets"


def install_docs(app: FastAPI) -> None:
    """``/docs`` and its assets under ``/docs-assets`` (create the app with ``docs_url=None``)."""
    app.mount(ASSETS, StaticFiles(directory=Path(swagger_ui_path)), name="docs-assets")
    openapi_url = app.openapi_url or "/openapi.json"

    @app.get("/docs", include_in_schema=False)
    def docs() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=openapi_url, title=f"{app.title} — API",
            swagger_js_url=f"{ASSETS}/swagger-ui-bundle.js",
            swagger_css_url=f"{ASSETS}/swagger-ui.css",
            swagger_favicon_url=f"{ASSETS}/favicon-32x32.png",
        )

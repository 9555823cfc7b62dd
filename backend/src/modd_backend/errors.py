"""Errors with a structured body: ``{"detail": "...", ...extra}`` so that the
editor gets diagnostics, the current revision or the denied parts as data.

>>> raise ApiError(409, "stale revision", current_revision=4)   # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse


class ApiError(Exception):
    def __init__(self, status: int, detail: str, **extra: Any) -> None:
        super().__init__(detail)
        self.status = status
        self.body = {"detail": detail, **extra}


async def _handle(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, ApiError)
    return JSONResponse(exc.body, status_code=exc.status)


def install(app: FastAPI) -> None:
    app.add_exception_handler(ApiError, _handle)

"""Errors with a structured body: ``{"detail": "...", ...extra}`` so that the
editor gets diagnostics, the current revision or the denied parts as data.

>>> raise ApiError(409, "stale revision", current_revision=4)   # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse


class ApiError(Exception):
    def __init__(self, status: int, detail: str, *, headers: dict[str, str] | None = None,
                 **extra: Any) -> None:
        super().__init__(detail)
        self.status = status
        self.body = {"detail": detail, **extra}
        self.headers = headers


async def _handle(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, ApiError)
    return JSONResponse(exc.body, status_code=exc.status, headers=exc.headers)


def retry_later(status: int, detail: str, retry_after_s: float) -> ApiError:
    """429 or 503 with ``Retry-After`` in whole seconds (at least 1)."""
    seconds = max(1, int(retry_after_s + 0.999))
    return ApiError(status, detail, headers={"Retry-After": str(seconds)},
                    retry_after_s=seconds)


def install(app: FastAPI) -> None:
    app.add_exception_handler(ApiError, _handle)

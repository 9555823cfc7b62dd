"""Errors with a structured body: ``{"detail": "...", ...extra}`` so that the
editor gets diagnostics, the current revision or the denied parts as data.

>>> raise ApiError(409, "stale revision", current_revision=4)   # doctest: +SKIP
"""

from __future__ import annotations

import json
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response

#: Validation errors answered at most (a body of 150,000 unknown keys listed
#: each, with its input echoed).
MAX_VALIDATION_ERRORS = 50


class ApiError(Exception):
    def __init__(
        self, status: int, detail: str, *, headers: dict[str, str] | None = None, **extra: Any
    ) -> None:
        super().__init__(detail)
        self.status = status
        self.body = {"detail": detail, **extra}
        self.headers = headers

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled whole (it crosses from a store or archive worker process)."""
        return (_api_error, (self.status, self.body, self.headers))


def _api_error(status: int, body: dict[str, Any], headers: dict[str, str] | None) -> ApiError:
    exc = ApiError(status, str(body.get("detail", "")), headers=headers)
    exc.body = body
    return exc


async def _handle(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, ApiError)
    return JSONResponse(exc.body, status_code=exc.status, headers=exc.headers)


def retry_later(status: int, detail: str, retry_after_s: float) -> ApiError:
    """429 or 503 with ``Retry-After`` in whole seconds (at least 1)."""
    seconds = max(1, int(retry_after_s + 0.999))
    return ApiError(status, detail, headers={"Retry-After": str(seconds)}, retry_after_s=seconds)


async def _invalid(_request: Request, exc: Exception) -> Response:
    """FastAPI's 422 without echoing the input: a value it cannot write back
    as JSON (``1e400``, a lone surrogate) made the answer itself fail with
    500, and a large body was echoed whole. ``type``, ``loc``, ``msg`` and
    ``ctx`` (as text) are kept; the text is ASCII JSON, so any key is safe."""
    assert isinstance(exc, RequestValidationError)
    errors = [
        {
            "type": str(e.get("type", "")),
            "loc": [x if isinstance(x, int) else str(x) for x in e.get("loc", ())],
            "msg": str(e.get("msg", "")),
            **(
                {"ctx": {str(k): str(v) for k, v in e["ctx"].items()}}
                if isinstance(e.get("ctx"), dict)
                else {}
            ),
        }
        for e in list(exc.errors())[:MAX_VALIDATION_ERRORS]
    ]
    body = json.dumps({"detail": errors}, ensure_ascii=True)
    return Response(body, status_code=422, media_type="application/json")


def install(app: FastAPI) -> None:
    app.add_exception_handler(ApiError, _handle)
    app.add_exception_handler(RequestValidationError, _invalid)

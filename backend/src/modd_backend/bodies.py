"""Model-carrying request bodies read off the event loop.

FastAPI parses a route's pydantic body (``json.loads``, then the model's
check) on the event loop, before the route runs: 30-100 ms of CPU for a
model of a few MiB, during which no other request is answered. The routes
that take a model (validate, save, create a project, plan) instead take the
body's bytes (:data:`BodyDep`, an async read that costs nothing) and read
them with :func:`parse_as` in the route itself, which FastAPI runs in its
thread pool (``def`` routes) or which the plan route runs in its worker
process. The answers stay FastAPI's: 413 from the guard middleware before
any of this, 422 with FastAPI's error form (``loc`` from ``body``) for a
body that is not the route's model.

The request body's schema stays in the OpenAPI description:
:func:`documented` gives the route's ``openapi_extra`` and
:func:`install_schemas` adds the models to ``components/schemas``.

>>> @router.post("/validate", openapi_extra=documented(ModelInput))   # doctest: +SKIP
... def validate_model(body: BodyDep) -> ValidateOut:
...     parsed = parse_as(body, ModelInput)
"""

from __future__ import annotations

import email.message
import json
from dataclasses import dataclass
from typing import Annotated, Any, TypeVar

from fastapi import Depends, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ValidationError

M = TypeVar("M", bound=BaseModel)


@dataclass(frozen=True)
class Body:
    """A request's body as bytes, and whether FastAPI would read it as JSON."""

    data: bytes
    is_json: bool


def is_json(content_type: str | None) -> bool:
    """FastAPI's rule for parsing a body as JSON: no Content-Type, or
    application/json or application/*+json."""
    if not content_type:
        return True
    message = email.message.Message()
    message["content-type"] = content_type
    subtype = message.get_content_subtype()
    return message.get_content_maintype() == "application" and (
        subtype == "json" or subtype.endswith("+json")
    )


async def request_body(request: Request) -> Body:
    """The body's bytes (already bounded by the guard middleware: 413)."""
    return Body(await request.body(), is_json(request.headers.get("content-type")))


BodyDep = Annotated[Body, Depends(request_body)]


def read_as(body: bytes, json_body: bool, cls: type[M]) -> M | list[dict[str, Any]]:
    """The body read as ``cls``, or FastAPI's validation errors for it
    (``loc`` from ``body``): what FastAPI does for a body parameter, here
    wherever it is called (a thread, a worker process)."""
    try:
        if not body:
            return [{"type": "missing", "loc": ("body",), "msg": "Field required", "input": None}]
        data: Any = body
        if json_body:
            try:
                data = json.loads(body)
            except json.JSONDecodeError as exc:
                return [
                    {
                        "type": "json_invalid",
                        "loc": ("body", exc.pos),
                        "msg": "JSON decode error",
                        "input": {},
                        "ctx": {"error": exc.msg},
                    }
                ]
            except UnicodeDecodeError as exc:
                return [
                    {
                        "type": "json_invalid",
                        "loc": ("body", exc.start),
                        "msg": "JSON decode error",
                        "input": {},
                        "ctx": {"error": str(exc)},
                    }
                ]
        return cls.model_validate(data)
    except ValidationError as exc:
        return [
            {
                **e,
                "loc": ("body", *e["loc"]),
                **({"ctx": {k: str(v) for k, v in e["ctx"].items()}} if "ctx" in e else {}),
            }
            for e in exc.errors(include_url=False, include_input=False)
        ]


def parse_as(body: Body, cls: type[M]) -> M:
    """:func:`read_as`, raising FastAPI's 422 when the body is not a ``cls``.
    Call it from a ``def`` route (the thread pool), not on the event loop."""
    out = read_as(body.data, body.is_json, cls)
    if isinstance(out, list):
        raise RequestValidationError(out)
    return out


#: The body models of the routes that read their body themselves, added to
#: the OpenAPI description by :func:`install_schemas`.
_DOCUMENTED: dict[str, type[BaseModel]] = {}


def documented(cls: type[BaseModel]) -> dict[str, Any]:
    """A route's ``openapi_extra``: its JSON body is a ``cls``."""
    _DOCUMENTED[cls.__name__] = cls
    return {
        "requestBody": {
            "required": True,
            "content": {
                "application/json": {"schema": {"$ref": f"#/components/schemas/{cls.__name__}"}}
            },
        }
    }


def install_schemas(app: FastAPI) -> None:
    """Add the :func:`documented` models (and the models they use) to the
    app's OpenAPI ``components/schemas``, where the routes' bodies point."""
    base = app.openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is not None:
            return app.openapi_schema
        spec = base()
        schemas = spec.setdefault("components", {}).setdefault("schemas", {})
        for name, cls in sorted(_DOCUMENTED.items()):
            schema = cls.model_json_schema(ref_template="#/components/schemas/{model}")
            for inner, definition in schema.pop("$defs", {}).items():
                schemas.setdefault(inner, definition)
            schemas.setdefault(name, schema)
        app.openapi_schema = spec
        return spec

    app.openapi = openapi  # type: ignore[method-assign]

"""Request and response bodies shared by several routers (the OpenAPI
schemas). A model itself travels as the JSON document of
metamodel/modd.schema.json, typed here as a free object: the schema file,
not a second copy, defines it."""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any, Literal

from fastapi import Path
from pydantic import BaseModel, Field, model_validator

Format = Literal["json", "modd"]


class DiagnosticOut(BaseModel):
    """One located problem: JSON pointer always, file:line:col for text input,
    and where the located text ends (end_col exclusive) when the parser knows."""

    severity: Literal["error", "warning"]
    message: str
    pointer: str
    file: str | None = None
    line: int | None = None
    col: int | None = None
    end_line: int | None = None
    end_col: int | None = None


class ModelInput(BaseModel):
    """A model given as a JSON document (``model``) or as text (``text`` in
    ``format``, .modd by default). Exactly one of the two."""

    model: dict[str, Any] | None = None
    text: str | None = Field(default=None, max_length=2_000_000)
    format: Format = "modd"

    @model_validator(mode="after")
    def _one_of(self) -> ModelInput:
        if (self.model is None) == (self.text is None):
            raise ValueError("give exactly one of 'model' and 'text'")
        return self


class InvalidModelOut(BaseModel):
    """422 for a model that cannot be read at all (syntax errors)."""

    detail: str
    diagnostics: list[DiagnosticOut]


class VersionOut(BaseModel):
    project_id: int
    revision: int
    valid: bool
    author: str
    message: str
    created_at: datetime


class ModelOut(VersionOut):
    model: dict[str, Any]
    diagnostics: list[DiagnosticOut]


class ConflictOut(BaseModel):
    """409: the save was based on an old revision."""

    detail: str
    current_revision: int


#: The ``responses=`` argument of a route (extra documented statuses).
Responses = dict[int | str, dict[str, Any]]

#: A row id in a path: bounded so that no database integer overflows.
Id = Annotated[int, Path(ge=1, le=2**31 - 1)]

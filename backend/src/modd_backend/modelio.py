"""Reading models from API input: JSON documents or .modd/JSON text, always
with every diagnostic as structured data (never raising for bad input)."""

from __future__ import annotations

import json
from typing import Any

from modd_model import LoadResult, load_text, validate
from modd_model.diagnostics import Diagnostic
from modd_model.io import decode

from .errors import ApiError
from .schemas import Format, ModelInput


def diagnostics_json(diags: list[Diagnostic]) -> list[dict[str, object]]:
    return [d.to_json() for d in diags]


def require_valid(model: dict[str, Any], revision: int, then: str = "first") -> None:
    """ApiError 422 with the diagnostics when the revision's model has errors."""
    errors = [d for d in validate(model) if d.severity == "error"]
    if errors:
        raise ApiError(
            422,
            f"revision {revision} has errors: fix them {then}",
            diagnostics=diagnostics_json(errors),
        )


def read_input(body: ModelInput, filename: str = "<editor>") -> LoadResult:
    if body.model is not None:
        return LoadResult(body.model, validate(body.model), {})
    assert body.text is not None
    return read_text(body.text, body.format, filename)


def read_text(text: str, fmt: Format, filename: str = "<editor>") -> LoadResult:
    result = load_text(text, filename, fmt)
    if result.model is not None and not isinstance(result.model, dict):
        return LoadResult(None, [Diagnostic("a model is a JSON object", "", "error")], {})
    return result


def require_document(result: LoadResult) -> dict[str, Any]:
    """The parsed document, or 422 with the diagnostics when there is none."""
    if result.model is None:
        raise ApiError(
            422, "the model cannot be read", diagnostics=diagnostics_json(result.diagnostics)
        )
    doc: dict[str, Any] = result.model
    return doc


def decode_body(raw: bytes, fmt: Format, filename: str) -> LoadResult:
    """A raw model file: UTF-8 (or another encoding with a byte-order mark), or
    windows-1252 for files of the original tool that are not UTF-8, with a
    warning (modd_model.io.decode)."""
    text, notes = decode(raw, filename)
    if text is None:
        return LoadResult(None, notes, {})
    result = read_text(text, fmt, filename)
    result.diagnostics[:0] = notes
    return result


def canonical_json(model: dict[str, Any]) -> str:
    return json.dumps(model, ensure_ascii=False, sort_keys=False)

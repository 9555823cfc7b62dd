"""Located errors: every problem of a model says where it is, as a JSON pointer
and, for text input, as file:line:col; printed gcc-style."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

Severity = Literal["error", "warning"]


@dataclass(frozen=True)
class Location:
    """A position in a source file (1-based line and column; line 0 means the
    file as a whole, e.g. for JSON input located by its pointer)."""

    file: str
    line: int
    col: int
    end_line: int | None = None
    end_col: int | None = None


@dataclass(frozen=True)
class Diagnostic:
    """One problem of a model.

    ``pointer`` is a JSON pointer into the model (RFC 6901), ``""`` for the whole
    model; ``location`` is set when the model came from text.
    """

    message: str
    pointer: str = ""
    severity: Severity = "error"
    location: Location | None = None
    source_line: str | None = field(default=None, compare=False)

    def __str__(self) -> str:
        where = self.location.file if self.location else "<model>"
        if self.location and self.location.line > 0:  # line 0: the whole file
            where += f":{self.location.line}:{self.location.col}"
        ptr = f" [{self.pointer}]" if self.pointer else ""
        text = f"{where}: {self.severity}: {self.message}{ptr}"
        if self.source_line is not None and self.location and self.location.line > 0:
            caret = " " * (self.location.col - 1) + "^"
            text += f"\n    {self.source_line}\n    {caret}"
        return text

    def to_json(self) -> dict[str, object]:
        """Structured form for the editor (pins the error to a node or a text range)."""
        out: dict[str, object] = {
            "severity": self.severity,
            "message": self.message,
            "pointer": self.pointer,
        }
        if self.location:
            out["file"] = self.location.file
        if self.location and self.location.line > 0:
            out["line"] = self.location.line
            out["col"] = self.location.col
            if self.location.end_line is not None and self.location.end_col is not None:
                # the end of the located text, exclusive (the parser's end column)
                out["end_line"] = self.location.end_line
                out["end_col"] = self.location.end_col
        return out


class ModelError(Exception):
    """A model that cannot be used; carries all of its diagnostics, not only the first."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        self.diagnostics = diagnostics
        errors = [d for d in diagnostics if d.severity == "error"]
        super().__init__("\n".join(str(d) for d in errors) or "invalid model")


def pointer_join(*parts: str | int) -> str:
    """JSON pointer from path parts, escaping ``~`` and ``/``."""
    return "".join("/" + str(p).replace("~", "~0").replace("/", "~1") for p in parts)


def pointer_parent(pointer: str) -> str:
    return pointer.rsplit("/", 1)[0] if pointer else ""

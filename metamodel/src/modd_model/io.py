"""Reading and writing models in both notations, .modd text and JSON.

``load_*`` parse, then validate, and attach text positions to every diagnostic
whose JSON pointer came from text. ``load_model`` raises on errors; the
``LoadResult`` form returns warnings and errors together for editors."""

from __future__ import annotations

import codecs
import json
import os
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal, TextIO

from .diagnostics import Diagnostic, Location, ModelError, pointer_parent
from .jsondepth import MAX_DEPTH, json_depth
from .parser import SourceMap, parse_lenient
from .printer import print_model
from .validate import validate

Format = Literal["modd", "json"]


@dataclass
class LoadResult:
    """A parsed model (None when it could not be parsed) and all its diagnostics."""

    model: dict[str, Any] | None
    diagnostics: list[Diagnostic]
    source_map: SourceMap

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.severity == "error"]

    @property
    def ok(self) -> bool:
        return self.model is not None and not self.errors


def format_of(path: str | Path) -> Format:
    return "json" if str(path).endswith(".json") else "modd"


def _locate(diags: list[Diagnostic], smap: SourceMap, lines: list[str]) -> list[Diagnostic]:
    out = []
    for d in diags:
        ptr = d.pointer
        while ptr not in smap and ptr:
            ptr = pointer_parent(ptr)
        loc = smap.get(ptr)
        if loc is None and d.location is None:
            out.append(d)
            continue
        loc = d.location or loc
        assert loc is not None
        src = lines[loc.line - 1] if 0 < loc.line <= len(lines) else None
        out.append(replace(d, location=loc, source_line=src))
    return out


def load_text(text: str, filename: str = "<text>", fmt: Format = "modd") -> LoadResult:
    """Parse and validate a model given as text; never raises for bad input."""
    lines = text.splitlines()
    smap: SourceMap = {}
    if fmt == "json":
        depth = json_depth(text.encode("utf-8", "surrogatepass"))
        if depth > MAX_DEPTH:
            return LoadResult(
                None,
                [
                    Diagnostic(
                        f"invalid JSON: nested {depth} levels deep; at most {MAX_DEPTH} are read",
                        "",
                        "error",
                        Location(filename, 1, 1),
                        lines[0][:200] if lines else None,
                    )
                ],
                {},
            )
        try:
            doc: Any = json.loads(text)
        except json.JSONDecodeError as exc:
            loc = Location(filename, exc.lineno, exc.colno)
            src = lines[exc.lineno - 1] if 0 < exc.lineno <= len(lines) else None
            return LoadResult(
                None, [Diagnostic(f"invalid JSON: {exc.msg}", "", "error", loc, src)], {}
            )
        # JSON has no line:col per pointer here: the file and the pointer locate it.
        whole_file = Location(filename, 0, 0)
        return LoadResult(doc, [replace(d, location=whole_file) for d in validate(doc)], {})
    doc, smap, word_errors = parse_lenient(text, filename)
    if doc is None:
        return LoadResult(None, word_errors, {})
    # A wrong word is reported once, by the builder, not again by the schema.
    flagged = {d.pointer for d in word_errors}
    checks = [d for d in validate(doc) if d.pointer not in flagged]
    return LoadResult(doc, word_errors + _locate(checks, smap, lines), smap)


#: Largest model file read (a legal model is far smaller; see docs/dsl.md).
MAX_FILE_BYTES = 16 * 1024 * 1024
_BOMS = (
    (codecs.BOM_UTF8, "utf-8-sig"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
)


def decode(
    data: bytes, filename: str, encoding: str | None = None
) -> tuple[str | None, list[Diagnostic]]:
    """The text of a model file, and a note on how it was decoded.

    With ``encoding`` given, exactly that (an undecodable byte is an error with
    its line and column). Otherwise a byte-order mark decides, then UTF-8; a
    file that is not UTF-8 is read as windows-1252, the default of Eclipse on
    many installations, where the original tool's files were written (a
    warning says so)."""
    if encoding is None:
        for bom, enc in _BOMS:
            if data.startswith(bom):
                return decode(data, filename, enc)
        try:
            return data.decode("utf-8"), []
        except UnicodeDecodeError:
            text = data.decode("cp1252", errors=_LATIN1_FALLBACK)
            note = Diagnostic(
                "not UTF-8: read as windows-1252 (choose another encoding with --encoding)",
                "",
                "warning",
                Location(filename, 1, 1),
            )
            return text, [note]
    try:
        return data.decode(encoding), []
    except LookupError:
        return None, [
            Diagnostic(f"unknown encoding {encoding!r}", "", "error", Location(filename, 0, 0))
        ]
    except UnicodeDecodeError as exc:
        head = data[: exc.start]
        line = head.count(b"\n") + 1
        col = exc.start - (head.rfind(b"\n") + 1) + 1
        return None, [
            Diagnostic(
                f"byte 0x{data[exc.start]:02x} is not valid {encoding}",
                "",
                "error",
                Location(filename, line, col),
            )
        ]


def _latin1(exc: UnicodeError) -> tuple[str, int]:
    # cp1252 leaves five bytes undefined; Latin-1 gives them a meaning.
    assert isinstance(exc, UnicodeDecodeError)
    return exc.object[exc.start : exc.end].decode("latin-1"), exc.end


_LATIN1_FALLBACK = "modd-latin1"
codecs.register_error(_LATIN1_FALLBACK, _latin1)


def load_file(path: str | Path, encoding: str | None = None) -> LoadResult:
    """Load a model file (.modd, .collector or .json) in any encoding ``decode`` reads."""
    p = Path(path)
    try:
        with p.open("rb") as f:
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        return LoadResult(None, [Diagnostic(f"cannot read {p}: {exc.strerror or exc}")], {})
    if len(data) > MAX_FILE_BYTES:
        return LoadResult(
            None,
            [
                Diagnostic(
                    f"{p} is larger than {MAX_FILE_BYTES} bytes",
                    "",
                    "error",
                    Location(str(path), 0, 0),
                )
            ],
            {},
        )
    text, notes = decode(data, str(path), encoding)
    if text is None:
        return LoadResult(None, notes, {})
    result = load_text(text, str(path), format_of(p))
    result.diagnostics[:0] = notes
    return result


def write_atomic(path: str | Path, text: str) -> None:
    """Replace ``path`` with ``text`` or leave it untouched: write a temporary
    file beside it, fsync, rename over it. On any error (a full disk) the
    temporary file is removed and the original is as it was."""
    p = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        if p.exists():
            os.chmod(tmp, p.stat().st_mode & 0o7777)
        os.replace(tmp, p)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def locate(diags: list[Diagnostic], result: LoadResult, path: str | Path) -> list[Diagnostic]:
    """Diagnostics found after loading (the planner's, on the model's JSON
    pointers) located in the file as :func:`load_file` locates its own."""
    if format_of(path) == "json" or not result.source_map:
        return [replace(d, location=d.location or Location(str(path), 0, 0)) for d in diags]
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        lines = []
    return _locate(diags, result.source_map, lines)


def load_or_report(
    path: str | Path,
    *,
    quiet_warnings: bool = False,
    out: TextIO | None = None,
    encoding: str | None = None,
) -> dict[str, Any] | None:
    """The valid model of a file, or None; every diagnostic goes to ``out``
    (stderr), as each command-line tool reports a model it was given."""
    result = load_file(path, encoding)
    for d in result.diagnostics:
        if not (quiet_warnings and d.severity == "warning"):
            print(d, file=out or sys.stderr)
    return result.model if result.ok else None


def load_model(path: str | Path) -> dict[str, Any]:
    """A valid model from a .modd or .json file; raises ModelError listing every error.

    >>> model = load_model("metamodel/examples/scenarios/scenario1.modd")  # doctest: +SKIP
    """
    result = load_file(path)
    if not result.ok:
        raise ModelError(result.diagnostics)
    assert result.model is not None
    return result.model


def dumps(doc: dict[str, Any], fmt: Format) -> str:
    """A model as canonical text in either notation."""
    if fmt == "json":
        return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"
    return print_model(doc)

"""The MoDD metamodel: load, validate, parse and print mission models.

>>> from modd_model import load_model, dumps
>>> model = load_model("mission.modd")          # doctest: +SKIP
>>> print(dumps(model, "json"))                 # doctest: +SKIP

The names below are imported on first use (PEP 562), so that ``modd --help``
and light submodules (``modd_model.numbers``, ``modd_model.cli``) do not pay
for the parser (lark); the validator imports jsonschema on first use.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# ``validate`` is both a submodule and a function: imported here, so that the
# function, not the module, is the package's attribute (the module is light;
# it imports jsonschema on first use).
from .diagnostics import Diagnostic, Location, ModelError
from .validate import validate

if TYPE_CHECKING:
    from .io import LoadResult, dumps, format_of, load_file, load_model, load_or_report, load_text
    from .parser import parse_text
    from .printer import print_model

_WHERE = {
    "LoadResult": "io",
    "dumps": "io",
    "format_of": "io",
    "load_file": "io",
    "load_or_report": "io",
    "load_model": "io",
    "load_text": "io",
    "parse_text": "parser",
    "print_model": "printer",
}

__all__ = [
    "Diagnostic",
    "Location",
    "LoadResult",
    "ModelError",
    "dumps",
    "format_of",
    "load_file",
    "load_or_report",
    "load_model",
    "load_text",
    "parse_text",
    "print_model",
    "validate",
]


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'modd_model' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))

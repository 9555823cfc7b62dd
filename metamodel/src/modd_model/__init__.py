"""The MoDD metamodel: load, validate, parse and print mission models.

>>> from modd_model import load_model, dumps
>>> model = load_model("mission.modd")          # doctest: +SKIP
>>> print(dumps(model, "json"))                 # doctest: +SKIP
"""

from .diagnostics import Diagnostic, Location, ModelError
from .io import LoadResult, dumps, format_of, load_file, load_model, load_or_report, load_text
from .parser import parse_text
from .printer import print_model
from .validate import validate

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

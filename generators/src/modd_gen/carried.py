"""Reading a file the generators carry from its one home elsewhere in the
repository (the C++ clients, the Python subscriber client): the wheel's copy
when this package was installed from one (``force-include`` puts it beside the
module that carries it), else the checkout's original."""

from __future__ import annotations

from collections.abc import Mapping
from importlib import resources
from pathlib import Path

#: The checkout this package sits in (src/modd_gen -> the repository).
CHECKOUT = Path(__file__).resolve().parents[3]


def read_carried(package: str, originals: Mapping[str, str], name: str, what: str) -> str:
    """``name`` (a key of ``originals``, its path inside ``package``) as text;
    ValueError for a name not carried, FileNotFoundError when neither copy exists."""
    if name not in originals:
        raise ValueError(f"no carried {what} file {name!r}")
    packaged = resources.files(package).joinpath(name)
    if packaged.is_file():
        return packaged.read_text(encoding="utf-8")
    original = CHECKOUT / originals[name]
    if not original.is_file():
        raise FileNotFoundError(
            f"{what} source {name!r} is neither in the package "
            f"nor at {original} (build the wheel from a checkout)"
        )
    return original.read_text(encoding="utf-8")

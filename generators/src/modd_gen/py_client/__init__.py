"""The Python subscriber client the generators carry beside the scientist's
stubs, so that a stub runs with plain ``python3`` on a laptop that has only
``eclipse-zenoh`` (and pandas for ``--dataframe``): the runtime's own client
modules (``modd.subscribe`` and what it imports, the contracts it reads), not a
second copy of them.

Their one home is runtime/python and metamodel/src (tested there); nothing is
committed here. A wheel gets them at build time (``force-include`` in
generators/pyproject.toml puts them in this package), a checkout reads the
originals, as :mod:`modd_gen.cpp_client` does for the C++ clients.

>>> "def subscribe" in read("modd/__init__.py")
True
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

_RT, _MM = "runtime/python/src", "metamodel/src"
_CLIENT = "modd"  # the package name (a path, not a zenoh key)

#: path beside the stubs (also the file in this package, in a wheel) -> its original.
ORIGINALS = {
    f"{_CLIENT}/{name}": f"{_RT}/{_CLIENT}/{name}"
    for name in (
        "__init__.py",
        "subscriber.py",
        "zenoh_session.py",
        "zenoh_auth.py",
        "subbroker/__init__.py",
        "subbroker/client.py",
        "subbroker/keys.py",
        "subbroker/payload.py",
    )
} | {
    f"modd_contracts/{name}": f"{_MM}/modd_contracts/{name}"
    for name in ("__init__.py", "keys.py", "types_gen.py")
}

#: The checkout this package sits in (src/modd_gen/py_client -> the repository).
CHECKOUT = Path(__file__).resolve().parents[4]


def read(name: str) -> str:
    """One carried file (a key of :data:`ORIGINALS`): the wheel's copy, else the checkout's."""
    if name not in ORIGINALS:
        raise ValueError(f"no carried Python client file {name!r}")
    packaged = resources.files(__package__).joinpath(name)
    if packaged.is_file():
        return packaged.read_text(encoding="utf-8")
    original = CHECKOUT / ORIGINALS[name]
    if not original.is_file():
        raise FileNotFoundError(
            f"Python client source {name!r} is neither in the package "
            f"nor at {original} (build the wheel from a checkout)"
        )
    return original.read_text(encoding="utf-8")

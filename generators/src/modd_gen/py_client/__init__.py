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

from ..carried import read_carried

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
        "zenoh_gate_policy.py",
        "zenoh_mesh.py",
        "zenoh_recovery.py",
        "subbroker/__init__.py",
        "subbroker/client.py",
        "subbroker/keys.py",
        "subbroker/payload.py",
        "subbroker/seen.py",
    )
} | {
    f"modd_contracts/{name}": f"{_MM}/modd_contracts/{name}"
    for name in ("__init__.py", "keys.py", "types_gen.py")
}


def read(name: str) -> str:
    """One carried file (a key of :data:`ORIGINALS`): the wheel's copy, else the checkout's."""
    return read_carried(__package__, ORIGINALS, name, "Python client")

"""The C++ client sources the generators carry into generated projects
(publisher client, with the ingress wire header it shares with the
PubBroker, into driver projects; subscriber client into subscriber projects).

Their one home is runtime/cpp (built and tested there); nothing is committed
here. A wheel gets them at build time (``force-include`` in
generators/pyproject.toml puts them in this package, read with
:mod:`importlib.resources`), so an installed wheel generates what a checkout
does; a checkout (an editable install, the Docker images' ``uv sync``) reads
the originals.

>>> header, source = client("publisher")
>>> "namespace modd" in header and source.startswith("#include")
True
"""

from __future__ import annotations

from ..carried import read_carried

#: file in this package (in a wheel) -> its original, relative to the repository.
ORIGINALS = {
    "publisher.hpp": "runtime/cpp/include/modd/client/publisher.hpp",
    "publisher.cpp": "runtime/cpp/src/client/publisher.cpp",
    "subscriber.hpp": "runtime/cpp/include/modd/client/subscriber.hpp",
    "subscriber.cpp": "runtime/cpp/src/client/subscriber.cpp",
    "delivered_value.gen.hpp": "runtime/cpp/include/modd/client/delivered_value.gen.hpp",
    "wire.hpp": "runtime/cpp/include/modd/ingress/wire.hpp",  # the publisher's, shared
    # its codes and limits, generated from modd_contracts/wire.json
    "wire.gen.hpp": "runtime/cpp/include/modd/ingress/wire.gen.hpp",
    # the aarch64 cross toolchain, which also cross-builds the runtime itself (make test)
    "aarch64-linux-gnu.cmake": "runtime/cpp/cmake/aarch64-linux-gnu.cmake",
}


def read(name: str) -> str:
    """One carried file (a key of :data:`ORIGINALS`): the wheel's copy, else the checkout's."""
    return read_carried(__package__, ORIGINALS, name, "C++ client")


def client(kind: str) -> tuple[str, str]:
    """``(header, source)`` of the ``publisher`` or ``subscriber`` client."""
    return read(f"{kind}.hpp"), read(f"{kind}.cpp")

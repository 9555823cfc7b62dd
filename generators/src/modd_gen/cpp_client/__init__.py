"""The C++ client sources the generators carry into generated projects
(publisher client into driver projects, subscriber client into subscriber
projects), as package data read with :mod:`importlib.resources`, so an
installed wheel (the backend's image) generates what a checkout does.

Their one home stays runtime/cpp (built and tested there); this folder holds
a copy, refreshed by ``python -m modd_gen.cpp_client`` and held to the
originals by a test and ``make check`` (``--check``).

>>> header, source = client("publisher")
>>> "namespace modd" in header and source.startswith("#include")
True
"""

from __future__ import annotations

import argparse
import sys
from importlib import resources
from pathlib import Path

#: file in this package -> its original, relative to the repository.
ORIGINALS = {
    "publisher.hpp": "runtime/cpp/include/modd/client/publisher.hpp",
    "publisher.cpp": "runtime/cpp/src/client/publisher.cpp",
    "subscriber.hpp": "runtime/cpp/include/modd/client/subscriber.hpp",
    "subscriber.cpp": "runtime/cpp/src/client/subscriber.cpp",
    "delivered_value.gen.hpp": "runtime/cpp/include/modd/client/delivered_value.gen.hpp",
}


def read(name: str) -> str:
    """One carried file (a key of :data:`ORIGINALS`)."""
    if name not in ORIGINALS:
        raise ValueError(f"no carried C++ file {name!r}")
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def client(kind: str) -> tuple[str, str]:
    """``(header, source)`` of the ``publisher`` or ``subscriber`` client."""
    return read(f"{kind}.hpp"), read(f"{kind}.cpp")


def stale(repo: Path) -> list[str]:
    """Carried files that differ from their originals in the checkout ``repo``."""
    return [name for name, original in ORIGINALS.items()
            if read(name) != (repo / original).read_text(encoding="utf-8")]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="refresh the carried C++ client sources")
    parser.add_argument("--check", action="store_true", help="exit 1 if a copy is stale")
    args = parser.parse_args(argv)
    repo = Path(__file__).resolve().parents[4]  # a checkout: where the originals are
    if args.check:
        for name in stale(repo):
            print(f"stale: {name} (run python -m modd_gen.cpp_client)", file=sys.stderr)
        return 1 if stale(repo) else 0
    here = Path(__file__).resolve().parent
    for name, original in ORIGINALS.items():
        (here / name).write_text((repo / original).read_text(encoding="utf-8"), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())

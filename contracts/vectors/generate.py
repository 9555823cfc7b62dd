"""The one writer of the protocols' test vectors, with the Python codecs:
``link/`` (the link protocol: frames, backfill, datagrams; docs/protocol.md)
and ``ingress/`` (the ingress's replies; docs/ingress.md). Both codecs' tests
read them byte for byte (runtime/python/tests, runtime/cpp/tests), and a test
checks that this script reproduces the committed files.

The contracts' own vectors beside them (``keys.json``, ``status.json``,
``delivered_value.json``, ``archive_record.json``) are written by hand: they
are the specification the code is checked against, not its output.

Run: .venv/bin/python contracts/vectors/generate.py
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

HERE = Path(__file__).resolve().parent


def _load(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"vectors_{path.parent.name}", path)
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(root: Path = HERE) -> None:
    """Writes ``root/link/*.json`` and ``root/ingress/replies.json``."""
    sys.path.insert(0, str(HERE / "link"))  # the link writer's helpers, beside it
    link = _load(HERE / "link" / "generate.py")
    link.HERE = root / "link"
    link.HERE.mkdir(parents=True, exist_ok=True)
    link.main()
    ingress = _load(HERE / "ingress" / "generate.py")
    (root / "ingress").mkdir(parents=True, exist_ok=True)
    ingress.write(root / "ingress")


if __name__ == "__main__":
    main()
    print(f"wrote {HERE / 'link'} and {HERE / 'ingress'}")

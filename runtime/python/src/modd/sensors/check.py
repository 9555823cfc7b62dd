"""The model for ``modd-sensors``, read and validated by the metamodel in a child
process: the reader runs for the whole mission, and the DSL parser, the JSON
Schema validator and UDUNITS (~35 MB together) are needed only once, at start.
The child's diagnostics go to the reader's stderr, located as every tool
reports them; it hands the valid model back as JSON.

Example::

    model = checked_model("boat.modd")   # None (diagnostics printed) when invalid
"""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

CHECK_TIMEOUT_S = 300.0  # a cold start on a loaded single-board computer


def checked_model(path: str) -> dict[str, Any] | None:
    child = subprocess.run(
        [sys.executable, "-m", "modd.sensors.check", path],
        stdout=subprocess.PIPE,
        timeout=CHECK_TIMEOUT_S,
        check=False,
    )
    if child.returncode != 0:
        return None
    model: dict[str, Any] = json.loads(child.stdout)
    return model


def model_or_why(path: str) -> tuple[dict[str, Any] | None, str]:
    """The valid model, or None and its diagnostics (for a deploy's answer)."""
    child = subprocess.run(
        [sys.executable, "-m", "modd.sensors.check", path],
        capture_output=True,
        timeout=CHECK_TIMEOUT_S,
        check=False,
    )
    if child.returncode != 0:
        return None, child.stderr.decode(errors="replace").strip()[:500]
    model: dict[str, Any] = json.loads(child.stdout)
    return model, ""


def main(argv: list[str] | None = None) -> int:
    from modd_model import load_or_report

    (path,) = argv if argv is not None else sys.argv[1:]
    model = load_or_report(path)
    if model is None:
        return 1
    sys.stdout.write(json.dumps(model))
    return 0


if __name__ == "__main__":
    sys.exit(main())

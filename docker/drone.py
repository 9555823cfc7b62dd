"""The simulated drone of docker-compose.yml: ``modd up MODEL --part drone ...``
with the PubBroker's link listening on another address than the model's.

    python docker/drone.py --listen 0.0.0.0 MODEL --part drone --simulate --workdir DIR

`modd up` takes the link endpoint from the model (``PubBroker name("host":port,
...)``), which for the demo is loopback: another container could not reach it.
This writes a copy of the model whose PubBroker endpoint host is ``--listen``
(the port stays the model's) to ``DIR/model.json``, then replaces itself with
``modd up`` on that copy, passing every other argument through. Nothing else of
the model changes, so a deploy from the workbench matches what runs.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path


def listening_copy(model_path: str, host: str, workdir: Path) -> Path:
    """The model with its PubBroker endpoint host set to ``host``, as JSON in workdir."""
    from modd_model import load_or_report

    model = load_or_report(model_path)
    if model is None:
        raise SystemExit(f"drone: {model_path} is not a valid model")
    model["pubBroker"]["endpoint"]["host"] = host
    workdir.mkdir(parents=True, exist_ok=True)
    out = workdir / "model.json"
    out.write_text(json.dumps(model, indent=2) + "\n")
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="drone.py", description=__doc__.splitlines()[0])
    p.add_argument(
        "--listen",
        default="0.0.0.0",
        metavar="HOST",
        help="address the PubBroker's link listens on (default all interfaces)",
    )
    p.add_argument("--workdir", required=True, metavar="DIR", help="modd up's run directory")
    p.add_argument("model", metavar="MODEL")
    args, rest = p.parse_known_args(argv)
    workdir = Path(args.workdir)
    copy = listening_copy(args.model, args.listen, workdir)
    modd = str(Path(sys.executable).parent / "modd")
    argv_up = [modd, "up", str(copy), "--workdir", str(workdir), *rest]
    print("drone: " + " ".join(argv_up), flush=True)
    os.execv(modd, argv_up)
    return 1  # not reached


if __name__ == "__main__":
    raise SystemExit(main())

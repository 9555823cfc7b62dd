"""``modd generate FILE --out DIR [--role ROLE]``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from modd_model import load_or_report

from .artifact import write_artifacts
from .generate import ROLES, generate

INDEX = "INDEX.json"


def run(args: argparse.Namespace) -> int:
    model = load_or_report(args.file)
    if model is None:
        return 1
    out = Path(args.out)
    written = write_artifacts(out, generate(model, args.role))
    index = [
        {
            "path": w.artifact.path,
            "role": w.artifact.role,
            "ownership": w.artifact.ownership.value,
            "action": w.action,
        }
        for w in written
    ]
    (out / INDEX).write_text(
        json.dumps({"model": str(args.file), "files": index}, indent=2) + "\n", encoding="utf-8"
    )
    for entry in index:
        note = (
            " (yours: kept)"
            if entry["action"] == "kept"
            else (" (yours: written once)" if entry["ownership"] == "user" else "")
        )
        print(f"{entry['path']}{note}")
    print(f"{len(index)} files under {out} (index: {out / INDEX})")
    return 0


def register(sub: Any) -> None:
    p = sub.add_parser("generate", help="generate configs, driver projects and stubs")
    p.add_argument("file", metavar="FILE", help=".modd or .json model")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--role", choices=list(ROLES), help="only this role's files")
    p.set_defaults(func=run)

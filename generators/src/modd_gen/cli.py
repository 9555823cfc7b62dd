"""``modd generate FILE --out DIR [--role ROLE] [--station NAME=ENDPOINT ...]``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from modd_model import load_or_report

from .artifact import write_artifacts
from .generate import ROLES, generate
from .targets.stations import artifacts as station_artifacts
from .targets.stations import check_campaign, parse_station

INDEX = "INDEX.json"


def run(args: argparse.Namespace) -> int:
    try:
        stations = [parse_station(t) for t in args.station or ()]
        if stations:
            check_campaign(stations)
    except ValueError as exc:
        print(f"modd generate: {exc}", file=sys.stderr)
        return 2
    model = load_or_report(args.file)
    if model is None:
        return 1
    out = Path(args.out)
    made = generate(model, args.role)
    if stations and args.role in (None, "operator"):
        made += station_artifacts(model, stations)
    written = write_artifacts(out, made)
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
    p.add_argument(
        "--station",
        action="append",
        metavar="NAME[=ENDPOINT]",
        help="a base station of the campaign (twice or more): one SubBroker configuration "
        "each under operator/stations/NAME/, joined by zenoh's router mesh; NAME alone for "
        "a station nothing can connect to (behind a cellular link): it dials the others",
    )
    p.set_defaults(func=run)

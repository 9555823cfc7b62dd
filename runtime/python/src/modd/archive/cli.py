"""``modd archive recover FILE`` and ``modd archive info FILE`` (entry point
``modd.commands`` ``archive``). Imports stay inside the commands so that
``modd --help`` does not load the MCAP reader.

    modd archive info usv-20260101T000000Z-0000.mcap [--json] [--gap-s 2]
    modd archive recover usv-20260101T000000Z-0000.mcap [-o OUT | --in-place]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any


def register(sub: Any) -> None:
    p = sub.add_parser("archive", help="inspect or recover a PubBroker MCAP archive")
    cmds = p.add_subparsers(dest="archive_command", metavar="ACTION", required=True)
    info = cmds.add_parser("info", help="topics, message counts, time range and gaps")
    info.add_argument("file", metavar="FILE", type=Path)
    info.add_argument("--json", action="store_true", help="machine-readable output")
    info.add_argument(
        "--gap-s",
        type=float,
        default=None,
        metavar="S",
        help="report silences longer than S seconds (default: 5 x the topic's median interval)",
    )
    info.set_defaults(func=run_info)
    rec = cmds.add_parser("recover", help="rewrite a crashed file with its summary and index")
    rec.add_argument("file", metavar="FILE", type=Path)
    out = rec.add_mutually_exclusive_group()
    out.add_argument("-o", "--output", type=Path, help="output file (default FILE-recovered.mcap)")
    out.add_argument("--in-place", action="store_true", help="replace FILE (atomically)")
    rec.set_defaults(func=run_recover)


def _check(path: Path) -> str | None:
    if not path.is_file():
        return f"modd archive: {path}: no such file"
    return None


def run_info(args: argparse.Namespace) -> int:
    from .info import archive_info, format_info

    if (err := _check(args.file)) is not None:
        print(err, file=sys.stderr)
        return 2
    gap = None if args.gap_s is None else int(args.gap_s * 1e9)
    try:
        info = archive_info(args.file, min_gap_ns=gap)
    except (ValueError, OSError, MemoryError) as exc:
        print(f"modd archive info: {exc}", file=sys.stderr)
        return 1
    print(json.dumps(info.to_json(), indent=1) if args.json else format_info(info))
    return 0


def run_recover(args: argparse.Namespace) -> int:
    from .recover import format_report, recover

    if (err := _check(args.file)) is not None:
        print(err, file=sys.stderr)
        return 2
    output = args.file if args.in_place else args.output
    try:
        r = recover(args.file, output)
    except (ValueError, OSError, MemoryError) as exc:
        print(f"modd archive recover: {exc}", file=sys.stderr)
        return 1
    print(format_report(r))
    return 0

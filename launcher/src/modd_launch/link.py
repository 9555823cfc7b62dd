"""``modd link cut|restore|status``: rehearse an outage on the simulated link
of a ``modd up --simulate`` run (``make run``), for training: ``cut`` drops the
SubBroker's link to the PubBroker and keeps it down, ``restore`` lets it
reconnect at once (then *Fill gaps* in the workbench, or ``modd backfill``,
recovers what was missed). The run is named by its ``--workdir`` (``make
run``'s is ``data/run``) or by its drone (``modd up``'s default run directory).

>>> main_args = ["link", "cut", "--workdir", "data/run"]  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any


def _folder(args: argparse.Namespace) -> Path:
    from modd.subbroker.rehearsal import FOLDER

    if args.workdir:
        return Path(str(args.workdir)) / FOLDER
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    base = Path(runtime) / "modd-up" if runtime else Path(f"/tmp/modd-up-{os.getuid()}")
    return base / str(args.drone) / FOLDER


def run(args: argparse.Namespace) -> int:
    from modd.subbroker.rehearsal import is_cut, set_cut

    folder = _folder(args)
    if not folder.is_dir():
        print(
            f"modd link: {folder} is not there: no `modd up --simulate` run (make run) "
            "in that directory; name it with --workdir DIR or --drone NAME",
            file=sys.stderr,
        )
        return 1
    if args.action in ("cut", "restore"):
        try:
            set_cut(folder, args.action == "cut")
        except OSError as exc:
            print(f"modd link: cannot {args.action} the link: {exc}", file=sys.stderr)
            return 1
    state = "cut (the SubBroker keeps it down)" if is_cut(folder) else "up (not cut)"
    print(f"modd link: the simulated link of {folder.parent} is {state}")
    return 0


def register(sub: Any) -> None:
    p = sub.add_parser(
        "link", help="cut or restore the simulated link of a modd up --simulate run (rehearsal)"
    )
    p.add_argument("action", choices=("cut", "restore", "status"))
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workdir", metavar="DIR", help="the run directory (make run: data/run)")
    where.add_argument(
        "--drone",
        metavar="NAME",
        default="usv",
        help="the drone of modd up's default run directory",
    )
    p.set_defaults(func=run)

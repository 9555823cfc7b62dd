"""``modd-pair FILE`` (and ``modd pair FILE``): import a pairing bundle made on
the workbench into this drone's configuration (``/etc/modd``).

The one-time code is read from ``--code-file PATH`` (``-``: standard input,
one line), else asked for at the terminal without echo, else read from
standard input: never from the command line, which shell history and ``ps``
keep. Exit status 0 when paired, 1 when the bundle is refused (the reason is
printed), 2 on a usage error.

    sudo modd-pair /media/usb/usv.modd-pair
    modd-pair usv.modd-pair --config-dir /tmp/etc-modd --code-file - < code.txt
"""

from __future__ import annotations

import argparse
import getpass
import os
import pwd
import sys
import time
from pathlib import Path
from typing import Any

from .bundle import MAX_BUNDLE_BYTES, BundleError, check_time, decrypt, verify
from .install import SERVICES, check_drone, check_pairing, current_drone, install

DEFAULT_DIR = Path("/etc/modd")
SERVICE_USER = "modd"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("bundle", type=Path, help="the .modd-pair file made on the workbench")
    p.add_argument(
        "--code-file",
        metavar="PATH",
        help="read the one-time code from PATH ('-': standard input); default: ask",
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument("--config-dir", type=Path, help=f"where to write (default {DEFAULT_DIR})")
    where.add_argument(
        "--root", type=Path, help="write into ROOT/etc/modd (an image being prepared)"
    )
    p.add_argument(
        "--drone", help="this drone's name (default: the name in pubbroker.json, if any)"
    )
    p.add_argument(
        "--owner",
        help=f"owner of the secrets (default: {SERVICE_USER} when run as root, else yourself)",
    )
    p.add_argument(
        "--new-station",
        action="store_true",
        help="accept a bundle signed by another base station than this drone's",
    )


def read_code(option: str | None) -> str:
    if option == "-" or (option is None and not sys.stdin.isatty()):
        return sys.stdin.readline().strip()
    if option is not None:
        try:
            return Path(option).read_text().strip()
        except OSError as exc:
            raise BundleError(f"code file {option}: {exc.strerror}") from None
    return getpass.getpass("pairing code (shown once on the workbench): ")


def default_owner() -> str | None:
    if os.geteuid() != 0:
        return None
    try:
        pwd.getpwnam(SERVICE_USER)
    except KeyError:
        return None
    return SERVICE_USER


def read_bundle(path: Path) -> bytes:
    try:
        with path.open("rb") as f:
            return f.read(MAX_BUNDLE_BYTES + 1)
    except OSError as exc:
        raise BundleError(f"{path}: {exc.strerror}") from None


def pair(args: argparse.Namespace) -> int:
    config_dir = args.config_dir or (args.root / "etc/modd" if args.root else DEFAULT_DIR)
    bundle = verify(read_bundle(args.bundle))
    this = (args.drone, "--drone") if args.drone else current_drone(config_dir)
    if this is not None:
        check_drone(bundle.drone, *this)
    check_time(bundle, time.time_ns())
    check_pairing(bundle, config_dir, args.new_station)
    opened = decrypt(bundle, read_code(args.code_file))
    owner = args.owner if args.owner is not None else default_owner()
    written = install(opened, config_dir, owner)
    print(f"modd-pair: drone {opened.drone!r} paired with base station {opened.fingerprint}")
    for path, mode in written.files:
        who = f", owner {owner}" if owner and mode == 0o600 else ""
        print(f"  wrote {path} ({mode:04o}{who})")
    print(f"now restart the drone's services: sudo systemctl restart {' '.join(SERVICES)}")
    return 0


def run(args: argparse.Namespace) -> int:
    try:
        return pair(args)
    except BundleError as exc:
        print(f"modd-pair: refused: {exc}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, EOFError):
        print("modd-pair: cancelled; nothing written", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"modd-pair: {exc.filename or ''}: {exc.strerror}", file=sys.stderr)
        return 1


def register(sub: Any) -> None:
    """``modd pair`` (the ``modd`` CLI's subcommand)."""
    p = sub.add_parser("pair", help="import a pairing bundle into this drone's configuration")
    add_arguments(p)
    p.set_defaults(func=run)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="modd-pair", description=__doc__.split("\n\n")[0])
    add_arguments(p)
    return run(p.parse_args(argv))

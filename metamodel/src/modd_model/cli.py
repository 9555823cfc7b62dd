"""The ``modd`` command line. Subcommands are plugins found through the
``modd.commands`` entry points, so each package (planner, generators, runtime)
registers its own: ``register(subparsers)`` adds a subparser and sets ``func``."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from importlib.metadata import entry_points
from typing import Any


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="modd", description="MoDD: model-driven data "
                                     "collection for drones.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for ep in sorted(entry_points(group="modd.commands"), key=lambda e: e.name):
        try:
            register = ep.load()
        except ImportError as exc:
            # A broken plugin must not take the other commands down with it.
            _register_broken(sub, ep.name, exc)
            continue
        register(sub)
    return parser


def _register_broken(sub: Any, name: str, exc: ImportError) -> None:
    def fail(_args: argparse.Namespace) -> int:
        print(f"modd {name}: this command could not be loaded: {exc}", file=sys.stderr)
        return 2

    p = sub.add_parser(name, help="(unavailable: failed to load)")
    p.set_defaults(func=fail)


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        code: int = args.func(args)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
    return code


if __name__ == "__main__":
    sys.exit(main())

"""The ``modd`` command line. Subcommands are plugins found through the
``modd.commands`` entry points, so each package (planner, generators, runtime)
registers its own: ``register(subparsers)`` adds a subparser and sets ``func``.

Plugins load lazily: ``modd --help`` lists the entry points' names without
importing any of them, and ``modd COMMAND ...`` imports only that command's
plugin (``push`` pulls in the backend application; ``plan`` only the planner).
This module imports nothing of ``modd_model`` itself.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

#: One-line help of the known commands, shown by ``modd --help`` without
#: loading their plugins (a plugin not listed here shows its entry point).
COMMAND_HELP = {
    "archive": "inspect or recover a PubBroker MCAP archive",
    "backfill": "fill what the link missed from the drone's archive",
    "convert": "convert a model between .modd, JSON and the original tool's .collector",
    "fmt": "rewrite models in canonical form",
    "generate": "generate configs, driver projects and stubs",
    "link": "cut or restore the simulated link of a modd up --simulate run (rehearsal)",
    "plan": "schedule, buffer sizes, delays and link cost of a model",
    "push": "put a model into a running workbench (and deploy it)",
    "up": "run a model locally: PubBroker, SubBroker, simulated sensors",
    "validate": "check models; errors with file:line:col on stderr",
}

_DESCRIPTION = "MoDD: model-driven data collection for drones."


#: The metamodel's own commands, as its pyproject.toml declares them (a test
#: holds the two to each other): ``modd plan FILE`` and these others start
#: without reading every installed distribution's entry points
#: (importlib.metadata and its imports cost a fifth of the start-up).
BUILTIN = {
    "convert": "modd_model.commands:register_convert",
    "fmt": "modd_model.commands:register_fmt",
    "plan": "modd_plan.cli:register",
    "validate": "modd_model.commands:register_validate",
}


def _entry_points() -> dict[str, EntryPoint]:
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group="modd.commands")}


def _builtin_parser(command: str) -> argparse.ArgumentParser:
    parser, sub = _new_parser()
    module, _, attr = BUILTIN[command].partition(":")
    getattr(import_module(module), attr)(sub)
    return parser


def _new_parser() -> tuple[argparse.ArgumentParser, Any]:
    parser = argparse.ArgumentParser(prog="modd", description=_DESCRIPTION)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    return parser, sub


def _load(sub: Any, ep: EntryPoint) -> None:
    try:
        register = ep.load()
    except ImportError as exc:
        # A broken plugin must not take the other commands down with it.
        _register_broken(sub, ep.name, exc)
        return
    register(sub)


def build_parser(command: str | None = None, *, load_all: bool = True) -> argparse.ArgumentParser:
    """The parser with ``command``'s plugin loaded (every plugin when
    ``command`` is None and ``load_all``); the other commands are listed by
    name only."""
    parser, sub = _new_parser()
    for name, ep in sorted(_entry_points().items()):
        if name == command or (command is None and load_all):
            _load(sub, ep)
        else:  # listed for --help and for argparse's "invalid choice" message
            sub.add_parser(name, help=COMMAND_HELP.get(name, f"(plugin {ep.value})"))
    return parser


def _command_of(argv: Sequence[str], names: set[str]) -> str | None:
    """The subcommand named on the command line (the first non-option word)."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in names else None
    return None


def _register_broken(sub: Any, name: str, exc: ImportError) -> None:
    def fail(_args: argparse.Namespace) -> int:
        print(f"modd {name}: this command could not be loaded: {exc}", file=sys.stderr)
        return 2

    p = sub.add_parser(name, help="(unavailable: failed to load)")
    p.set_defaults(func=fail)


def main(argv: Sequence[str] | None = None) -> int:
    args_in = list(sys.argv[1:] if argv is None else argv)
    builtin = _command_of(args_in, set(BUILTIN))
    if builtin is not None:
        args = _builtin_parser(builtin).parse_args(args_in)
    else:
        command = _command_of(args_in, set(_entry_points()))
        args = build_parser(command, load_all=False).parse_args(args_in)
    try:
        code: int = args.func(args)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
    return code


if __name__ == "__main__":
    sys.exit(main())

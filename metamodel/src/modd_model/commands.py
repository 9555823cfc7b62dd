"""``modd validate``, ``modd convert`` and ``modd fmt``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .collector import print_collector
from .comments import keep_comments
from .io import LoadResult, decode, dumps, format_of, load_file, load_or_report, write_atomic
from .science import no_position


def _report(result: LoadResult, quiet_warnings: bool = False) -> None:
    for d in result.diagnostics:
        if d.severity == "warning" and quiet_warnings:
            continue
        print(d, file=sys.stderr)


def run_validate(args: argparse.Namespace) -> int:
    status = 0
    for path in args.files:
        result = load_file(path, args.encoding)
        _report(result)
        if not result.ok:
            status = 1
            continue
        if result.model is not None and (note := no_position(result.model)) is not None:
            print(f"{path}: {note.severity}: {note.message} [{note.pointer}]", file=sys.stderr)
        if not args.quiet:
            print(f"{path}: valid")
    return status


def run_convert(args: argparse.Namespace) -> int:
    model = load_or_report(args.file, quiet_warnings=True, encoding=args.encoding)
    if model is None:
        return 1
    if args.to == "collector":
        text, omitted = print_collector(model)
        for d in omitted:
            print(d, file=sys.stderr)
    else:
        text = dumps(model, args.to)
    try:
        if args.output and args.output != "-":
            write_atomic(args.output, text)
        else:
            sys.stdout.write(text)
    except OSError as exc:
        print(f"{args.output}: cannot write: {exc.strerror or exc}", file=sys.stderr)
        return 1
    return 0


def run_fmt(args: argparse.Namespace) -> int:
    status = 0
    for path in args.files:
        result = load_file(path, args.encoding)
        _report(result, quiet_warnings=True)
        if not result.ok or result.model is None:
            status = 1
            continue
        current = Path(path).read_bytes()
        text = _canonical(path, result, current, args)
        if current == text.encode("utf-8"):
            continue
        if args.check:
            print(f"{path}: not in canonical form", file=sys.stderr)
            status = 1
            continue
        try:
            write_atomic(path, text)
        except OSError as exc:
            print(
                f"{path}: cannot write ({exc.strerror or exc}); the file is unchanged",
                file=sys.stderr,
            )
            status = 1
            continue
        print(f"{path}: reformatted")
    return status


def _canonical(path: str, result: LoadResult, current: bytes, args: argparse.Namespace) -> str:
    """The canonical text of a loaded file, its comments kept in their places
    (unless --drop-comments): they are not part of the model, so the printer
    alone would lose them."""
    assert result.model is not None
    text = dumps(result.model, format_of(path))
    if format_of(path) != "modd" or args.drop_comments:
        return text
    source, _ = decode(current, path, args.encoding)
    return text if source is None else keep_comments(source, result.source_map, text)


def register_validate(sub: Any) -> None:
    p = sub.add_parser("validate", help="check models; errors with file:line:col on stderr")
    p.add_argument("files", nargs="+", metavar="FILE", help=".modd or .json model")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing for valid files")
    _encoding_option(p)
    p.set_defaults(func=run_validate)


def register_convert(sub: Any) -> None:
    p = sub.add_parser(
        "convert", help="convert a model between .modd, JSON and the original tool's .collector"
    )
    p.add_argument("file", metavar="FILE")
    p.add_argument(
        "--to",
        choices=["json", "modd", "collector"],
        required=True,
        help="collector: the original tool's form (says what it leaves out)",
    )
    p.add_argument("-o", "--output", metavar="OUT", help="output file (default: stdout)")
    _encoding_option(p)
    p.set_defaults(func=run_convert)


def register_fmt(sub: Any) -> None:
    p = sub.add_parser("fmt", help="rewrite models in canonical form")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.add_argument(
        "--check", action="store_true", help="only report files not in canonical form (exit 1)"
    )
    p.add_argument(
        "--drop-comments",
        action="store_true",
        help="leave the comments out of the canonical form (kept by default)",
    )
    _encoding_option(p)
    p.set_defaults(func=run_fmt)


def _encoding_option(p: Any) -> None:
    p.add_argument(
        "--encoding",
        metavar="NAME",
        help="the file's text encoding (default: "
        "UTF-8, or windows-1252 for a file that is not UTF-8)",
    )

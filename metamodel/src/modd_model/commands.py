"""``modd validate``, ``modd convert`` and ``modd fmt``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .io import LoadResult, dumps, format_of, load_file, load_or_report


def _report(result: LoadResult, quiet_warnings: bool = False) -> None:
    for d in result.diagnostics:
        if d.severity == "warning" and quiet_warnings:
            continue
        print(d, file=sys.stderr)


def run_validate(args: argparse.Namespace) -> int:
    status = 0
    for path in args.files:
        result = load_file(path)
        _report(result)
        if not result.ok:
            status = 1
        elif not args.quiet:
            print(f"{path}: valid")
    return status


def run_convert(args: argparse.Namespace) -> int:
    model = load_or_report(args.file, quiet_warnings=True)
    if model is None:
        return 1
    text = dumps(model, args.to)
    if args.output and args.output != "-":
        Path(args.output).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


def run_fmt(args: argparse.Namespace) -> int:
    status = 0
    for path in args.files:
        model = load_or_report(path, quiet_warnings=True)
        if model is None:
            status = 1
            continue
        text = dumps(model, format_of(path))
        current = Path(path).read_text(encoding="utf-8")
        if current == text:
            continue
        if args.check:
            print(f"{path}: not in canonical form", file=sys.stderr)
            status = 1
        else:
            Path(path).write_text(text, encoding="utf-8")
            print(f"{path}: reformatted")
    return status




def register_validate(sub: Any) -> None:
    p = sub.add_parser("validate", help="check models; errors with file:line:col on stderr")
    p.add_argument("files", nargs="+", metavar="FILE", help=".modd or .json model")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing for valid files")
    p.set_defaults(func=run_validate)


def register_convert(sub: Any) -> None:
    p = sub.add_parser("convert", help="convert a model between .modd and JSON")
    p.add_argument("file", metavar="FILE")
    p.add_argument("--to", choices=["json", "modd"], required=True)
    p.add_argument("-o", "--output", metavar="OUT", help="output file (default: stdout)")
    p.set_defaults(func=run_convert)


def register_fmt(sub: Any) -> None:
    p = sub.add_parser("fmt", help="rewrite models in canonical form")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.add_argument("--check", action="store_true", help="only report files not in canonical "
                   "form (exit 1)")
    p.set_defaults(func=run_fmt)

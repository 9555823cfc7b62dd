"""``modd dataset`` (entry point ``modd.commands`` ``dataset``)::

    modd dataset ARCHIVE_DIR_OR_FILES... --model MODEL --format netcdf|parquet|csv|geojson|gpx
                 -o OUT [--from T0 --to T1] [--topics T ...] [--resample PERIOD] [--received]
                 [--metadata FILE] [--time receive|instrument]

With --received the files are base-station records (the SubBroker's
``record/<drone>/*.mcap``) and the dataset holds the windows the subscribers
received; --topics then names subscribers or their topics.

--metadata FILE (YAML or JSON, ACDD/IOOS attribute names: creator_name,
publisher_url, license, platform, instruments...) describes the dataset for a
data centre; without it, ``dataset.yaml`` or ``dataset.json`` beside the model
is read when there is one (docs/user-guide/datasets.md, "Metadata").

Times are ISO 8601 (``2026-11-27T10:00:00Z``; UTC when no offset is given) or
seconds since the Unix epoch; PERIOD is seconds (``0.5``, ``10s``). Exit 0
with the dataset written; 1 on a request or archive error (one located line
on stderr, never a traceback, and no partial output left behind); 2 on bad
arguments.
"""

from __future__ import annotations

import argparse
import datetime as dt
import sys
from pathlib import Path
from typing import Any

FORMATS = ("netcdf", "parquet", "csv", "geojson", "gpx")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "dataset",
        help="export the archive as a dataset (NetCDF, Parquet, "
        "CSV, GeoJSON, GPX) with units and positions",
        description=__doc__.split("\n\n")[1] if __doc__ else None,
    )
    p.add_argument("paths", nargs="+", type=Path, metavar="ARCHIVE_DIR_OR_FILES")
    p.add_argument("--model", required=True, type=Path, help="the model the archive was made with")
    p.add_argument("--format", required=True, choices=FORMATS)
    p.add_argument("-o", "--output", required=True, type=Path, metavar="OUT")
    p.add_argument(
        "--from",
        dest="start",
        type=parse_time,
        metavar="T0",
        help="first time (ISO 8601 or Unix seconds)",
    )
    p.add_argument("--to", dest="end", type=parse_time, metavar="T1", help="end time (excluded)")
    p.add_argument(
        "--topics",
        nargs="+",
        metavar="TOPIC",
        help="topics to export (drone.sensor.variable, sensor.variable or variable)",
    )
    p.add_argument(
        "--resample",
        type=parse_period,
        metavar="PERIOD",
        help="wide form: the mean of each topic per PERIOD seconds",
    )
    p.add_argument(
        "--received",
        action="store_true",
        help="the files are base-station records: export the windows the subscribers received",
    )
    p.add_argument(
        "--time",
        dest="clock",
        choices=("receive", "instrument"),
        default="receive",
        help="the time axis: the PubBroker's receive time (default), or the instrument's "
        "time for sensors declaring clock = instrument; the other clock is written beside it",
    )
    p.add_argument(
        "--metadata",
        type=Path,
        metavar="FILE",
        help="the dataset's metadata (YAML or JSON: creator, publisher, license...; "
        "default: dataset.yaml or dataset.json beside the model)",
    )
    p.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="progress on stderr (default: when stderr is a terminal)",
    )
    p.set_defaults(func=run)


def parse_time(text: str) -> int:
    """ns since the Unix epoch."""
    try:
        return int(round(float(text) * 1e9))
    except ValueError:
        pass
    try:
        t = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a time (ISO 8601 or Unix seconds)"
        ) from None
    if t.tzinfo is None:
        t = t.replace(tzinfo=dt.UTC)
    return int(t.timestamp()) * 1_000_000_000 + t.microsecond * 1000


def parse_period(text: str) -> float:
    try:
        value = float(text.removesuffix("s"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a period in seconds") from None
    if not 0 < value <= 86_400:
        raise argparse.ArgumentTypeError("the period must be in (0, 86400] seconds")
    return value


def run(args: argparse.Namespace) -> int:
    from modd_model.io import load_or_report

    from .build import DatasetError, make_dataset
    from .metadata import MetadataError, load_metadata, project_metadata

    model = load_or_report(args.model, quiet_warnings=True)
    if model is None:
        return 1
    meta_path = args.metadata or project_metadata(args.model)
    try:
        metadata = load_metadata(meta_path) if meta_path is not None else None
    except MetadataError as exc:
        print(f"modd dataset: {exc}", file=sys.stderr)
        return 1
    progress = sys.stderr.isatty() if args.progress is None else args.progress
    try:
        summary = make_dataset(
            args.paths,
            model,
            args.format,
            args.output,
            start_ns=args.start,
            end_ns=args.end,
            topics=args.topics,
            resample_s=args.resample,
            progress=progress,
            received=args.received,
            metadata=metadata,
            clock=args.clock,
        )
    except DatasetError as exc:
        print(f"modd dataset: {exc}", file=sys.stderr)
        return 1
    for note in summary.notes:
        print(f"modd dataset: note: {note}", file=sys.stderr)
    print(
        f"{args.output}: {summary.samples:,} "
        + (
            f"values of {len(summary.per_topic)} subscribers"
            if args.received
            else f"samples of {len(summary.per_topic)} topics"
        )
        + f" ({args.format})"
    )
    return 0

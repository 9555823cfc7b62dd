"""``modd backfill``: fill what the link missed from the drone's archive
(entry point ``modd.commands`` ``backfill``; docs/subbroker.md, "Backfill").

    modd backfill --drone usv --subscriber sub_5 --gaps
    modd backfill --drone usv --subscriber sub_5 --from 2026-11-24T10:00:00Z --to 1795000000 --json

It asks the SubBroker's ``modd/<drone>/backfill`` queryable (zenoh at
``tcp/127.0.0.1:7447`` unless ``--connect`` or ``$MODD_ZENOH_CONNECT`` says
otherwise, with the backend's credentials from ``--credentials`` or
``$MODD_ZENOH_CREDENTIALS``), shows a progress bar on stderr and, with
``--json``, ends with one line ``{"windows": N, "duplicates": N, "bytes": N,
"seconds": S}``. Imports stay inside the command (``modd --help`` loads none).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import UTC, datetime
from typing import Any

POLL_S = 0.25


def parse_time(text: str) -> int:
    """Seconds since the epoch or ISO 8601 UTC, as nanoseconds.

    >>> parse_time("1795000000.5"), parse_time("2026-11-24T00:00:00Z")
    (1795000000500000000, 1795478400000000000)
    """
    try:
        return int(round(float(text) * 1e9)) if "." in text else int(text) * 1_000_000_000
    except ValueError:
        pass
    try:
        when = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(
            f"{text!r} is neither seconds since the epoch nor ISO 8601 UTC"
        ) from exc
    if when.tzinfo is None:
        when = when.replace(tzinfo=UTC)
    return int(when.timestamp()) * 1_000_000_000 + when.microsecond * 1000


def register(sub: Any) -> None:
    p = sub.add_parser("backfill", help="fill what the link missed from the drone's archive")
    p.add_argument("--drone", required=True, help="the drone's name (its SubBroker's keys)")
    p.add_argument("--subscriber", required=True, help="whose subscriptions to fill")
    span = p.add_mutually_exclusive_group(required=True)
    span.add_argument(
        "--gaps", action="store_true", help="every window missed since the running config began"
    )
    span.add_argument(
        "--from",
        dest="t0",
        type=parse_time,
        metavar="T0",
        help="start: seconds since the epoch or ISO 8601 UTC (with --to)",
    )
    p.add_argument("--to", dest="t1", type=parse_time, metavar="T1", help="end (with --from)")
    p.add_argument(
        "--rate", type=int, metavar="B/s", help="cap the pace (default: the link's spare budget)"
    )
    p.add_argument("--json", action="store_true", help="end with one JSON line of figures")
    p.add_argument(
        "--connect", default=None, help="the SubBroker's zenoh (default tcp/127.0.0.1:7447)"
    )
    p.add_argument(
        "--credentials", default=None, help="a backend .cred file (default $MODD_ZENOH_CREDENTIALS)"
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=3600.0,
        metavar="S",
        help="give up (and cancel) after S seconds",
    )
    p.set_defaults(func=run)


def _ask(session: Any, key: str, request: dict[str, Any]) -> dict[str, Any]:
    for reply in session.get(key, payload=json.dumps(request), timeout=10.0):
        if reply.ok is not None:
            out: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
            return out
    raise ConnectionError(
        f"no answer on {key}: is the SubBroker running (and are the credentials a backend's)?"
    )


def _bar(p: dict[str, Any]) -> str:
    total, done = int(p.get("windows_total", 0)), int(p.get("windows_done", 0))
    width = 30
    filled = width if total == 0 else width * done // total
    left = p.get("seconds_left")
    eta = f"  {left:.0f} s left" if isinstance(left, int | float) else ""
    why = (
        f"  ({str(p.get('reason'))[:60]})"
        if p.get("status") == "RUNNING" and p.get("reason")
        else ""
    )
    return (
        f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} windows  "
        f"{p.get('bytes_per_s', 0):.0f}/{p.get('rate_bps') or '-'} B/s{eta}{why}   "
    )


def run(args: argparse.Namespace) -> int:
    from .subbroker.keys import backfill_key
    from .zenoh_session import client_settings, open_session

    if (args.t0 is None) != (args.t1 is None):
        print("modd backfill: --from and --to go together", file=sys.stderr)
        return 2
    request: dict[str, Any] = {"op": "start", "subscriber": args.subscriber}
    if args.gaps:
        request["gaps"] = True
    else:
        request["from_ns"], request["to_ns"] = args.t0, args.t1
    if args.rate is not None:
        request["rate_bps"] = args.rate
    try:
        key = backfill_key(args.drone)
        session = open_session(client_settings(args.connect, args.credentials))
    except (ValueError, OSError) as exc:
        print(f"modd backfill: {exc}", file=sys.stderr)
        return 2
    try:
        return _follow(session, key, request, args)
    except ConnectionError as exc:
        print(f"modd backfill: {exc}", file=sys.stderr)
        return 1
    finally:
        session.close()  # type: ignore[no-untyped-call]


def _follow(session: Any, key: str, request: dict[str, Any], args: argparse.Namespace) -> int:
    p = _ask(session, key, request)
    if p.get("status") not in ("RUNNING", "DONE"):
        print(f"modd backfill: {p.get('status')}: {p.get('reason')}", file=sys.stderr)
        return 1
    job_id = p["id"]
    deadline = time.monotonic() + args.timeout
    try:
        while p.get("status") == "RUNNING":
            if sys.stderr.isatty() or not args.json:
                print(_bar(p), end="", file=sys.stderr, flush=True)
            if time.monotonic() > deadline:
                p = _ask(session, key, {"op": "cancel", "id": job_id})
                break
            time.sleep(POLL_S)
            p = _ask(session, key, {"op": "progress", "id": job_id})
    except KeyboardInterrupt:
        p = _ask(session, key, {"op": "cancel", "id": job_id})
    print(_bar(p), file=sys.stderr)
    if p.get("status") != "DONE":
        print(f"modd backfill: {p.get('status')}: {p.get('reason')}", file=sys.stderr)
    if args.json:
        print(
            json.dumps(
                {
                    "windows": p.get("windows", 0),
                    "duplicates": p.get("duplicates", 0),
                    "bytes": p.get("bytes", 0),
                    "seconds": p.get("seconds", 0.0),
                }
            )
        )
    return 0 if p.get("status") == "DONE" else 1

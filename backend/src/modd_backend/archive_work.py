"""The archive routes' work (reading an MCAP topic, formatting CSV, reducing a
series) in a small pool of worker processes, never in the service's own
process: a reader of a large file is pure Python, and several of them in
the worker threads would hold the interpreter lock away from the event loop,
so ``/api/health`` and every light route would wait behind them (issue 23:
health stalled 4-20 s during 40-70 parallel CSV exports). The workers and
their fair queue are archive_pool.py; here are the functions they run and the
bounds of each request (bytes read, samples held, seconds run).

>>> await pool.run(user, csv_text, path, "usv.a.x", None, None, time_s=60)  # doctest: +SKIP
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from .archives import Sample, read_topic, reduce_minmax

#: Worker processes reading archives (the machine's cores are shared with the brokers).
ARCHIVE_WORKERS = 2
#: Bytes one archive request may read (the sum of its files' sizes).
MAX_ARCHIVE_BYTES = 4 * 1024**3
#: Samples a series or CSV request holds at most (a topic's range).
MAX_TOPIC_SAMPLES = 2_000_000
#: Seconds a series or CSV may run in its worker before it is stopped (503).
TOPIC_TIME_S = 60.0
#: Seconds a dataset export may run in its worker before it is stopped (503).
EXPORT_TIME_S = 180.0
#: The shortest resampling period of an export, seconds (1 ms).
MIN_RESAMPLE_S = 0.001


class Refused(Exception):
    """Archive work refused by a bound: ``status`` (413 or 422) and why."""

    def __init__(self, status: int, text: str, **extra: Any) -> None:
        super().__init__(text)
        self.status = status
        self.extra = extra

    def __reduce__(self) -> Any:  # sent back from the worker with its status
        return (_refused, (self.status, str(self), self.extra))


def _refused(status: int, text: str, extra: dict[str, Any]) -> Refused:
    return Refused(status, text, **extra)


def check_bytes(paths: Iterable[Path], limit: int | None = None) -> int:
    """The bytes ``paths`` hold; Refused(413) beyond ``limit`` (MAX_ARCHIVE_BYTES)."""
    cap = MAX_ARCHIVE_BYTES if limit is None else limit
    total = sum(p.stat().st_size for p in paths)
    if total > cap:
        raise Refused(
            413,
            f"the files hold {total:,} bytes; one request reads at most {cap:,}: "
            "choose fewer files, or use `modd dataset` on the base station",
        )
    return total


def _topic(path: Path, topic: str, start_ns: int | None, end_ns: int | None) -> list[Sample]:
    samples = read_topic(path, topic, start_ns, end_ns, limit=MAX_TOPIC_SAMPLES)
    if len(samples) > MAX_TOPIC_SAMPLES:
        raise Refused(
            413,
            f"more than {MAX_TOPIC_SAMPLES:,} samples of {topic} in the range: "
            "choose a shorter range",
        )
    return samples


def csv_text(path: Path, topic: str, start_ns: int | None, end_ns: int | None) -> str:
    """Every sample of the range, unreduced: ``log_time_ns,topic,value``."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["log_time_ns", "topic", "value"])
    for t, v in _topic(path, topic, start_ns, end_ns):
        writer.writerow([t, topic, v])
    return out.getvalue()


def series(
    path: Path, topic: str, start_ns: int | None, end_ns: int | None, max_points: int
) -> tuple[int, list[Sample]]:
    """(how many samples the range holds, at most ``max_points`` of them)."""
    samples = _topic(path, topic, start_ns, end_ns)
    return len(samples), reduce_minmax(samples, max_points)


#: The most samples one export from the browser may hold (about a day of 100 Hz on
#: 100 topics is 860 M: a scientist exports that with ``modd dataset``, not a browser).
MAX_EXPORT_SAMPLES = 20_000_000


def dataset_file(
    paths: list[Path],
    model: dict[str, Any],
    fmt: str,
    out: Path,
    start_ns: int | None,
    end_ns: int | None,
    topics: list[str] | None,
    resample_s: float | None,
    max_samples: int,
    received: bool = False,
    metadata: dict[str, Any] | None = None,
) -> tuple[list[str], int | None, int | None]:
    """``modd dataset`` (``--received`` with ``received``) into ``out`` (in a
    worker), with the dataset ``metadata`` (the object of a ``dataset.yaml``);
    its notes and the time span written (ns). Raises DatasetError."""
    from modd.dataset.build import DatasetError, make_dataset
    from modd.dataset.export import Options
    from modd.dataset.metadata import MetadataError, parse_metadata
    from modd_model import validate

    try:
        meta = parse_metadata(metadata, "metadata") if metadata is not None else None
    except MetadataError as exc:
        raise DatasetError(str(exc)) from None
    errors = [str(d) for d in validate(model) if d.severity == "error"]
    if errors:
        raise Refused(422, "the model is not valid", errors=errors[:20])
    check_bytes(paths)
    if resample_s is not None:
        check_resample(resample_s, _span_ns(paths, start_ns, end_ns), max_samples)
    summary = make_dataset(
        paths,
        model,
        fmt,
        out,
        start_ns=start_ns,
        end_ns=end_ns,
        topics=topics,
        resample_s=resample_s,
        options=Options(max_samples=max_samples),
        received=received,
        metadata=meta,
    )
    return summary.notes, summary.start_ns, summary.end_ns


def check_resample(resample_s: float, span_ns: int | None, max_samples: int) -> None:
    """Refused(422): a period under MIN_RESAMPLE_S, or one giving more grid
    points over ``span_ns`` than ``max_samples``."""
    if resample_s < MIN_RESAMPLE_S:
        raise Refused(
            422, f"resample_s {resample_s:g} is below the shortest period, {MIN_RESAMPLE_S:g} s"
        )
    if span_ns is not None and span_ns / 1e9 / resample_s > max_samples:
        raise Refused(
            422,
            f"resample_s {resample_s:g} gives {span_ns / 1e9 / resample_s:,.0f} points over "
            f"the range; at most {max_samples:,}: choose a longer period or a shorter range",
        )


def _span_ns(paths: list[Path], start_ns: int | None, end_ns: int | None) -> int | None:
    """The time the export covers: the range, clipped to the files' own
    (from their summaries; None when a file has none and the range is open)."""
    from mcap.reader import make_reader

    first: int | None = None
    last: int | None = None
    for path in paths:
        try:
            with path.open("rb") as f:
                summary = make_reader(f).get_summary()
        except Exception:  # a file being written: no summary
            summary = None
        st = summary.statistics if summary is not None else None
        if st is None or not st.message_count:
            if start_ns is None or end_ns is None:
                return None
            continue
        first = st.message_start_time if first is None else min(first, st.message_start_time)
        last = st.message_end_time if last is None else max(last, st.message_end_time)
    los = [x for x in (first, start_ns) if x is not None]
    his = [x for x in (last, end_ns) if x is not None]
    return max(0, min(his) - max(los)) if los and his else None

"""An export in two streaming passes over the archive files: the position
topics first (the track: a few bytes per fix), then every sample, batch by
batch, with its position interpolated, into a sink (one writer per format).
Memory is the track plus one decompressed chunk, whatever the mission's
length (the wide form adds one row per resampling period).

>>> summary = export(files, plan, NetcdfSink(out), Options())  # doctest: +SKIP
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Protocol

import numpy as np

from .mcapread import Batch, FileState, read_file
from .plan import ExportPlan, PlanError, Variable
from .position import Track, build_track
from .qc import QcRunner

#: Reads one file as batches: (path, state, progress, only topics).
Reader = Callable[
    [Path, FileState | None, Callable[[int], None] | None, set[str] | None], Iterator[Batch]
]


@dataclass(frozen=True)
class Options:
    """Bounds of the position cleaning (docs/user-guide/datasets.md)."""

    max_speed_ms: float = 100.0  # a fix implying more is a GPS glitch
    max_climb_ms: float = 50.0
    max_samples: int | None = None  # refuse more (the backend's bound)


@dataclass
class Summary:
    """What an export wrote, and everything worth a user's attention."""

    samples: int = 0
    per_topic: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    start_ns: int | None = None
    end_ns: int | None = None
    positioned: int = 0  # samples with a latitude and longitude
    lat_range: tuple[float, float] | None = None
    lon_range: tuple[float, float] | None = None
    alt_range: tuple[float, float] | None = None


class Sink(Protocol):
    """A format writer. ``open`` before any sample; ``write`` per batch (one
    topic, time order within a topic; ``historical`` marks a received window
    delivered by backfill; ``qc`` the samples' aggregate QARTOD flags, ``location``
    their positions' location test flags); ``close`` last, with the summary."""

    def open(self, plan: ExportPlan, track: Track | None) -> None: ...

    def write(
        self,
        var: Variable,
        time_ns: np.ndarray,
        value: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        other: np.ndarray | None = None,
        qc: np.ndarray | None = None,
        historical: np.ndarray | None = None,
        location: np.ndarray | None = None,
    ) -> None: ...

    def close(self, plan: ExportPlan, summary: Summary) -> None: ...


#: No time (numpy's NaT as int64 ns).
NAT = np.iinfo(np.int64).min


class TooMany(PlanError):
    """More samples than the caller allows."""


def find_files(paths: list[Path]) -> list[Path]:
    """The MCAP files named, or held by the folders named, in time order."""
    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            out += sorted(f for f in p.iterdir() if f.suffix == ".mcap" and f.is_file())
        elif p.is_file():
            out.append(p)
        else:
            raise PlanError(f"{p}: no such file or folder")
    if not out:
        raise PlanError(f"no .mcap file in {', '.join(map(str, paths))}")
    return out


def clocked(plan: ExportPlan, var: Variable | None, b: Batch) -> Batch:
    """The batch on the plan's time axis; ``publish_ns`` then holds the other
    clock (the instrument's, NaN-free only for topics that declare it)."""
    if b.publish_ns is None or not plan.two_clocks:
        return b
    if plan.clock == "instrument" and var is not None and var.instrument_clock:
        return replace(b, time_ns=b.publish_ns, publish_ns=b.time_ns)
    return b


def _in_range(plan: ExportPlan, b: Batch) -> Batch:
    keep = np.ones(len(b.time_ns), dtype=bool)
    if plan.start_ns is not None:
        keep &= b.time_ns >= plan.start_ns
    if plan.end_ns is not None:
        keep &= b.time_ns < plan.end_ns
    if keep.all():
        return b
    pub = b.publish_ns[keep] if b.publish_ns is not None else None
    hist = b.historical[keep] if b.historical is not None else None
    return Batch(b.topic, b.value_type, b.time_ns[keep], b.value[keep], pub, hist)


def read_track(
    files: list[Path], plan: ExportPlan, options: Options, reader: Reader = read_file
) -> Track | None:
    """Pass 1: the position topics' fixes (all of them: interpolation needs
    the fixes just outside the asked range too)."""
    pos = plan.position
    if pos is None:
        return None
    roles = {pos.latitude: "latitude", pos.longitude: "longitude"}
    if pos.altitude:
        roles[pos.altitude] = "altitude"
    parts: dict[str, tuple[list[np.ndarray], list[np.ndarray]]] = {
        r: ([], []) for r in roles.values()
    }
    for path in files:
        for raw in reader(path, None, None, set(roles)):
            b = clocked(plan, plan.variables.get(raw.topic), raw)
            if b.topic in roles:
                ts, vs = parts[roles[b.topic]]
                ts.append(b.time_ns)
                vs.append(b.value.astype(np.float64))
    fixes = {
        r: (
            np.concatenate(ts) if ts else np.zeros(0, np.int64),
            np.concatenate(vs) if vs else np.zeros(0),
        )
        for r, (ts, vs) in parts.items()
    }
    return build_track(fixes, pos.max_gap_s, options.max_speed_ms, options.max_climb_ms)


def _account(
    s: Summary, var: Variable, b: Batch, lat: np.ndarray, lon: np.ndarray, alt: np.ndarray
) -> None:
    n = len(b.time_ns)
    s.samples += n
    s.per_topic[var.topic] = s.per_topic.get(var.topic, 0) + n
    lo, hi = int(b.time_ns.min()), int(b.time_ns.max())
    s.start_ns = lo if s.start_ns is None else min(s.start_ns, lo)
    s.end_ns = hi if s.end_ns is None else max(s.end_ns, hi)
    have = np.isfinite(lat) & np.isfinite(lon)
    s.positioned += int(have.sum())
    for attr, arr in (("lat_range", lat), ("lon_range", lon), ("alt_range", alt)):
        finite = arr[np.isfinite(arr)]
        if len(finite):
            old = getattr(s, attr)
            new = (float(finite.min()), float(finite.max()))
            setattr(s, attr, new if old is None else (min(old[0], new[0]), max(old[1], new[1])))


def _check_batch(
    plan: ExportPlan, b: Batch, path: Path, s: Summary, strangers: set[str]
) -> Variable | None:
    var = plan.variables.get(b.topic)
    if var is None:
        if b.topic in strangers:
            return None
        if plan.source == "received":
            strangers.add(b.topic)  # the subscribers chosen are known: say which were not
            s.notes.append(
                f"{path.name}: subscriber {b.topic} left out (not chosen, or not in the "
                "model: a dynamic subscription or another model revision)"
            )
        elif not b.topic.startswith(plan.drone + "."):
            strangers.add(b.topic)
            s.notes.append(
                f"{path.name}: topic {b.topic} is not in the model (an archive of "
                "another model or revision?): left out"
            )
        return None
    if var.value_type != b.value_type:
        raise PlanError(
            f"{path}: topic {b.topic} is archived as {b.value_type} but the model "
            f"says {var.value_type} (an archive of another model revision?)"
        )
    return var


#: Samples of one topic gathered before a writer sees them (a writer's cost is per call),
#: and the most held in all (the memory bound: ~40 B a sample).
BATCH = 1 << 16
HELD = 1 << 20


class _Batcher:
    """Gathers each topic's samples into large batches for ``emit``."""

    def __init__(self, emit: Callable[[Variable, Batch], None]) -> None:
        self.emit = emit
        self.parts: dict[str, tuple[Variable, list[Batch]]] = {}
        self.counts: dict[str, int] = {}
        self.held = 0

    def add(self, var: Variable, b: Batch) -> None:
        self.parts.setdefault(var.topic, (var, []))[1].append(b)
        n = self.counts[var.topic] = self.counts.get(var.topic, 0) + len(b.time_ns)
        self.held += len(b.time_ns)
        if n >= BATCH:
            self.flush(var.topic)
        elif self.held >= HELD:
            for topic in list(self.parts):
                self.flush(topic)

    def flush(self, topic: str) -> None:
        var, parts = self.parts.pop(topic)
        self.held -= self.counts.pop(topic)
        if len(parts) == 1:
            self.emit(var, parts[0])
            return
        time_ns = np.concatenate([p.time_ns for p in parts])
        pubs = [p.publish_ns for p in parts if p.publish_ns is not None]
        pub = np.concatenate(pubs) if len(pubs) == len(parts) else None
        value = np.concatenate([p.value for p in parts])
        hists = [p.historical for p in parts if p.historical is not None]
        hist = np.concatenate(hists) if len(hists) == len(parts) else None
        self.emit(var, Batch(topic, parts[0].value_type, time_ns, value, pub, hist))

    def close(self) -> None:
        for topic in list(self.parts):
            self.flush(topic)


def export(
    files: list[Path],
    plan: ExportPlan,
    sink: Sink,
    options: Options,
    progress: Callable[[str, int, int], None] | None = None,
    reader: Reader = read_file,
) -> Summary:
    """Writes the dataset into ``sink``: the samples of archive files, or with
    ``reader`` another kind of file (received.read_record: the windows of
    base-station records). Raises PlanError or mcapread.ArchiveError."""
    summary = Summary()
    track = read_track(files, plan, options, reader)
    if track is not None:
        summary.notes += track.notes
    runner = QcRunner(plan) if getattr(sink, "takes_qc", True) else None
    sink.open(plan, track)
    strangers: set[str] = set()
    nonfinite: dict[str, int] = {}

    def emit(var: Variable, b: Batch) -> None:
        nan = np.full(len(b.time_ns), np.nan)
        lat, lon, alt = track.at(b.time_ns) if track else (nan, nan, nan)
        flags = runner.flags(var, b.time_ns, b.value) if runner else None
        where = runner.location_flags(lat, lon) if runner else None
        other = other_clock(plan, var, b)
        sink.write(var, b.time_ns, b.value, lat, lon, alt, other, flags, b.historical, where)
        _account(summary, var, b, lat, lon, alt)

    batcher, seen = _Batcher(emit), 0
    for path in files:
        state = FileState(path)
        size = path.stat().st_size
        tick = (lambda done, p=path, n=size: progress(p.name, done, n)) if progress else None
        for raw in reader(path, state, tick, None):
            var = _check_batch(plan, raw, path, summary, strangers)
            b = _in_range(plan, clocked(plan, var, raw)) if var is not None else raw
            if var is None or len(b.time_ns) == 0:
                continue
            seen += len(b.time_ns)
            if options.max_samples is not None and seen > options.max_samples:
                raise TooMany(
                    f"more than {options.max_samples:,} samples in the range: "
                    "narrow the time range or the topics"
                )
            if b.value.dtype.kind == "f" and not np.isfinite(b.value).all():
                bad = int((~np.isfinite(b.value)).sum())
                nonfinite[var.topic] = nonfinite.get(var.topic, 0) + bad
            batcher.add(var, b)
        if state.cut_at is not None:
            summary.notes.append(
                f"{path.name}: not closed (cut or still being written): exported up "
                f"to offset {state.cut_at} of {size} bytes; "
                "`modd archive recover` closes it"
            )
    batcher.close()
    summary.notes += runner.notes.values() if runner else []
    _final_notes(plan, summary, nonfinite, track)
    sink.close(plan, summary)
    return summary


def other_clock(plan: ExportPlan, var: Variable, b: Batch) -> np.ndarray | None:
    """The second time of each sample (int64 ns; NAT, numpy's NaT, where there is
    none): the instrument's beside the receive axis (topics declaring it only),
    the receive time beside the instrument axis; None with one clock in the export."""
    if not plan.two_clocks:
        return None
    if b.publish_ns is None or (plan.clock == "receive" and not var.instrument_clock):
        return np.full(len(b.time_ns), NAT, dtype=np.int64)
    return b.publish_ns


def _final_notes(
    plan: ExportPlan, s: Summary, nonfinite: dict[str, int], track: Track | None
) -> None:
    received = plan.source == "received"
    for topic, n in nonfinite.items():
        s.notes.append(
            f"subscriber {topic}: {n} empty windows (no sample): fill values"
            if received
            else f"topic {topic}: {n} NaN/Inf samples, kept as they were archived"
        )
    for topic in plan.variables:
        if topic not in s.per_topic:
            s.notes.append(
                f"subscriber {topic}: no window in the range"
                if received
                else f"topic {topic}: no sample in the range"
            )
    if plan.position is None:
        s.notes.append("the model declares no position: latitude and longitude are fill values")
    elif track is not None and s.samples and s.positioned < s.samples:
        s.notes.append(
            f"{s.samples - s.positioned} of {s.samples} samples are outside the "
            f"track or in a gap of more than {track.max_gap_ns / 1e9:g} s between "
            "fixes: their position is the fill value"
        )


def print_progress(name: str, done: int, total: int) -> None:
    """A progress line on stderr (rewritten in place)."""
    pct = 100.0 * done / total if total else 100.0
    sys.stderr.write(f"\rmodd dataset: {name} {pct:5.1f}%")
    if done >= total:
        sys.stderr.write("\n")
    sys.stderr.flush()

"""`modd dataset` throughput and memory on an archive written by the real PubBroker,
side by side with the naive reference a scientist writes today (the workbench's per-topic
CSV export read with pandas, positions joined with merge_asof). Prints figures; asserts
nothing. The issue's targets: >= 1 M samples/s for netcdf and parquet, peak RSS <= 500 MB.

    .venv/bin/python tests/bench/bench_dataset.py [--samples 10000000] [--topics 20]
                                                  [--json build/bench/dataset.json] [--qc]
                                                  [--rate 1000] [--time instrument|receive]
                                                  [--repeat 1]

The archive: ``--topics`` float32 topics at one rate (``--rate``, per topic, default
1000 Hz), two of them the platform's latitude and longitude (a straight track), blasted
through the ingress (zstd chunks), as bench_pubbroker.py's ingest does. Each sample
carries its own sample time (the publisher's stamp, one per topic per period); the
PubBroker stamps its receive time, the same for every sample of one ingress frame of
4,096. By default (``--time instrument``) the model's two sensors are NMEA instruments
declaring ``clock = instrument``, so the archive's publish time is each sample's
instrument time and the export runs with ``--time instrument``: that is the time axis
(the receive time written beside it), as for a real instrument stating its clock.
``--time receive`` exports on the receive time (one clock, repeating within a frame).

``--qc`` exports with QARTOD flags on every topic but the position (a metadata file's
``qc`` section: gross range, spike, rate of change and flat line on 18 topics; above
1 Hz the two timed tests run in scaled time, docs/user-guide/datasets.md "Quality
flags"); the location test runs on every sample's position with or without ``--qc``
(the model declares a position). A test the export could not evaluate is printed (its
note): with ``--time receive`` the two timed tests are not evaluated (the times repeat).
``--repeat N`` runs each format N times, alternating, and reports the median run (by
wall time) with every run's wall and CPU seconds and the load average after each.
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "tests" / "runtime"), str(REPO / "tests" / "subbroker")]

import numpy as np  # noqa: E402
from modd.link.codec import varint  # noqa: E402
from modd.link.frames import ValueType  # noqa: E402
from modd.publisher import encode_hello, encode_register  # noqa: E402
from pubbroker_harness import PubBroker  # noqa: E402

BIN = Path(sys.executable).parent


def model_text(names: list[str], clock: str = "instrument") -> str:
    """The model: with ``clock = instrument`` both sensors are NMEA instruments stating
    their own time (the GNSS's GGA, the other's XDR quadruplets), so the archive's publish
    time is each sample's instrument time and ``--time instrument`` makes it the axis."""
    nmea = clock == "instrument"
    settings = ' kind nmea on "/dev/ttyUSB0" { clock = instrument; }' if nmea else ""
    gga = (" from sentence GGA.lat", " from sentence GGA.lon") if nmea else ("", "")
    variables = " ".join(
        f'{n.split(".")[2]}("1"){f" from sentence XDR.f{4 * i + 2}" if nmea else ""};'
        for i, n in enumerate(names[2:])
    )
    topics = ", ".join(f'"{n}"' for n in names)
    return (
        f"Drone usv {{ Sensors {{ Sensor gps{settings} measures {{ "
        f"lat(degree_north){gga[0]}; lon(degree_east){gga[1]}; }} "
        f"Sensor ins{settings} measures {{ {variables} }} }}\n"
        f'Position {{ latitude = "usv.gps.lat"; longitude = "usv.gps.lon"; }} }}\n'
        f'PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");\n'
        f"Publishers {{ Publisher p(0.01, {topics}); }}\nSubscriptions {{ }}\n"
    )


def write_archive(
    tmp: Path,
    total: int,
    topics: int,
    rate_hz: float = 1000.0,
    batch: int = 4096,
    clock: str = "instrument",
) -> tuple[Path, Path]:
    """(archive folder, model file): ``total`` samples through the real PubBroker, each
    stamped by its publisher with its own sample time (one per topic per period: the
    archive's publish time, the instrument's clock when the model declares it)."""
    names = ["usv.gps.lat", "usv.gps.lon"] + [f"usv.ins.t{i}" for i in range(topics - 2)]
    b = PubBroker(
        tmp,
        [(n, "float32") for n in names],
        archive={"queue_limit_samples": 50_000_000, "flush_interval_ms": 1000},
        # a mission's worth of samples, stamped in the past
        ingress={"max_future_ms": 0, "max_past_ms": 0},
        default_buffer_size=1000,
        log_period_s=1,
    ).start()
    rec = np.dtype([("id", "u1"), ("ts", "<i8"), ("v", "<f4")])
    arr = np.zeros(batch, dtype=rec)
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(b.unix_path)
    s.sendall(
        encode_hello("bench")
        + b"".join(encode_register(i, ValueType.FLOAT32, n) for i, n in enumerate(names))
    )
    head = bytes([0x03]) + varint(batch)
    frame_len = varint(len(head) + batch * rec.itemsize)
    step_ns = int(1e9 / rate_hz)
    ts0, sent = time.time_ns() - (total // topics + 1) * step_ns, 0
    while sent < total:
        k = np.arange(sent, sent + batch)
        arr["id"] = k % topics  # topics in turn across frames: every sample time unique
        step = k // topics
        arr["ts"] = ts0 + step * step_ns  # one sample per topic per period
        arr["v"] = np.where(
            arr["id"] == 0,
            47.7 + step * 1e-8,
            np.where(arr["id"] == 1, -3.35 + step * 1e-8, np.sin(step * 0.01)),
        )
        s.sendall(frame_len + head + arr.tobytes())
        sent += batch
    s.close()
    deadline = time.monotonic() + 600
    while f"samples_archived={sent} " not in b.log() and time.monotonic() < deadline:
        time.sleep(0.1)
    b.stop()
    if f"samples_archived={sent} " not in b.log():
        raise RuntimeError(f"the PubBroker did not archive all {sent} samples: {b.log()[-600:]}")
    model = tmp / "bench.modd"
    model.write_text(model_text(names, clock))
    return b.archive_dir, model


def timed(argv: list[str]) -> dict[str, Any]:
    """Wall time, CPU, peak RSS (the child's, from wait4) and notes of one command."""
    t0 = time.monotonic()
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - t0
    out = (proc.stdout.read() if proc.stdout else "") + (proc.stderr.read() if proc.stderr else "")
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{argv[:3]} failed: {out[-2000:]}")
    return {
        "seconds": round(wall, 2),
        "peak_rss_mb": round(usage.ru_maxrss / 1024, 1),
        "cpu_s": round(usage.ru_utime + usage.ru_stime, 2),
        "notes": [line for line in out.splitlines() if ": note: " in line],
    }


REFERENCE = r"""
import sys, glob, pandas as pd
csvs, out = sys.argv[1], sys.argv[2]
frames = {p: pd.read_csv(p) for p in sorted(glob.glob(csvs + "/*.csv"))}
lat = next(f for p, f in frames.items() if p.endswith("usv.gps.lat.csv")).rename(
    columns={"value": "lat"})[["log_time_ns", "lat"]]
lon = next(f for p, f in frames.items() if p.endswith("usv.gps.lon.csv")).rename(
    columns={"value": "lon"})[["log_time_ns", "lon"]]
samples = pd.concat(frames.values(), ignore_index=True).sort_values("log_time_ns")
samples = pd.merge_asof(samples, lat, on="log_time_ns", direction="nearest")
samples = pd.merge_asof(samples, lon, on="log_time_ns", direction="nearest")
samples.to_parquet(out)
print(len(samples))
"""


def reference_csvs(archive: Path, out: Path) -> float:
    """The workbench's per-topic CSV export (backend archive_work.csv_text), timed."""
    from modd_backend.archive_work import csv_text
    from modd_backend.archives import file_info

    out.mkdir()
    t0 = time.monotonic()
    for path in sorted(archive.glob("*.mcap")):
        for topic in file_info(path).topics:
            with (out / f"{path.stem}-{topic}.csv").open("a") as f:
                f.write(csv_text(path, topic, None, None))
    return time.monotonic() - t0


def qc_metadata(tmp: Path, topics: int) -> Path:
    """A metadata file (JSON) with the four QARTOD tests on every ``usv.ins`` topic."""
    tests = {
        "gross_range_test": {"fail_span": [-1.5, 1.5], "suspect_span": [-1, 1]},
        "spike_test": {"suspect_threshold": 0.5, "fail_threshold": 1},
        "rate_of_change_test": {"threshold": 50},
        "flat_line_test": {"suspect_threshold": 60, "fail_threshold": 120, "tolerance": 1e-6},
    }
    path = tmp / "dataset.json"
    path.write_text(json.dumps({"qc": {f"usv.ins.t{i}": tests for i in range(topics - 2)}}))
    return path


def export_run(
    archive: Path, model: Path, fmt: str, out: Path, more: list[str], samples: int
) -> dict[str, Any]:
    """One ``modd dataset`` export, timed, with its rates and whether any QC test was
    left unevaluated (the export's notes say which, and why)."""
    argv = [str(BIN / "modd"), "dataset", str(archive), "--model", str(model)]
    r = timed([*argv, "--format", fmt, "-o", str(out), "--no-progress", *more])
    r["samples_per_s"] = round(samples / r["seconds"])
    r["samples_per_cpu_s"] = round(samples / max(r["cpu_s"], 1e-3))
    r["qc_not_evaluated"] = [n for n in r.pop("notes") if "not evaluated" in n]
    out.unlink()
    return r


def median_of(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The median run (by wall time) with every run's wall and CPU seconds."""
    order = sorted(runs, key=lambda r: r["seconds"])
    mid = dict(order[(len(order) - 1) // 2])
    mid["runs"] = [{"seconds": r["seconds"], "cpu_s": r["cpu_s"]} for r in runs]
    mid["median_cpu_s"] = float(np.median([r["cpu_s"] for r in runs]))
    mid["load_average"] = [r["load_average"] for r in runs]
    return mid


def report(fmt: str, r: dict[str, Any], label: str) -> None:
    walls = ", ".join(f"{x['seconds']}" for x in r["runs"])
    cpus = ", ".join(f"{x['cpu_s']}" for x in r["runs"])
    print(
        f"modd dataset --format {fmt}{label}: median "
        f"{r['seconds']} s [{walls}], {r['samples_per_s']:,} samples/s (target >= "
        f"1,000,000); CPU median {r['median_cpu_s']} s [{cpus}]; peak RSS "
        f"{r['peak_rss_mb']} MB (target <= 500); load average {r['load_average']}"
    )
    for note in r["qc_not_evaluated"]:
        print(f"  QC test not evaluated: {note}")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=10_000_000)
    p.add_argument("--topics", type=int, default=20)
    p.add_argument("--no-reference", action="store_true", help="skip the pandas reference")
    p.add_argument("--json", type=Path)
    p.add_argument("--qc", action="store_true", help="QARTOD flags on every topic")
    p.add_argument("--rate", type=float, default=1000.0, help="samples per second per topic")
    p.add_argument(
        "--time",
        choices=("instrument", "receive"),
        default="instrument",
        help="the export's time axis: the instruments' sample times (default; the model's "
        "sensors declare clock = instrument) or the PubBroker's receive time (one per frame)",
    )
    p.add_argument("--repeat", type=int, default=1, help="exports per format, alternating")
    args = p.parse_args()
    results: dict[str, Any] = {"samples": args.samples, "topics": args.topics}
    with tempfile.TemporaryDirectory(prefix="modd-bench-dataset-") as d:
        tmp = Path(d)
        t0 = time.monotonic()
        (tmp / "broker").mkdir()
        archive, model = write_archive(
            tmp / "broker", args.samples, args.topics, args.rate, clock=args.time
        )
        size = sum(f.stat().st_size for f in archive.glob("*.mcap"))
        print(
            f"archive: {args.samples:,} samples of {args.topics} topics by the PubBroker in "
            f"{time.monotonic() - t0:.1f} s, {size / 1e6:.1f} MB"
        )
        more = ["--time", args.time] if args.time == "instrument" else []
        more += ["--metadata", str(qc_metadata(tmp, args.topics))] if args.qc else []
        results |= {"qc": args.qc, "rate_hz": args.rate, "time": args.time}
        runs: dict[str, list[dict[str, Any]]] = {"netcdf": [], "parquet": []}
        for _ in range(args.repeat):
            for fmt, suffix in (("netcdf", "nc"), ("parquet", "parquet")):
                out = tmp / f"out.{suffix}"
                r = export_run(archive, model, fmt, out, more, args.samples)
                r["load_average"] = round(os.getloadavg()[0], 1)
                runs[fmt].append(r)
        for fmt, rs in runs.items():
            results[fmt] = median_of(rs)
            report(
                fmt,
                results[fmt],
                (" --time instrument" if more[:1] == ["--time"] else "")
                + (" --metadata qc.json" if args.qc else ""),
            )
        if not args.no_reference:
            results["reference"] = run_reference(archive, tmp, args.samples)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1))
    return 0


def run_reference(archive: Path, tmp: Path, samples: int) -> dict[str, Any]:
    export_s = reference_csvs(archive, tmp / "csv")
    r = timed([sys.executable, "-c", REFERENCE, str(tmp / "csv"), str(tmp / "ref.parquet")])
    r.pop("notes")
    r["samples_per_s"] = round(samples / r["seconds"])
    r["csv_export_seconds"] = round(export_s, 1)
    print(
        f"reference (pandas read_csv + merge_asof, then parquet): {r['seconds']} s, "
        f"{r['samples_per_s']:,} samples/s, peak RSS {r['peak_rss_mb']} MB; its input, "
        f"the workbench's per-topic CSV export, took {export_s:.1f} s more"
    )
    return r


if __name__ == "__main__":
    raise SystemExit(main())

"""The serial soak (issue 38): scenario 1 over serial through modd-radio at 10 %
loss each way for ``--seconds``, the real PubBroker and SubBroker, the load
generator as the instruments' reader; the resident memory (VmRSS) of every
process of the chain sampled every ``--every`` seconds. After the load:
`modd backfill --gaps` for every subscriber, then `--gaps` again and
`--from 0 --to <end>` (both must find 0 windows). Checks (exit 1 when one fails):

- every window of every subscriber, derived ones included, from its first to the
  run's end, delivered live or by backfill, once, each equal to the aggregate
  recomputed from the on-board archive read with the official `mcap` reader (a
  0.25 s window may be missing only when the archive holds no sample in it);
- archive = samples in: the samples the load sent, per topic, are the archive's;
- memory flat over the last half of the load: for each process the least-squares
  line through its RSS samples of that half rises by at most 1 MiB + 2 % of its
  value at the half's start (FLAT_MIB, FLAT_FRACTION).

    .venv/bin/python tests/bench/soak_serial.py --seconds 3600   # make bench SOAK=1
    .venv/bin/python tests/bench/soak_serial.py --seconds 60     # test_soak_short.py
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "subbroker"))

from modd.ports import free_port  # noqa: E402
from modd.subbroker.payload import DeliveredValue  # noqa: E402
from modd.zenoh_session import client_settings, open_session, wait_connected  # noqa: E402
from radio_harness import (  # noqa: E402
    radio_counts,
    start_backfills,
    start_pubbroker_dgram,
    start_radio_serial,
    subbroker_dgram_config,
)
from soak import rss_kib  # noqa: E402
from subbroker_harness import (  # noqa: E402
    Proc,
    check_against_archive,
    load_counts,
    model_copy,
    processes,
    read_archive,
    shared_credentials,
    start_load,
    start_subbroker,
    wait_port,
    window_samples,
)

RADIO_SPEC = "loss=0.1,latency_ms=30,jitter_ms=10,seed=38"
FLAT_MIB, FLAT_FRACTION = 1.0, 0.02
Rss = dict[str, list[tuple[float, int]]]
SUBS = {f"sub_{i}": (2_000_000_000 if i in (1, 2) else 250_000_000) for i in range(1, 8)}


class Collector:
    """Every value under modd/usv/sub/*, per subscriber (zenoh's callback thread)."""

    def __init__(self) -> None:
        self.values: dict[str, list[DeliveredValue]] = {}

    def on_sample(self, sample: Any) -> None:
        v = DeliveredValue.from_json(sample.payload.to_bytes())
        self.values.setdefault(v.subscriber, []).append(v)


def backfill_all(zport: int, *span: str) -> dict[str, dict[str, Any]]:
    """`modd backfill` for every subscriber (one CLI each, at once): its --json figures."""
    out: dict[str, dict[str, Any]] = {}
    for sub, p in start_backfills(zport, SUBS, *span).items():
        stdout, stderr = p.communicate(timeout=300)
        if p.returncode != 0:
            raise RuntimeError(f"backfill {sub} {span}: {stderr[-2000:]}")
        out[sub] = json.loads(stdout.strip().splitlines()[-1])
    return out


def sample_loop(procs: dict[str, Proc], load: Proc, every: float, log: Any) -> Rss:
    """RSS of every process every ``every`` s while the load runs: name -> [(s, KiB)]."""
    t0 = time.monotonic()
    rss: Rss = {name: [] for name in procs}
    next_at = t0
    while load.alive():
        now = time.monotonic()
        if now >= next_at:
            for name, proc in procs.items():
                kib = rss_kib(proc.pid)
                if kib is not None and proc.alive():
                    rss[name].append((now - t0, kib))
            row = " ".join(f"{n}={v[-1][1] / 1024:.1f}" for n, v in rss.items() if v)
            print(f"{now - t0:7.0f} s  RSS MiB {row}", file=log, flush=True)
            next_at += every
        time.sleep(0.2)
    return rss


def slope_growth(samples: list[tuple[float, int]]) -> float:
    """KiB the least-squares line through ``samples`` rises over their span."""
    n = len(samples)
    mt = sum(t for t, _ in samples) / n
    mv = sum(v for _, v in samples) / n
    var = sum((t - mt) ** 2 for t, _ in samples)
    if var == 0:
        return 0.0
    slope = sum((t - mt) * (v - mv) for t, v in samples) / var
    return slope * (samples[-1][0] - samples[0][0])


def check_memory(rss: Rss, seconds: float) -> tuple[list[tuple[Any, ...]], list[str]]:
    rows: list[tuple[Any, ...]] = []
    failed: list[str] = []
    for name, samples in rss.items():
        last = [s for s in samples if s[0] >= seconds / 2]
        if len(samples) < 4 or len(last) < 3:
            failed.append(f"{name}: too few RSS samples ({len(samples)})")
            continue
        grew = slope_growth(last)
        bound = FLAT_MIB * 1024 + FLAT_FRACTION * last[0][1]
        rows.append(
            (name, samples[0][1], last[0][1], samples[-1][1], max(v for _, v in samples), grew)
        )
        if grew > bound:
            failed.append(
                f"{name}: RSS rose {grew / 1024:.2f} MiB over the last half "
                f"(bound {bound / 1024:.2f})"
            )
    return rows, failed


def check_windows(
    values: dict[str, list[DeliveredValue]], archive: Any, until_ns: int
) -> tuple[dict[str, dict[str, int]], list[str]]:
    """Per subscriber (live, backfilled); failures: duplicates, holes, values off the archive."""
    figures: dict[str, dict[str, int]] = {}
    failed: list[str] = []
    for sub, period in SUBS.items():
        mine = [v for v in values.get(sub, []) if v.end_ns <= until_ns]
        if not mine:
            failed.append(f"{sub}: nothing delivered")
            continue
        ends = sorted(v.end_ns for v in mine)
        if len(ends) != len(set(ends)):
            failed.append(f"{sub}: {len(ends) - len(set(ends))} windows delivered twice")
        missing = set(range(ends[0], until_ns + 1, period)) - set(ends)
        full = [e for e in missing if window_samples(archive.get(mine[0].topic, []), e - period, e)]
        if full or (period > 10**9 and missing):
            failed.append(
                f"{sub}: {len(missing)} windows never delivered ({len(full)} with samples)"
            )
        try:
            check_against_archive({sub: mine}, archive)
        except AssertionError as e:
            failed.append(f"{sub}: a window differs from the archive: {str(e)[:300]}")
        back = sum(v.backfilled for v in mine)
        figures[sub] = {"live": len(mine) - back, "backfilled": back, "empty_slots": len(missing)}
    return figures, failed


def check_samples(sent: dict[str, int], archive: Any) -> tuple[int, int, list[str]]:
    have = {t: len(s) for t, s in archive.items()}
    failed = [
        f"{t}: sent {n}, archived {have.get(t, 0)}" for t, n in sent.items() if have.get(t, 0) != n
    ]
    return sum(sent.values()), sum(have.values()), failed


def run(tmp: Path, seconds: float, every: float, log: Any, rotate_s: int) -> dict[str, Any]:
    model = model_copy(tmp, "scenario1.modd")
    zport, ingress = free_port(), free_port()
    radio, base, drone = start_radio_serial(tmp, RADIO_SPEC)
    link = {"transport": "serial", "device": drone, "port": 1}
    pb = start_pubbroker_dgram(tmp, model, link, ingress, archive_opts={"rotate_s": rotate_s})
    sb = start_subbroker(
        tmp, subbroker_dgram_config(tmp, model, "127.0.0.1:1", zport, "serial", device=base)
    )
    out: dict[str, Any] = {}
    with processes(radio, pb, sb):
        wait_port(zport, 60)
        cred = shared_credentials().cred_file("backend")
        session: Any = open_session(client_settings(f"tcp/127.0.0.1:{zport}", cred))
        try:
            assert wait_connected(session)
            got = Collector()
            session.declare_subscriber("modd/usv/sub/*", got.on_sample)
            if not sb.wait_log("running", 60):
                raise RuntimeError(sb.log()[-2000:])
            load = start_load(tmp, model, ingress, seconds)
            with processes(load):
                procs = {"pubbroker": pb, "subbroker": sb, "radio": radio, "load": load}
                out["rss"] = sample_loop(procs, load, every, log)
                load.p.wait(30)
                out["sent"] = load_counts(load)
            time.sleep(6.0)  # the last NACKs answered or given up
            until_ns = time.time_ns() - 3_000_000_000
            out["gaps"] = backfill_all(zport, "--gaps")
            time.sleep(2.0)  # the backfilled values reach the subscriber
            out["gaps_again"] = backfill_all(zport, "--gaps")
            out["span_again"] = backfill_all(zport, "--from", "0", "--to", str(until_ns / 1e9))
            time.sleep(1.0)
            out["values"] = {k: list(v) for k, v in got.values.items()}
            out["until_ns"] = until_ns
            out["radio"] = radio_counts(radio)
        finally:
            session.close()
    out["archive"] = read_archive(tmp / "archive", model)
    return out


def report(out: dict[str, Any], seconds: float) -> list[str]:
    figures, failed = check_windows(out["values"], out["archive"], out["until_ns"])
    sent, archived, f2 = check_samples(out["sent"], out["archive"])
    rows, f3 = check_memory(out["rss"], seconds)
    failed += f2 + f3
    for name in ("gaps_again", "span_again"):
        left = {s: r["windows"] for s, r in out[name].items() if r["windows"]}
        if left:
            failed.append(f"backfill {name}: windows still to fill {left}")
    print(f"radio: {RADIO_SPEC}; {out['radio']}")
    print(f"samples: sent {sent}, archived {archived} (the official mcap reader)")
    print("subscriber   live  backfilled  empty 0.25 s slots  (--gaps filled)")
    for sub, f in figures.items():
        print(
            f"{sub:10} {f['live']:6} {f['backfilled']:11} {f['empty_slots']:19}  "
            f"({out['gaps'][sub]['windows']})"
        )
    print(
        f"--gaps again: {sum(r['windows'] for r in out['gaps_again'].values())} windows; "
        f"--from/--to again: {sum(r['windows'] for r in out['span_again'].values())}"
    )
    print(
        f"RSS MiB ({len(out['rss']['subbroker'])} samples of each; flat: line over the last half "
        f"rises <= {FLAT_MIB:g} MiB + {FLAT_FRACTION:.0%})"
    )
    print("process      first  half  last   max   last-half rise")
    for name, first, half, last, peak, grew in rows:
        print(
            f"{name:10} {first / 1024:6.1f} {half / 1024:5.1f} {last / 1024:5.1f} "
            f"{peak / 1024:5.1f}   {grew / 1024:+.2f}"
        )
    return failed


def main() -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--seconds", type=float, default=3600.0)
    p.add_argument("--every", type=float, default=5.0, help="RSS sampling period (s)")
    p.add_argument("--keep", type=Path, help="keep the run's files (logs, archive) here")
    p.add_argument(
        "--rotate-s",
        type=int,
        default=3600,
        help="the PubBroker's archive.rotate_s (default 3600, its own): the open file's "
        "summary (an MCAP chunk index per chunk) is held in memory until the file rotates",
    )
    args = p.parse_args()
    print(
        f"soak_serial: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}, "
        f"{time.strftime('%Y-%m-%dT%H:%MZ', time.gmtime())}, {args.seconds:g} s, "
        f"PubBroker archive.rotate_s {args.rotate_s}",
        flush=True,
    )
    with tempfile.TemporaryDirectory(prefix="modd-soak-serial-") as d:
        tmp = args.keep or Path(d)
        tmp.mkdir(parents=True, exist_ok=True)
        started = time.monotonic()
        out = run(tmp, args.seconds, args.every, sys.stdout, args.rotate_s)
        failed = report(out, args.seconds)
        print(f"done in {time.monotonic() - started:.0f} s, load {os.getloadavg()[0]:.1f}")
    for f in failed:
        print(f"FAILED: {f}")
    print("all checks held" if not failed else f"{len(failed)} checks failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

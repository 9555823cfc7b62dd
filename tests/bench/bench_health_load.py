"""Issue 41's load benchmark: ``GET /api/health`` of a real ``modd-backend``
under 50 editors (each reads its project's head, saves on it and waits
``--think`` s), 10 stream WebSocket viewers (each watching a project, so
every save reaches one), 4 CSV exporters of an archive, for ``--seconds``
(180), on SQLite and on a local PostgreSQL server. Beside it a bare
FastAPI/uvicorn app (benchkit/bare_app.py) answering the same health JSON,
pinned with the backend to the same cores (``--cores``, all by default), is
probed the same way at the same time: the machine's own floor under that
load. Each probe is a process of its own (the load's 64 client threads would
otherwise delay it in this process), polling every 10 ms.

Prints, per run, p50/p95/p99/max of both probes and the saves: acknowledged,
and lost (an acknowledged revision missing from the project's history, or a
final model that is not the last acknowledged save). Several ``--runs`` give
the median of each figure. Asserts nothing.

    .venv/bin/python tests/bench/bench_health_load.py [--seconds 180] [--runs 1]
        [--database sqlite|postgres|both] [--cores 0-1] [--store-processes N]

``--store-processes`` is the backend's (``$MODD_STORE_PROCESSES``; its
default 2; 0: the store work in the backend's own threads, as before).

Target (issue 41): health p99 <= 50 ms on SQLite and PostgreSQL, 0 lost saves.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx2 as httpx
from bench_health_csv import stop_backend, write_archive
from bench_health_editing import DEMO, Load, pct, start, wait_login
from benchkit.postgres import local_postgres
from modd.ports import free_port

HERE = Path(__file__).resolve().parent


class Saving(Load):
    """The editors of bench_health_editing, keeping every acknowledged save."""

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.acked: dict[int, list[tuple[int, int]]] = {}

    def editor(self, pid: int) -> None:
        url = f"{self.base}/api/projects/{pid}/model"
        acked = self.acked.setdefault(pid, [])
        with httpx.Client(timeout=120, headers=self.admin) as c:
            i = 0
            while not self.stop.is_set():
                head = c.get(url).json()
                link = dict(head["model"].get("link") or {}, maxBuffer=1000 + i)
                t0 = time.perf_counter()
                body = {"model": dict(head["model"], link=link), "base_revision": head["revision"]}
                r = c.put(url, json=body)
                took = (time.perf_counter() - t0) * 1e3
                self.count(f"save {r.status_code}")
                if r.status_code == 200:
                    acked.append((r.json()["revision"], 1000 + i))
                    with self.lock:
                        self.saves.append(took)
                i += 1
                self.stop.wait(self.think_s)


def lost_saves(base: str, admin: dict[str, str], acked: dict[int, list[tuple[int, int]]]) -> int:
    """Acknowledged saves the store does not hold (an independent read-back)."""
    lost = 0
    with httpx.Client(timeout=120, headers=admin) as c:
        for pid, saves in acked.items():
            have = {v["revision"] for v in c.get(f"{base}/api/projects/{pid}/versions").json()}
            lost += sum(1 for rev, _ in saves if rev not in have)
            if saves:
                rev, buf = saves[-1]
                head = c.get(f"{base}/api/projects/{pid}/model").json()
                lost += head["revision"] != rev or head["model"]["link"]["maxBuffer"] != buf
    return lost


def probe(url: str, seconds: float, out: Path) -> subprocess.Popen[bytes]:
    """A process polling ``url`` every 10 ms for ``seconds``; latencies (ms) to ``out``."""
    code = (
        "import json,sys,time,httpx2 as h\n"
        "u,s,o=sys.argv[1],float(sys.argv[2]),sys.argv[3];lat=[];end=time.monotonic()+s\n"
        "with h.Client(timeout=60) as c:\n"
        "  while time.monotonic()<end:\n"
        "    t=time.perf_counter();c.get(u);lat.append((time.perf_counter()-t)*1e3)\n"
        "    time.sleep(0.01)\n"
        "open(o,'w').write(json.dumps(lat))\n"
    )
    return subprocess.Popen([sys.executable, "-c", code, url, str(seconds), str(out)])


def pinned(cores: str | None, cmd: list[str], **kw: Any) -> subprocess.Popen[bytes]:
    return subprocess.Popen(["taskset", "-c", cores, *cmd] if cores else cmd, **kw)


def start_bare(cores: str | None, port: int) -> subprocess.Popen[bytes]:
    cmd = [sys.executable, "-m", "uvicorn", "benchkit.bare_app:app", "--port", str(port)]
    return pinned(
        cores,
        [*cmd, "--log-level", "warning", "--no-access-log"],
        cwd=HERE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def wait_up(url: str) -> None:
    deadline = time.monotonic() + 60
    while True:
        try:
            httpx.get(url, timeout=5)
            return
        except httpx.TransportError:
            assert time.monotonic() < deadline, f"{url} does not answer"
            time.sleep(0.2)


def figures(lat: list[float]) -> dict[str, float]:
    return {
        "n": len(lat),
        "p50": pct(lat, 50),
        "p95": pct(lat, 95),
        "p99": pct(lat, 99),
        "max": max(lat, default=float("nan")),
    }


def one_run(a: argparse.Namespace, tmp: Path, database_url: str | None) -> dict[str, Any]:
    port, bare_port = free_port(), free_port()
    base = f"http://127.0.0.1:{port}"
    write_archive(tmp / "archives" / "usv" / "run-0000.mcap", a.samples)
    proc = start(tmp, port, database_url, a.cores)
    bare = start_bare(a.cores, bare_port)
    try:
        admin = wait_login(base, proc)
        wait_up(f"http://127.0.0.1:{bare_port}/api/health")
        text = DEMO.read_text()
        pids = [
            httpx.post(
                f"{base}/api/projects",
                headers=admin,
                timeout=60,
                json={"name": f"p{i}-{port}", "model": {"text": text}},  # runs share PostgreSQL
            ).json()["id"]
            for i in range(a.editors)
        ]
        load = Saving(base, admin, a.think)
        token = admin["Authorization"][7:]
        threads = load.start(port, token, pids, a.viewers, a.exporters)
        outs = [tmp / "health.json", tmp / "bare.json"]
        probes = [
            probe(f"{base}/api/health", a.seconds, outs[0]),
            probe(f"http://127.0.0.1:{bare_port}/api/health", a.seconds, outs[1]),
        ]
        for p in probes:
            p.wait()
        load.stop.set()
        for t in threads:
            t.join(180)
        lost = lost_saves(base, admin, load.acked)
        backend, floor = (json.loads(o.read_text()) for o in outs)
        return {
            "health": figures(backend),
            "bare": figures(floor),
            "saves": len(load.saves),
            "save_p99": pct(load.saves, 99),
            "lost": lost,
            "answers": dict(sorted(load.answers.items())),
        }
    finally:
        stop_backend(proc)
        stop_backend(bare)


def ratio(health: dict[str, float], bare: dict[str, float]) -> str:
    """The backend's p50/p99 over the bare app's: the load's cost beyond the machine's."""
    return (
        f"  backend / bare app: p50 {health['p50'] / bare['p50']:.1f}x, "
        f"p99 {health['p99'] / bare['p99']:.1f}x"
    )


def row(name: str, f: dict[str, float]) -> str:
    return (
        f"  {name:<8} {f['n']:>6.0f} probes  p50 {f['p50']:6.1f}  p95 {f['p95']:6.1f}  "
        f"p99 {f['p99']:6.1f}  max {f['max']:7.1f} ms"
    )


def median_of(runs: list[dict[str, Any]], key: str) -> dict[str, float]:
    return {k: statistics.median(r[key][k] for r in runs) for k in runs[0][key]}


def measure(a: argparse.Namespace, db: str, url: str | None) -> None:
    runs = []
    for i in range(a.runs):
        with tempfile.TemporaryDirectory() as tmpdir:
            load_avg = os.getloadavg()[0]
            r = one_run(a, Path(tmpdir), url)
            runs.append(r)
        print(f"{db} run {i + 1}/{a.runs} (load average {load_avg:.1f} at its start):")
        print(row("backend", r["health"]))
        print(row("bare app", r["bare"]))
        print(ratio(r["health"], r["bare"]))
        print(
            f"  saves {r['saves']} acknowledged (p99 {r['save_p99']:.0f} ms), "
            f"{r['lost']} lost; answers {r['answers']}",
            flush=True,
        )
    if a.runs > 1:
        print(f"{db}, median of {a.runs} runs:")
        print(row("backend", median_of(runs, "health")))
        print(row("bare app", median_of(runs, "bare")))
        print(ratio(median_of(runs, "health"), median_of(runs, "bare")))
        print(f"  lost saves in all runs: {sum(r['lost'] for r in runs)}", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--editors", type=int, default=50)
    ap.add_argument("--viewers", type=int, default=10)
    ap.add_argument("--exporters", type=int, default=4)
    ap.add_argument("--seconds", type=float, default=180.0)
    ap.add_argument("--think", type=float, default=1.0, help="seconds between an editor's saves")
    ap.add_argument("--samples", type=int, default=200_000, help="archive samples")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--database", choices=("sqlite", "postgres", "both"), default="both")
    ap.add_argument("--cores", help="taskset list for the backend and the bare app (all)")
    ap.add_argument(
        "--store-processes", type=int, help="the backend's store processes (its default: 2)"
    )
    a = ap.parse_args()
    if a.store_processes is not None:
        os.environ["MODD_STORE_PROCESSES"] = str(a.store_processes)
    print(
        f"{a.editors} editors (a save every {a.think:g} s + its answer), {a.viewers} viewers, "
        f"{a.exporters} CSV exporters, {a.seconds:g} s; {os.cpu_count()} cores, "
        f"backend and bare app on cores {a.cores or 'all'}, "
        f"store processes {os.environ.get('MODD_STORE_PROCESSES', '2 (default)')}"
    )
    if a.database in ("sqlite", "both"):
        measure(a, "SQLite", None)
    if a.database in ("postgres", "both"):
        with local_postgres() as url:
            measure(a, "PostgreSQL", url)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

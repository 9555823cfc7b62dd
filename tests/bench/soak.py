"""The soak: the whole chain (publishers -> PubBroker -> link -> SubBroker ->
zenoh -> backend) running scenario 1 for a while, with faults on a schedule,
then the reconciliation checks of issue 23. Real processes on loopback only.

Faults, at fixed fractions of the run: a link cut (3 s, through a proxy that
drops everything), kill -9 of the SubBroker, a backend killed (kill -9) in the
middle of a deploy (held by stopping the PubBroker), a lying publisher (a
sample stamped in 2107), a flooding publisher (as fast as it can), kill -9 of
the PubBroker (its open file recovered at the restart), a link stall (the
proxy forwards nothing for 2 s), kill -9 of the backend.

Checks at the end (exit 1 when one fails):
- the last PubBroker run's counters reconcile: samples_in = archived +
  archive_failed + every rejected_* counter, nothing pending;
- so do EVERY run's, those ended by kill -9 included, from the counters each run keeps
  beside its files, against what its files hold (check_runs);
- every archive file is read completely by two MCAP readers: the Python
  ``mcap`` package and the TypeScript ``@mcap/core`` (node), with the same counts;
- no deploy record is pending, and the drone runs what the last acked record says;
- memory is flat: the last PubBroker's and SubBroker's RSS at the end within
  25 % (+ 4 MiB) of their RSS a quarter into their run.

    .venv/bin/python tests/bench/soak.py --seconds 1800     # make bench SOAK=1
    .venv/bin/python tests/bench/soak.py --seconds 75       # tests/bench/test_soak_short.py
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx2 as httpx
from mcap.reader import make_reader

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "subbroker"))
from subbroker_harness import (  # noqa: E402
    Blackhole,
    Proc,
    free_port,
    model_copy,
    shared_credentials,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

PASSWORD = "soak-admin-password"
NODE_MODULES = REPO / "frontend" / "node_modules"
MCAP_COUNT = REPO / "tests" / "ecosystem" / "mcap_count.cjs"


def varint(v: int) -> bytes:
    out = bytearray()
    while True:
        b, v = v & 0x7F, v >> 7
        out.append(b | 0x80 if v else b)
        if not v:
            return bytes(out)


def frame(mtype: int, body: bytes) -> bytes:
    return varint(len(body) + 1) + bytes([mtype]) + body


def raw_publisher(
    port: int, name: str, topic: str, stamp: Callable[[], int], seconds: float, batch: int
) -> int:
    """Samples of one float32 topic, ``batch`` per frame, for ``seconds``; the
    number sent. Replies are read and discarded so that the socket never stalls."""
    data = name.encode()
    sent = 0
    with socket.create_connection(("127.0.0.1", port)) as s:
        s.setblocking(True)
        s.sendall(frame(0x01, bytes([1]) + varint(len(data)) + data))
        t = topic.encode()
        s.sendall(frame(0x02, varint(0) + bytes([0]) + varint(len(t)) + t))
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            records = b"".join(
                varint(0) + struct.pack("<q", stamp()) + struct.pack("<f", 1.5)
                for _ in range(batch)
            )
            try:
                s.sendall(frame(0x03, varint(batch) + records))
            except OSError:
                break
            sent += batch
            s.setblocking(False)
            try:
                while s.recv(65536):
                    pass
            except (BlockingIOError, OSError):
                pass
            s.setblocking(True)
    return sent


class Backend:
    def __init__(self, tmp: Path, zenoh: str) -> None:
        cred = shared_credentials()
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.cmd = [
            str(Path(sys.executable).with_name("modd-backend")),
            "--port",
            str(self.port),
            "--data",
            str(tmp / "backend"),
            "--zenoh-connect",
            zenoh,
            "--zenoh-credentials",
            str(cred.cred_file("backend")),
            "--deploy-key",
            str(cred.deploy_key_file),
            "--deploy-timeout",
            "3",
            "--scene-port",
            "-1",
            "--foxglove-port",
            "0",
            "--frontend",
            str(tmp / "none"),
        ]
        self.log = tmp / "backend.log"
        self.proc: subprocess.Popen[bytes] | None = None
        self.headers: dict[str, str] = {}

    def start(self) -> None:
        with self.log.open("ab") as out:
            self.proc = subprocess.Popen(
                self.cmd,
                stdout=out,
                stderr=subprocess.STDOUT,
                env={**os.environ, "MODD_ADMIN_PASSWORD": PASSWORD},
            )
        deadline = time.monotonic() + 90
        while True:
            try:
                r = httpx.post(
                    self.url + "/api/auth/login",
                    timeout=10,
                    json={"username": "admin", "password": PASSWORD},
                )
                break
            except httpx.TransportError:
                if time.monotonic() > deadline or self.proc.poll() is not None:
                    raise RuntimeError(
                        "the backend did not start: " + self.log.read_text()
                    ) from None
                time.sleep(0.1)
        self.headers = {"Authorization": f"Bearer {r.json()['token']}"}

    def call(self, method: str, path: str, **kw: Any) -> Any:
        r = httpx.request(method, self.url + path, headers=self.headers, timeout=30, **kw)
        r.raise_for_status()
        return r.json()

    def kill9(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGKILL)
            self.proc.wait(10)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.kill9()


def mount_tmpfs(directory: Path, size_mb: int = 512) -> bool:
    """Mount a tmpfs on ``directory`` (root only; False when not possible). Recovering a
    file left open by a crash finishes it in place (a few KiB, docs/reliability.md)."""
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    r = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size_mb}m,mode=0700", "tmpfs", str(directory)],
        capture_output=True,
        check=False,
    )
    return r.returncode == 0


def rss_kib(pid: int) -> int | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        return None
    return None


class Soak:
    def __init__(self, tmp: Path, seconds: float) -> None:
        self.tmp, self.seconds = tmp, seconds
        self.link, self.ingress, self.zport = free_port(), free_port(), free_port()
        self.model = model_copy(tmp, "scenario1.modd")
        self.archive = tmp / "archive"
        self.archive.mkdir()
        self.tmpfs = mount_tmpfs(self.archive)
        self.pb_count = 0
        self.pb = self.start_pb()
        self.proxy = Blackhole(self.link)
        self.cfg = subbroker_config(
            tmp, self.model, self.proxy.port, self.zport, state_dir=tmp / "state"
        )
        self.sb = start_subbroker(tmp, self.cfg)
        wait_port(self.zport)
        if not self.sb.wait_log("running", 30):
            raise RuntimeError("SubBroker did not start: " + self.sb.log())
        self.backend = Backend(tmp, f"tcp/127.0.0.1:{self.zport}")
        self.backend.start()
        # publishers run until stopped (the schedule drifts when restarts are slow)
        self.load = start_load(tmp, self.model, self.ingress, seconds * 4 + 600)
        self.events: list[str] = []
        self.rss: dict[str, list[tuple[float, int]]] = {"pubbroker": [], "subbroker": []}
        self.started = {"pubbroker": time.monotonic(), "subbroker": time.monotonic()}
        self.t0 = time.monotonic()

    def start_pb(self) -> Proc:
        self.pb_count += 1
        return start_pubbroker(
            self.tmp, self.model, self.link, self.ingress, tag=f"pb{self.pb_count}"
        )

    def note(self, text: str) -> None:
        line = f"{time.monotonic() - self.t0:7.1f} s  {text}"
        self.events.append(line)
        print(line, flush=True)

    def sample_rss(self) -> None:
        now = time.monotonic()
        for name, proc in (("pubbroker", self.pb), ("subbroker", self.sb)):
            kib = rss_kib(proc.pid)
            if kib is not None:
                self.rss[name].append((now, kib))

    # -- faults ----------------------------------------------------------------

    def link_cut(self) -> None:
        self.note("link cut for 3 s")
        self.proxy.drop()
        time.sleep(3)
        self.proxy.restore()

    def link_stall(self) -> None:
        self.note("link stalled for 2 s (nothing forwarded, nothing closed)")
        self.proxy.dropping = True
        time.sleep(2)
        self.proxy.dropping = False

    def kill_subbroker(self) -> None:
        self.note("kill -9 SubBroker, restart")
        self.sb.kill9()
        self.sb = start_subbroker(self.tmp, self.cfg, tag=f"sb{len(self.events)}")
        self.rss["subbroker"] = []
        self.started["subbroker"] = time.monotonic()

    def disk_full(self) -> None:
        """The archive's file system filled (a small tmpfs, as root) for 5 s."""
        if not self.tmpfs:
            self.note("disk full: skipped (needs root to mount a tmpfs)")
            return
        filler = self.archive / "filler.bin"
        chunk = b"\0" * (1 << 20)
        with filler.open("wb") as f:
            try:
                while True:
                    f.write(chunk)
                    f.flush()
            except OSError:
                pass
        full_at = time.monotonic()
        told = self.pb.wait_log("archive: write failed", 5)
        self.note(
            f"disk full for 5 s (the PubBroker said so: {told}, after "
            f"{time.monotonic() - full_at:.2f} s)"
        )
        time.sleep(max(0.0, 5 - (time.monotonic() - full_at)))
        with contextlib.suppress(OSError):
            filler.unlink()
        back = self.pb.wait_log("archive: writing again", 5)
        self.note(f"space back; the PubBroker writes again: {back}")

    def kill_pubbroker(self) -> None:
        self.note("kill -9 PubBroker, restart (its open file is recovered)")
        self.pb.kill9()
        self.pb = self.start_pb()
        self.rss["pubbroker"] = []
        self.started["pubbroker"] = time.monotonic()
        self.load.stop()  # its connection died with the broker: a new publisher run
        self.load = start_load(
            self.tmp,
            self.model,
            self.ingress,
            self.seconds * 4 + 600,
            tag=f"load{self.pb_count}",
            seed=self.pb_count,
        )

    def kill_backend(self) -> None:
        self.note("kill -9 backend, restart")
        self.backend.kill9()
        self.backend.start()

    def deploy_and_kill_backend(self) -> None:
        b = self.backend
        projects = b.call("GET", "/api/projects")
        model = json.loads(self.model.read_text())
        if not projects:
            pid = b.call("POST", "/api/projects", json={"name": "soak", "model": {"model": model}})[
                "id"
            ]
        else:
            pid = projects[0]["id"]
        head = b.call("GET", f"/api/projects/{pid}/model")
        nxt = copy.deepcopy(head["model"])
        nxt["subscribers"][0]["periodS"] = "4" if nxt["subscribers"][0]["periodS"] != "4" else "2"
        rev = b.call(
            "PUT",
            f"/api/projects/{pid}/model",
            json={"base_revision": head["revision"], "model": nxt},
        )["revision"]
        self.note(f"deploy of revision {rev}, backend killed (kill -9) in the middle")
        os.kill(self.pb.pid, signal.SIGSTOP)
        try:
            threading.Thread(target=self._post, args=(pid, rev), daemon=True).start()
            self.sb.wait_log(f"deploy of revision {rev} signed", 10)
            b.kill9()
        finally:
            os.kill(self.pb.pid, signal.SIGCONT)
        b.start()

    def _post(self, pid: int, rev: int) -> None:
        with contextlib.suppress(httpx.HTTPError, OSError):
            self.backend.call("POST", f"/api/projects/{pid}/deployments", json={"revision": rev})

    def lying_publisher(self) -> None:
        far = 4_350_000_000 * 10**9  # year 2107
        first = [True]

        def stamp() -> int:
            if first[0]:
                first[0] = False
                return far
            return time.time_ns()

        sent = raw_publisher(self.ingress, "liar", "usv.accelerometer.accel_x", stamp, 1.0, 1)
        self.note(f"lying publisher: one sample stamped in 2107, then {sent - 1} normal ones")

    def flooding_publisher(self) -> None:
        sent = raw_publisher(
            self.ingress, "flood", "usv.accelerometer.accel_y", time.time_ns, 3.0, 500
        )
        self.note(f"flooding publisher: {sent} samples in 3 s")

    # -- run ---------------------------------------------------------------------

    def run(self) -> None:
        schedule: list[tuple[float, Callable[[], None]]] = [
            (0.10, self.link_cut),
            (0.20, self.kill_subbroker),
            (0.30, self.deploy_and_kill_backend),
            (0.42, self.lying_publisher),
            (0.50, self.flooding_publisher),
            (0.55, self.disk_full),
            (0.60, self.kill_pubbroker),
            (0.72, self.link_stall),
            (0.80, self.kill_backend),
        ]
        for at, fault in schedule:
            while time.monotonic() - self.t0 < at * self.seconds:
                self.sample_rss()
                time.sleep(min(2.0, max(0.05, at * self.seconds - (time.monotonic() - self.t0))))
            fault()
        while time.monotonic() - self.t0 < self.seconds:
            self.sample_rss()
            time.sleep(min(2.0, max(0.05, self.seconds - (time.monotonic() - self.t0))))
        self.sample_rss()

    def stop(self) -> None:
        self.load.stop()
        self.backend.stop()
        self.sb.stop()
        self.pb.stop()
        self.proxy.close()


def check(soak: Soak) -> list[str]:
    """The failed checks (empty: all held); prints every figure."""
    failed: list[str] = []
    tmp = soak.tmp
    # 1. counters of the last PubBroker run
    line = [ln for ln in soak.pb.log().splitlines() if "stopped:" in ln]
    if not line:
        failed.append("the last PubBroker did not log its final counters")
    else:
        c = {k: int(v) for k, v in re.findall(r"(\w+)=(\d+)", line[-1])}
        refused = sum(v for k, v in c.items() if k.startswith("rejected_"))
        print(
            f"last PubBroker run: samples_in {c['samples_in']:,} = archived "
            f"{c['samples_archived']:,} + archive_failed {c['archive_failed']} + refused "
            f"{refused:,} (pending {c.get('samples_pending')})"
        )
        if (
            c["samples_in"] != c["samples_archived"] + c["archive_failed"] + refused
            or c.get("samples_pending", 0) != 0
        ):
            failed.append(f"counters do not reconcile: {c}")
    # 2. every archive file read completely by two readers
    files = sorted((tmp / "archive").glob("*.mcap"))
    py: dict[str, int] = {}
    for f in files:
        with f.open("rb") as fh:
            try:
                reader = make_reader(fh)
                if reader.get_summary() is None:
                    failed.append(f"{f.name}: no summary (not finalised)")
                py[f.name] = sum(1 for _ in reader.iter_messages())
            except Exception as exc:  # the reader's errors have no common base
                failed.append(f"{f.name}: the Python reader cannot read it: {exc}")
    node = shutil.which("node")
    ts: dict[str, int] = {}
    if node is None or not (NODE_MODULES / "@mcap" / "core").is_dir():
        failed.append("node or @mcap/core missing (scripts/setup.sh)")
    elif files:
        out = subprocess.run(
            [node, str(MCAP_COUNT), *map(str, files)],
            capture_output=True,
            text=True,
            timeout=300,
            env={**os.environ, "NODE_PATH": str(NODE_MODULES)},
        )
        if out.returncode != 0:
            failed.append(f"@mcap/core failed: {out.stderr[-500:]}")
        else:
            doc = json.loads(out.stdout.strip().splitlines()[-1])
            for path, res in doc.items() if isinstance(doc, dict) else []:
                if res.get("error") or not res.get("complete", True):
                    failed.append(f"@mcap/core: {path}: {res}")
                ts[Path(path).name] = sum(res.get("counts", {}).values())
    for name, n in py.items():
        if ts and ts.get(name) != n:
            failed.append(f"{name}: python mcap reads {n}, @mcap/core {ts.get(name)}")
    bad = [f for f in failed if "mcap" in f]
    print(
        f"archive: {len(files)} files, {sum(py.values()):,} messages, read completely by "
        f"python mcap and @mcap/core: {'yes' if not bad else 'NO'}"
    )
    failed += check_runs(tmp / "archive", py)
    return failed


def check_runs(archive: Path, read: dict[str, int]) -> list[str]:
    """The counters of EVERY PubBroker run against the archive, the runs ended by kill -9
    included: each run keeps its counters beside its files (``*.counters.json``, replaced at
    every acknowledgement; docs/reliability.md, "Counters that reconcile"). Per run, at its
    last record: samples_in = archived + archive_failed + refused + pending, exactly; its files
    hold exactly `archived` (a clean stop, pending 0) or at least `archived` (kill -9: what it
    wrote after its last record, at most its pending then plus 2 s of its input)."""
    failed: list[str] = []
    runs = [json.loads(p.read_text()) for p in sorted(archive.glob("*.counters.json"))]
    owned: set[str] = set()
    tot = {"in": 0, "archived": 0, "failed": 0, "refused": 0, "pending": 0, "late": 0}
    for r in runs:
        c, files, name = r["counters"], r["files"], r["run"]
        refused = sum(v for k, v in c.items() if k.startswith("rejected_"))
        if c["samples_in"] != (
            c["samples_archived"] + c["archive_failed"] + refused + c["samples_pending"]
        ):
            failed.append(f"run {name}: its counters do not reconcile: {c}")
        owned |= set(files)
        missing = [f for f in files if f not in read]
        if missing:
            failed.append(f"run {name}: files it wrote are not in the archive: {missing}")
        held = sum(read.get(f, 0) for f in files)
        short = [f for f, n in files.items() if read.get(f, 0) < n]
        if short:
            failed.append(f"run {name}: files hold fewer messages than it counted: {short}")
        late = held - c["samples_archived"]
        if r["final"]:
            if late != 0 or c["samples_pending"] != 0:
                failed.append(
                    f"run {name} (stopped): its files hold {held}, it counted "
                    f"{c['samples_archived']} archived, pending {c['samples_pending']}"
                )
        else:
            seconds = max(1e-9, (r["updated_ns"] - r["started_ns"]) / 1e9)
            bound = c["samples_pending"] + int(c["samples_in"] / seconds * 2.0) + 1
            print(
                f"run {name} ended by kill -9: its last record {seconds:.1f} s into it; "
                f"{late:,} written after it (bound {bound:,}: pending {c['samples_pending']:,} "
                f"+ 2 s of input)"
            )
            if late < 0 or late > bound:
                failed.append(
                    f"run {name}: {late} messages written after its last record (bound {bound})"
                )
        tot["in"] += c["samples_in"]
        tot["archived"] += c["samples_archived"]
        tot["failed"] += c["archive_failed"]
        tot["refused"] += refused
        tot["pending"] += c["samples_pending"]
        tot["late"] += max(0, late)
    orphans = sorted(set(read) - owned)
    if orphans:
        failed.append(f"archive files no run counts: {orphans}")
    killed = sum(1 for r in runs if not r["final"])
    print(
        f"every PubBroker run ({len(runs)}, {killed} ended by kill -9): samples_in "
        f"{tot['in']:,} = archived {tot['archived']:,} + archive_failed {tot['failed']} + "
        f"refused {tot['refused']:,} + pending at a kill {tot['pending']:,}; the archive holds "
        f"{sum(read.values()):,} = {tot['archived']:,} counted + {tot['late']:,} written after "
        f"a killed run's last record"
    )
    if not runs:
        failed.append("no run kept its counters")
    elif sum(read.values()) != tot["archived"] + tot["late"]:
        failed.append("the archive holds messages no run counted")
    return failed


def check_records(soak: Soak) -> list[str]:
    failed: list[str] = []
    b = soak.backend
    deadline = time.monotonic() + 15
    while True:
        projects = b.call("GET", "/api/projects")
        rows = [d for p in projects for d in b.call("GET", f"/api/projects/{p['id']}/deployments")]
        pending = [d for d in rows if d["status"] == "pending"]
        diff = b.call("GET", f"/api/projects/{projects[0]['id']}/deployed-diff") if projects else {}
        if not pending and diff.get("source") == "drone" or time.monotonic() > deadline:
            break
        time.sleep(0.5)
    acked = sorted((d for d in rows if d["status"] == "acked"), key=lambda d: d["id"])
    reports = diff.get("drone_reports") or {}
    print(
        f"deploy records: {len(rows)} ({len(acked)} acked, {len(pending)} pending); the drone "
        f"reports revision {reports.get('revision')} ({reports.get('source')}); "
        f"the last acked record: revision {acked[-1]['revision'] if acked else None}"
    )
    if pending:
        failed.append(f"records still pending: {pending}")
    if diff.get("source") != "drone":
        failed.append("the drone does not report what it runs")
    elif acked and (diff.get("deployed") or {}).get("id") != acked[-1]["id"]:
        failed.append(f"the drone runs {reports}, the last acked record is {acked[-1]}")
    return failed


def check_memory(soak: Soak) -> list[str]:
    failed = []
    for name, all_samples in soak.rss.items():
        # a process's first seconds load its code and fill its buffers: the
        # baseline is 10 s after its start, or a quarter into its run if later
        warm = soak.started[name] + 10
        samples = [s for s in all_samples if s[0] >= warm]
        if len(samples) < 4:
            print(f"memory {name}: too short a run after warm-up to judge")
            continue
        start = samples[len(samples) // 4][1]
        end = samples[-1][1]
        print(
            f"memory {name} (last instance, {samples[-1][0] - samples[0][0]:.0f} s after "
            f"warm-up): {start / 1024:.1f} MiB -> {end / 1024:.1f} MiB at the end"
        )
        if end > start * 1.25 + 4096:
            failed.append(f"{name} memory grew from {start} KiB to {end} KiB")
    return failed


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=1800.0)
    ap.add_argument("--keep", help="copy the run directory here at the end")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="modd-soak-") as d:
        tmp = Path(d)
        soak = Soak(tmp, a.seconds)
        failed: list[str] = []
        try:
            try:
                soak.run()
                failed += check_records(soak)
            finally:
                soak.stop()
            failed += check(soak)
            failed += check_memory(soak)
            if a.keep:
                shutil.copytree(tmp, a.keep, dirs_exist_ok=True)
        finally:  # the tmpfs never outlives the run, whatever failed
            if soak.tmpfs:
                subprocess.run(["umount", str(soak.archive)], check=False)
        for f in failed:
            print(f"soak: FAILED: {f}")
        print(
            f"soak: {len(soak.events)} faults in {a.seconds:g} s; "
            f"{'all checks held' if not failed else f'{len(failed)} checks failed'}"
        )
        return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())

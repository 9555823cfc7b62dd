"""The PubBroker under bad clocks, floods, a full disk and a crash (issue 23, docs/reliability.md),
with the real binary and the archive read back by the official `mcap` reader as the oracle."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from modd.ingress import Ack, Reject, decode_reply
from modd.link import codec
from modd.link.frames import ValueType
from modd.publisher import connect, encode_hello, encode_register, encode_samples
from pubbroker_harness import (
    BIN,
    BaseStation,
    PubBroker,
    f32,
    hand_config_scenario1,
    read_archive,
    run_load,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from support.namespaces import needs_mount_namespace  # noqa: E402

X, Y, Z = (f"usv.accelerometer.accel_{a}" for a in "xyz")


def final_counters(log: str) -> dict[str, int]:
    """The counters of the broker's last line ("stopped: name=value ...")."""
    line = [ln for ln in log.splitlines() if "stopped:" in ln][-1]
    return {k: int(v) for k, v in re.findall(r"(\w+)=(\d+)", line)}


def assert_reconciled(c: dict[str, int]) -> None:
    rejected = sum(v for k, v in c.items() if k.startswith("rejected_"))
    assert c["samples_in"] == c["samples_archived"] + c["archive_failed"] + rejected, c
    assert c["samples_pending"] == 0


def count_messages(directory: Path, topic: str) -> int:
    """Messages of one topic, by the official reader through the message indexes (the flood's
    million messages are not parsed)."""
    from mcap.reader import make_reader

    n = 0
    for path in sorted(directory.glob("*.mcap")):
        with open(path, "rb") as f:
            n += sum(1 for _ in make_reader(f).iter_messages(topics=[topic]))
    return n


def replies(s: socket.socket, until: float, done: Any) -> list[Any]:
    """Broker -> publisher frames until done(list) or the deadline."""
    sp = codec.FrameSplitter()
    out: list[Any] = []
    s.settimeout(0.1)
    deadline = time.monotonic() + until
    while time.monotonic() < deadline and not done(out):
        try:
            data = s.recv(65536)
        except TimeoutError:
            continue
        if not data:
            break
        out += [decode_reply(f.type, f.body) for f in sp.feed(data)]
    return out


def test_a_far_future_sample_blocks_nothing_and_its_publisher_is_told(broker_factory: Any) -> None:
    b = broker_factory()
    s = connect(f"unix:{b.unix_path}")
    now = time.time_ns()
    bad = 4_354_000_000_000_000_000  # year 2107: microseconds taken for nanoseconds and the like
    records = [(0, bad, 1.0)] + [(0, now + i * 1_000_000, f32(0.5 * i)) for i in range(20)]
    s.sendall(
        encode_hello("liar")
        + encode_register(0, ValueType.FLOAT32, X)
        + encode_samples(records, [ValueType.FLOAT32])
    )
    got = replies(s, 5.0, lambda r: any(isinstance(x, Ack) and x.settled == 21 for x in r))
    s.close()
    rejects = [r for r in got if isinstance(r, Reject)]
    assert len(rejects) == 1 and rejects[0].count == 1
    assert rejects[0].reason_text == "timestamp out of bounds"
    assert "ahead of the broker clock" in rejects[0].detail
    ack = [r for r in got if isinstance(r, Ack)][-1]
    assert (ack.received, ack.settled, ack.archived) == (21, 21, 20)
    # The same topic from another publisher right after: nothing blocked.
    later = run_load(f"unix:{b.unix_path}", [X], 50.0, 0.5)
    assert b.stop() == 0
    archived = [a.value for a in read_archive(b.archive_dir)[X]]
    assert archived[:20] == [f32(0.5 * i) for i in range(20)]
    assert len(archived) == 20 + later.published
    c = final_counters(b.log())
    assert c["rejected_timestamp"] == 1
    assert_reconciled(c)


def test_a_flooding_publisher_loses_only_its_own_samples(broker_factory: Any) -> None:
    flood_topic = "usv.flood.value"
    b = broker_factory(
        topics=[(X, "float32"), (Y, "float32"), (Z, "float32"), (flood_topic, "float32")],
        archive={"queue_limit_samples": 40_000, "message_index": True},
    )
    stop = threading.Event()
    sent = [0]

    def flood() -> None:
        s = connect(f"unix:{b.unix_path}")
        now = time.time_ns()
        batch = encode_samples([(0, now, 1.0)] * 20_000, [ValueType.FLOAT32])
        s.sendall(encode_hello("flooder") + encode_register(0, ValueType.FLOAT32, flood_topic))
        while not stop.is_set():
            s.sendall(batch)
            sent[0] += 20_000
        s.close()

    flooder = threading.Thread(target=flood)
    flooder.start()
    time.sleep(0.3)
    results: list[Any] = [None, None]

    def calm(i: int, topics: list[str]) -> None:
        results[i] = run_load(f"unix:{b.unix_path}", topics, 200.0, 2.0)

    calms = [
        threading.Thread(target=calm, args=(0, [X, Y])),
        threading.Thread(target=calm, args=(1, [Z])),
    ]
    for t in calms:
        t.start()
    for t in calms:
        t.join()
    stop.set()
    flooder.join()
    assert b.stop() == 0
    c = final_counters(b.log())
    assert_reconciled(c)
    assert c["rejected_quota"] > 0, c  # the flood was refused ...
    for r in results:  # ... and nothing of the others was
        for topic, n in r.per_topic.items():
            got = count_messages(b.archive_dir, topic)
            assert got == n, (topic, n, got)
    assert c["rejected_overflow"] == 0


def test_a_file_left_open_by_a_crash_is_recovered_at_start(broker_factory: Any) -> None:
    from mcap.reader import make_reader

    b = broker_factory()
    run_load(f"unix:{b.unix_path}", [X, Y], 100.0, 1.0)
    time.sleep(0.5)  # flushed (every 200 ms) and acknowledged
    b.stop(signal.SIGKILL)
    files = sorted(b.archive_dir.glob("*.mcap"))
    assert len(files) == 1
    assert not files[0].read_bytes().endswith(b"\x89MCAP0\r\n")  # no footer: a crashed file
    b2 = broker_factory(archive={"dir": str(b.archive_dir)})
    assert "left open by a crash" in b2.log()
    with open(files[0], "rb") as f:  # the official reader opens it with its summary
        summary = make_reader(f).get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count >= 150
    assert b2.stop() == 0
    assert len(read_archive(b.archive_dir)[X]) >= 75
    # Each run kept its counters beside its files; the killed one's last record too.
    records = {
        r["run"].rsplit("-", 1)[1]: r
        for r in (json.loads(p.read_text()) for p in b.archive_dir.glob("usv-run-*.counters.json"))
    }
    killed, clean = records[str(b.proc.pid)], records[str(b2.proc.pid)]
    for r in (killed, clean):
        assert_reconciled_record(r["counters"])
    assert not killed["final"] and clean["final"]
    assert killed["counters"]["samples_archived"] > 0
    # the killed run's file holds at least what it counted archived (the oracle: the archive)
    [(name, counted)] = killed["files"].items()
    with open(b.archive_dir / name, "rb") as f:
        held = sum(1 for _ in make_reader(f).iter_messages())
    assert held >= counted == killed["counters"]["samples_archived"], (held, counted)
    final = final_counters(b2.log())  # the clean run's record says what its last line says
    keys = [k for k in final if k.startswith(("samples_", "rejected_", "archive_failed"))]
    assert {k: clean["counters"][k] for k in keys} == {k: final[k] for k in keys}


def assert_reconciled_record(c: dict[str, int]) -> None:
    rejected = sum(v for k, v in c.items() if k.startswith("rejected_"))
    assert c["samples_in"] == (
        c["samples_archived"] + c["archive_failed"] + rejected + c["samples_pending"]
    ), c


class NamespacedBroker(PubBroker):
    """The broker in a private mount namespace whose archive directory is a small tmpfs
    (`unshare -rm`: no privileges needed, nothing mounted outside the test); the files are
    copied out when it stops, and the test fills the tmpfs through /proc/PID/root."""

    def __init__(self, tmp: Path, size_kib: int, **overrides: Any) -> None:
        super().__init__(tmp, [(X, "float32"), (Y, "float32"), (Z, "float32")], **overrides)
        self.size_kib = size_kib
        self.copied = tmp / "copied"
        self.pid = 0
        self.prelude = ""  # shell lines run on the fresh tmpfs before the broker starts

    def start(self) -> NamespacedBroker:
        self.archive_dir.mkdir(parents=True, exist_ok=True)
        self.copied.mkdir()
        pidfile = self.tmp / "pid"
        script = (
            f"mount -t tmpfs -o size={self.size_kib}k tmpfs '{self.archive_dir}' || exit 97\n"
            f"{self.prelude}\n"
            f"'{BIN}' --config '{self.config_path}' & echo $! > '{pidfile}'\n"
            f"wait $!; rc=$?; cp -a '{self.archive_dir}/.' '{self.copied}/'; exit $rc\n"
        )
        self._log = open(self.log_path, "wb")  # noqa: SIM115 (closed in stop)
        self.proc = subprocess.Popen(
            ["unshare", "-rm", "sh", "-c", script], stdout=self._log, stderr=subprocess.STDOUT
        )
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"namespaced broker exited: {self.log()}")
            if pidfile.exists() and pidfile.read_text().strip() and os.path.exists(self.unix_path):
                self.pid = int(pidfile.read_text())
                return self
            time.sleep(0.02)
        raise RuntimeError("namespaced broker did not start")

    def inside(self, name: str) -> Path:
        return Path(f"/proc/{self.pid}/root") / str(self.archive_dir).lstrip("/") / name

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 20.0) -> int:
        if self.proc is None:
            return 0
        try:
            if self.proc.poll() is None:
                os.kill(self.pid, sig)
                self.proc.wait(timeout)
            return int(self.proc.returncode)
        finally:
            self._log.close()


@needs_mount_namespace
def test_disk_full_then_space_back(tmp_path: Path) -> None:
    full_s = float(os.environ.get("MODD_DISK_FULL_S", "5"))
    b = NamespacedBroker(tmp_path, 2048, archive={"low_space_mb": 1, "flush_interval_ms": 200})
    b.start()
    try:
        base = BaseStation(b.link_port)
        base.configure(hand_config_scenario1(status_period_s=60))  # STATUS once a minute at most
        base.start()
        stop = threading.Event()
        result: list[Any] = []
        load = threading.Thread(
            target=lambda: result.append(
                run_load(f"unix:{b.unix_path}", [X, Y, Z], 100.0, full_s + 8.0, stop=stop)
            )
        )
        load.start()
        time.sleep(1.5)
        filler = b.inside("filler")
        with open(filler, "wb") as f:  # fill the tmpfs to the last byte
            try:
                while True:
                    f.write(b"\0" * 65536)
                    f.flush()
            except OSError:
                pass
        t_full = time.monotonic()
        told = None
        while time.monotonic() - t_full < 5:
            st = base.snapshot().statuses
            if st and st[-1].get("archive_state") == 2:
                told = time.monotonic() - t_full
                break
            time.sleep(0.02)
        time.sleep(max(0.0, full_s - (time.monotonic() - t_full)))
        filler.unlink()
        t_back = time.monotonic()
        back = None
        while time.monotonic() - t_back < 10:
            st = base.snapshot().statuses
            if st and st[-1].get("archive_state") == 0:
                back = time.monotonic() - t_back
                break
            time.sleep(0.02)
        load.join()
        base.close()
        assert b.stop() == 0
    finally:
        if b.alive():
            b.stop(signal.SIGKILL)
    print(f"disk full {full_s:.0f} s: operator told after {told} s, writing again after {back} s")
    assert told is not None and told <= 2.0, b.log()
    assert back is not None
    log = b.log()
    assert log.count("archive: write failed") == 1  # one line per state change
    assert log.count("archive: writing again") == 1
    files = sorted(b.copied.glob("*.mcap"))
    assert 1 <= len(files) <= 2  # at most one new file
    archive = read_archive(b.copied)  # every file read completely by the official reader
    published = result[0].per_topic
    for t in (X, Y, Z):
        assert len(archive[t]) == published[t]  # nothing accepted was lost
    c = final_counters(log)
    assert_reconciled(c)
    assert c["archive_failed"] == 0


def wait_log(b: PubBroker, text: str, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if text in b.log():
            return True
        time.sleep(0.05)
    return False


@needs_mount_namespace
def test_a_crashed_file_is_recovered_without_room_for_a_copy_and_when_space_returns(
    tmp_path: Path, broker_factory: Any
) -> None:
    from mcap.reader import make_reader

    # small chunks: the summary's chunk indexes (~7 KiB) cannot hide in the slack of the
    # file's last page, so a full disk really refuses them
    b = broker_factory(archive={"chunk_bytes": 4096})
    run_load(f"unix:{b.unix_path}", [X, Y], 1000.0, 1.5)
    time.sleep(0.5)  # flushed and acknowledged
    b.stop(signal.SIGKILL)
    [crashed] = sorted(b.archive_dir.glob("*.mcap"))
    size = crashed.stat().st_size
    assert size > 32 * 1024 and not crashed.read_bytes().endswith(b"\x89MCAP0\r\n")

    def broker_beside(tag: str, leave_blocks: int | None) -> NamespacedBroker:
        d = tmp_path / tag
        d.mkdir()
        nb = NamespacedBroker(d, size // 1024 + 256)
        a = nb.archive_dir
        fill = (
            f"cat /dev/zero > '{a}/filler' 2>/dev/null; true"
            if leave_blocks is None
            else f"n=$(stat -f -c %a '{a}'); dd if=/dev/zero of='{a}/filler' "
            f"bs=$(stat -f -c %S '{a}') count=$((n - {leave_blocks})) 2>/dev/null"
        )
        nb.prelude = f"cp '{crashed}' '{a}/' && {fill}"
        return nb.start()

    def finished(path: Path) -> int:
        with open(path, "rb") as f:
            reader = make_reader(f)
            summary = reader.get_summary()
            assert summary is not None and summary.statistics is not None
            n = sum(1 for _ in reader.iter_messages())
        assert n == summary.statistics.message_count
        return n

    # 1. Two free blocks beside a file many times that size: finished in place at start.
    nb = broker_beside("little-room", 2)
    try:
        assert wait_log(nb, "left open by a crash", 10), nb.log()
    finally:
        assert nb.stop() == 0
    kept = finished(nb.copied / crashed.name)
    assert kept >= 2500, kept  # ~3,000 published: at most the last chunk was not written

    # 2. Not one free byte: not finished at start, finished once space returns (no restart).
    nb = broker_beside("no-room", None)
    try:
        assert wait_log(nb, "cannot recover", 10), nb.log()
        nb.inside("filler").unlink()
        assert wait_log(nb, "now that there is room", 10), nb.log()
    finally:
        assert nb.stop() == 0
    assert finished(nb.copied / crashed.name) == kept


def test_kill_9_loses_nothing_acknowledged_on_disk_and_the_publisher_replays_the_rest(
    broker_factory: Any,
) -> None:
    """A publisher's `on_disk` is the broker's promise: after kill -9 of the broker, every
    sample it counted on disk is in the archive (read by the official reader after recovery),
    and what was sent but not acknowledged is sent again to the restarted broker, so that
    every sample published ends up in the archive (at least once)."""
    from modd.publisher import Publisher

    b = broker_factory()
    pub = Publisher("pub_1", f"tcp:127.0.0.1:{b.tcp_port}", reconnect_s=0.05)
    published: dict[str, set[int]] = {X: set(), Y: set()}
    for t in published:
        pub.declare(t, "float32")

    def publish_for(seconds: float, hz: float = 500.0) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            now = time.time_ns()
            for t, seen in published.items():
                if pub.publish(t, now, 1.0):
                    seen.add(now)
            time.sleep(1 / hz)

    try:
        publish_for(1.5)
        b.stop(signal.SIGKILL)
        at_kill = pub.stats()
        assert at_kill.on_disk > 0 and at_kill.sent > at_kill.on_disk  # a tail not yet on disk
        publish_for(0.3)  # queued while the broker is down
        b2 = broker_factory(archive={"dir": str(b.archive_dir)}, ingress={"port": b.tcp_port})
        publish_for(1.0)
        assert pub.wait_on_disk(10.0)
        st = pub.stats()
    finally:
        pub.close()
    assert b2.stop() == 0
    archive = read_archive(b.archive_dir)
    # the killed run's files (named by the counters it kept) hold at least what the
    # publisher was told is on disk
    from mcap.reader import make_reader

    [killed] = [
        r
        for r in (json.loads(p.read_text()) for p in b.archive_dir.glob("usv-run-*.counters.json"))
        if r["run"].endswith(f"-{b.proc.pid}")
    ]
    held_by_killed = 0
    for name in killed["files"]:
        with open(b.archive_dir / name, "rb") as f:
            held_by_killed += sum(1 for _ in make_reader(f).iter_messages())
    assert held_by_killed >= at_kill.on_disk, (held_by_killed, at_kill.on_disk)
    for t, seen in published.items():
        held = {a.publish_time for a in archive[t]}
        assert seen <= held, (t, len(seen - held))  # every published sample, at least once
    assert st.replayed > 0
    print(
        f"kill -9: {at_kill.on_disk} on disk of {at_kill.sent} sent at the kill; "
        f"{st.replayed} replayed; {sum(map(len, published.values()))} published, all archived"
    )


def test_a_publisher_that_disconnects_mid_frame_is_counted_and_harms_nobody(
    broker_factory: Any,
) -> None:
    """A publisher dying in the middle of a SAMPLES frame: its whole samples before it are
    archived, the announced records of the cut frame counted as malformed (the equation
    still holds), and another publisher on the same topic loses nothing."""
    b = broker_factory()
    s = connect(f"unix:{b.unix_path}")
    now = time.time_ns()
    whole = encode_samples([(0, now + i, f32(i)) for i in range(10)], [ValueType.FLOAT32])
    cut = encode_samples([(0, now + 100 + i, f32(i)) for i in range(40)], [ValueType.FLOAT32])
    s.sendall(
        encode_hello("dying")
        + encode_register(0, ValueType.FLOAT32, X)
        + whole
        + cut[: len(cut) // 2]
    )
    time.sleep(0.3)
    s.close()
    later = run_load(f"unix:{b.unix_path}", [X], 50.0, 0.5)
    assert b.alive()
    assert b.stop() == 0
    archived = read_archive(b.archive_dir)[X]
    assert len(archived) == 10 + later.published
    c = final_counters(b.log())
    assert c["rejected_malformed"] == 40 and c["ingress_malformed_frames"] == 1, c
    assert_reconciled(c)

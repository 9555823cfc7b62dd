"""The Python publisher client against a Unix socket played by the test."""

from __future__ import annotations

import socket
import time
from pathlib import Path

from modd.link import codec
from modd.link.frames import ValueType
from modd.publisher import Publisher, encode_samples


def read_frames(conn: socket.socket, until: float = 3.0) -> list[codec.RawFrame]:
    conn.settimeout(0.1)
    sp = codec.FrameSplitter()
    out: list[codec.RawFrame] = []
    deadline = time.monotonic() + until
    while time.monotonic() < deadline:
        try:
            data = conn.recv(65536)
        except TimeoutError:
            if out:
                break
            continue
        if not data:
            break
        out += sp.feed(data)
    return out


def test_registers_batches_and_reconnects(tmp_path: Path) -> None:
    path = str(tmp_path / "s.sock")
    srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    srv.bind(path)
    srv.listen(2)
    srv.settimeout(5)
    with Publisher("pub_py", f"unix:{path}", reconnect_s=0.05, connect_wait_s=0.1) as pub:
        pub.declare("usv.a.x", "float32")
        for i in range(300):
            assert pub.publish("usv.a.x", 1000 + i, i * 0.5)
        assert pub.publish("usv.a.flag", 5, True)
        conn, _ = srv.accept()
        assert pub.flush(3)
        frames = read_frames(conn)
        types = [f.type for f in frames]
        assert types[0] == 0x01 and types.count(0x02) == 2
        n = sum(codec.Reader(f.body).varint() for f in frames if f.type == 0x03)
        assert n == 301
        conn.close()
        # The broker went away: the next batch reconnects and registers again.
        deadline = time.monotonic() + 3
        while pub.connected and time.monotonic() < deadline:
            pub.publish("usv.a.x", 5000, 1.0)
            time.sleep(0.02)
        conn2, _ = srv.accept()
        pub.publish("usv.a.x", 6000, 2.0)
        assert pub.flush(3)
        frames2 = read_frames(conn2)
        assert frames2[0].type == 0x01 and any(f.type == 0x02 for f in frames2)
        conn2.close()
        assert pub.stats().connects >= 2
    srv.close()


def test_bounded_queue_never_blocks_nor_raises() -> None:
    pub = Publisher(
        "p", "unix:/nonexistent/x.sock", queue_capacity=10, reconnect_s=0.05, connect_wait_s=0
    )
    t = time.monotonic()
    ok = sum(pub.publish("t", i, 1.0) for i in range(1000))
    assert time.monotonic() - t < 0.5
    st = pub.stats()
    assert st.published == ok and st.published + st.dropped_queue_full == 1000
    pub.declare("n", "int")
    assert not pub.publish("n", 1, float("nan"))  # no int for NaN
    assert pub.stats().dropped_bad_topic == 1
    assert not pub.publish("t", 1, object())  # type: ignore[arg-type]
    pub.close(timeout=0.2)
    assert pub.stats().dropped_at_close + pub.stats().sent == pub.stats().published


def test_samples_encoding_matches_the_spec() -> None:
    wire = encode_samples([(0, 1, 1.5), (1, -2, True)], [ValueType.FLOAT32, ValueType.BOOL])
    assert (
        wire.hex()
        == "190302" + "00" + "0100000000000000" + "0000c03f" + "01" + "feffffffffffffff" + "01"
    )

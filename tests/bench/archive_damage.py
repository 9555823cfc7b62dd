"""Recovery of a crashed archive file with damaged bytes (docs/pubbroker.md "Crash bound",
docs/reliability.md): a real PubBroker is killed (kill -9) after ~22,500 messages; 25 copies of
its file get one single-byte flip each (tests/support/mcap_oracle.py's offsets), a 26th all 25;
a PubBroker started on that directory recovers them. Prints the messages kept (official `mcap`
reader) against the oracle's chunk-by-chunk count, the start-up time, and the same for
`modd archive recover`. `--compare BIN` runs another PubBroker build on the same copies.

Run: .venv/bin/python tests/bench/archive_damage.py [--compare /path/to/modd-pubbroker]
"""

from __future__ import annotations

import argparse
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path[:0] = [
    str(Path(__file__).resolve().parents[1] / "runtime"),
    str(Path(__file__).resolve().parents[1]),
]

import pubbroker_harness  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from pubbroker_harness import BIN, PubBroker, run_load  # noqa: E402
from support import mcap_oracle as oracle  # noqa: E402

TOPICS = [(f"usv.accelerometer.accel_{a}", "float32") for a in "xyz"]


def count(path: Path) -> int:
    with open(path, "rb") as f:
        return sum(1 for _ in make_reader(f).iter_messages())


def crashed_file(tmp: Path) -> bytes:
    (tmp / "b0").mkdir()
    b = PubBroker(tmp / "b0", TOPICS, archive={"chunk_bytes": 16384}).start()
    run_load(f"unix:{b.unix_path}", [t for t, _ in TOPICS], 2500.0, 3.0)
    time.sleep(0.5)
    b.stop(signal.SIGKILL)
    [path] = sorted(b.archive_dir.glob("*.mcap"))
    return path.read_bytes()


def damaged_copies(data: bytes, layout: list[oracle.Record], d: Path) -> dict[str, int]:
    """Writes the 26 copies; the oracle's count of each."""
    d.mkdir()
    want, every = {}, data
    for i, (at, mask) in enumerate(oracle.flips(data, layout)):
        one = oracle.flipped(data, at, mask)
        every = oracle.flipped(every, at, mask)
        (d / f"usv-flip{i:02d}.mcap").write_bytes(one)
        want[f"usv-flip{i:02d}.mcap"] = oracle.count_valid(one, layout)
    (d / "usv-flipall.mcap").write_bytes(every)
    want["usv-flipall.mcap"] = oracle.count_valid(every, layout)
    return want


def startup(label: str, binary: Path, data: bytes, layout: list[oracle.Record], tmp: Path) -> None:
    d = tmp / f"archive-{label}"
    want = damaged_copies(data, layout, d)
    pubbroker_harness.BIN = binary
    (tmp / f"b-{label}").mkdir()
    b = PubBroker(tmp / f"b-{label}", TOPICS, archive={"dir": str(d)})
    start = time.monotonic()
    b.start()
    took = time.monotonic() - start
    b.stop()
    got = {name: count(d / name) for name in want}
    single = [(want[n], got[n]) for n in want if n != "usv-flipall.mcap"]
    print(
        f"{label} PubBroker start-up on 26 crashed files: {took:.2f} s; single flips: kept = "
        f"oracle in {sum(w == g for w, g in single)}/25, fewest kept "
        f"{min(g for _, g in single)}; all 25 flips: kept {got['usv-flipall.mcap']}, oracle "
        f"{want['usv-flipall.mcap']}"
    )


def cli(data: bytes, layout: list[oracle.Record], tmp: Path) -> None:
    d = tmp / "cli"
    want = damaged_copies(data, layout, d)
    modd = Path(sys.executable).parent / "modd"
    equal = tracebacks = 0
    took: list[float] = []
    for name, n in want.items():
        out = d / f"out-{name}"
        start = time.monotonic()
        r = subprocess.run(
            [str(modd), "archive", "recover", str(d / name), "-o", str(out)],
            capture_output=True,
            text=True,
        )
        took.append(time.monotonic() - start)
        tracebacks += "Traceback" in r.stderr
        equal += r.returncode == 0 and count(out) == n
    print(
        f"modd archive recover, each of the 26 files: median {sorted(took)[13]:.2f} s "
        f"(the command's start included); kept = oracle in {equal}/26; tracebacks {tracebacks}"
    )


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--compare", type=Path, metavar="BIN", help="another modd-pubbroker build")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as t:
        tmp = Path(t)
        data = crashed_file(tmp)
        layout = oracle.records(data)
        chunks = sum(1 for op, _, _ in layout if op == oracle.CHUNK)
        print(
            f"crashed file: {len(data)} bytes, {chunks} chunks, "
            f"{oracle.count_valid(data, layout)} messages"
        )
        startup("this", BIN, data, layout, tmp)
        if args.compare:
            startup("compared", args.compare, data, layout, tmp)
        cli(data, layout, tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())

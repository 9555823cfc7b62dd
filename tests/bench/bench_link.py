"""The MoDD link on the wire: the paper's scenarios 1 and 2 run for real
(C++ PubBroker, publisher load at 25 Hz, SubBroker) and tshark captures the
link on loopback. Bytes are IP bytes (IP and TCP headers included), per
direction, printed beside the planner's prediction and the paper's figures.
Asserts nothing about time or size; the issue's targets are printed.

    .venv/bin/python tests/bench/bench_link.py [--seconds 30] [--scenario 1|2]

Needs tshark (scripts/setup.sh installs it) and the right to capture on lo
(root here). The figures go in docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "subbroker"))

from modd_model import load_model  # noqa: E402
from modd_plan import make_plan  # noqa: E402
from subbroker_harness import (  # noqa: E402
    SCENARIOS,
    free_port,
    model_copy,
    processes,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

TARGETS = {1: 300.0, 2: 140.0}  # drone -> base, B/s (issue 5)


def capture(port: int, pcap: Path) -> subprocess.Popen[bytes]:
    proc = subprocess.Popen(
        ["tshark", "-q", "-i", "lo", "-f", f"tcp port {port}", "-w", str(pcap)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    assert proc.stderr is not None
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:  # tshark says "Capturing on 'Loopback'" when ready
        line = proc.stderr.readline().decode(errors="replace")
        if "Capturing" in line:
            return proc
    raise RuntimeError("tshark did not start capturing")


def ip_bytes(pcap: Path, link_port: int) -> tuple[int, int, int, int, float]:
    """(bytes drone->base, bytes base->drone, packets each way, duration)."""
    out = subprocess.run(
        ["tshark", "-r", str(pcap), "-T", "fields", "-e", "frame.time_relative",
         "-e", "tcp.srcport", "-e", "ip.len"],
        check=True, capture_output=True, text=True,
    ).stdout
    down = up = n_down = n_up = 0
    last = 0.0
    for line in out.splitlines():
        t, src, length = line.split("\t")
        last = float(t)
        if int(src) == link_port:
            down, n_down = down + int(length), n_down + 1
        else:
            up, n_up = up + int(length), n_up + 1
    return down, up, n_down, n_up, last


def run(scenario: int, seconds: float, tmp: Path) -> dict[str, float]:
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp, f"scenario{scenario}.modd")
    pb = start_pubbroker(tmp, model, link, ingress)
    sb = start_subbroker(tmp, subbroker_config(tmp, model, link, zport))
    load = start_load(tmp, model, ingress, seconds + 4)
    pcap = tmp / f"link{scenario}.pcap"
    with processes(pb, sb, load):
        wait_port(zport)
        if not sb.wait_log("running", 15):
            raise RuntimeError(sb.log())
        time.sleep(1.0)  # steady state: handshake, PING and CONFIG are not counted
        tshark = capture(link, pcap)
        time.sleep(seconds)
        os.kill(tshark.pid, signal.SIGINT)
        tshark.wait(10)
    down, up, n_down, n_up, _ = ip_bytes(pcap, link)
    plan = make_plan(load_model(model))
    paper = json.loads((SCENARIOS / "expected.json").read_text())[f"scenario{scenario}"]
    return {
        "seconds": seconds,
        "drone_to_base": down / seconds,
        "base_to_drone": up / seconds,
        "packets_down_per_s": n_down / seconds,
        "packets_up_per_s": n_up / seconds,
        "planned_drone_to_base": float(plan.link.drone_to_base),
        "planned_base_to_drone": float(plan.link.base_to_drone),
        "paper_drone_to_base": float(paper["paper_bytes_per_s"]["drone_to_base_modd"]),
        "target_drone_to_base": TARGETS[scenario],
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=30.0)
    p.add_argument("--scenario", type=int, choices=(1, 2), action="append")
    args = p.parse_args(argv)
    if shutil.which("tshark") is None:
        print("tshark is not installed (scripts/setup.sh installs it)", file=sys.stderr)
        return 2
    print(f"MoDD link on the wire, loopback, {args.seconds:g} s per scenario, IP bytes/s")
    print(f"{'':10} {'drone->base':>12} {'planned':>8} {'paper':>8} {'target':>7} "
          f"{'base->drone':>12} {'planned':>8} {'pkts/s down/up':>15}")
    for scenario in args.scenario or [1, 2]:
        with tempfile.TemporaryDirectory(prefix="modd-bench-link-") as tmp:
            r = run(scenario, args.seconds, Path(tmp))
        print(f"scenario {scenario} {r['drone_to_base']:12.1f} {r['planned_drone_to_base']:8.1f} "
              f"{r['paper_drone_to_base']:8.1f} {r['target_drone_to_base']:7.0f} "
              f"{r['base_to_drone']:12.1f} {r['planned_base_to_drone']:8.1f} "
              f"{r['packets_down_per_s']:7.2f}/{r['packets_up_per_s']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

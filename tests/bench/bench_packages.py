"""The Debian packages (`make package`, packaging/README.md) and the drone on arm64:

1. each package's installed size per architecture (Installed-Size of its control file),
   its .deb size, and what it holds (the biggest parts of its tree); checks that the
   drone package carries no backend, workbench, planner solver or browser assets;
2. the resident memory of the drone's PubBroker at scenario 1 (its sensors' 75
   samples/s, the amd64 SubBroker connected over TCP) as the aarch64 build under
   qemu-user, beside the amd64 build: VmRSS of the process every 0.5 s, median and
   peak. Under qemu-user that is the emulator's RSS (guest memory + qemu's own, its
   translation cache included): an upper bound of the board's figure. Time and CPU
   under emulation mean nothing and are not reported.

    make package && .venv/bin/python tests/bench/bench_packages.py [--seconds 30] [--memory-only]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(REPO / "tests" / "subbroker"))

from benchkit.footprint import Sampler  # noqa: E402
from benchkit.report import table  # noqa: E402

PACKAGES = REPO / "build" / "package"
ARM64_PUBBROKER = REPO / "build" / "cpp-arm64" / "bin" / "modd-pubbroker"
NOT_ON_THE_DRONE = (
    "modd_backend",
    "cvxpy",
    "highspy",
    "scipy",
    "pandas",
    "pyarrow",
    "fastapi",
    "usr/share/modd/frontend",
)


def contents(deb: Path) -> dict[str, int]:
    """Bytes per part: usr/bin/NAME, a top-level Python distribution, the frontend, ..."""
    out = subprocess.run(
        ["dpkg-deb", "-c", str(deb)], capture_output=True, text=True, check=True
    ).stdout
    parts: dict[str, int] = defaultdict(int)
    for line in out.splitlines():
        f = line.split()
        size, path = int(f[2]), f[5].lstrip("./")
        segs = path.split("/")
        if path.startswith("usr/lib/modd/python/") and len(segs) > 5:
            key = "python: " + segs[4].split("-")[0].removesuffix(".libs")
        elif path.startswith("usr/share/modd/frontend"):
            key = "usr/share/modd/frontend"
        elif path.startswith("usr/bin/"):
            key = path
        else:
            key = "/".join(segs[:3])
        parts[key] += size
    return parts


def package_rows() -> list[list[object]]:
    rows: list[list[object]] = []
    for deb in sorted(PACKAGES.glob("*.deb")):
        field = subprocess.run(
            ["dpkg-deb", "-f", str(deb), "Package", "Architecture", "Installed-Size"],
            capture_output=True,
            text=True,
            check=True,
        )
        info = dict(line.split(": ", 1) for line in field.stdout.splitlines())
        parts = contents(deb)
        top = sorted(parts.items(), key=lambda kv: -kv[1])[:6]
        holds = ", ".join(f"{k} {v / 2**20:.1f}" for k, v in top)
        if info["Package"] == "modd-drone":
            bad = [p for p in parts for n in NOT_ON_THE_DRONE if n in p]
            assert not bad, f"{deb.name} carries {bad}"
        rows.append(
            [
                info["Package"],
                info["Architecture"],
                round(int(info["Installed-Size"]) / 1024, 1),
                round(deb.stat().st_size / 2**20, 1),
                holds,
            ]
        )
    return rows


def pubbroker_rss(command: list[str], seconds: float) -> tuple[int, int]:
    """(median, peak) VmRSS in kB of the PubBroker at scenario 1, SubBroker connected."""
    from subbroker_harness import (
        free_port,
        model_copy,
        processes,
        start_load,
        start_pubbroker,
        start_subbroker,
        subbroker_config,
    )

    with tempfile.TemporaryDirectory(prefix="modd-bench-pkg-") as d:
        tmp = Path(d)
        link, ingress, zport = free_port(), free_port(), free_port()
        model = model_copy(tmp, "scenario1.modd")
        pb = start_pubbroker(tmp, model, link, ingress, command=command)
        sb = start_subbroker(tmp, subbroker_config(tmp, model, link, zport))
        load = None
        try:
            assert sb.wait_log("config 1 running", 30), sb.log()
            load = start_load(tmp, model, ingress, seconds + 2)
            time.sleep(2)  # the load running, windows flowing
            sampler = Sampler(pb.pid).start()
            time.sleep(seconds)
            fp = sampler.stop()
        finally:
            with processes(pb, sb, *([load] if load else [])):
                pass
        return fp.rss_median_kb, fp.rss_peak_kb


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--memory-only", action="store_true", help="only the RSS part")
    a = ap.parse_args()
    if not a.memory_only:
        if not list(PACKAGES.glob("*.deb")):
            sys.exit(f"no package in {PACKAGES}: run make package first")
        print("## Packages (sizes in MiB; parts: the biggest in the tree)\n")
        print(table(["package", "arch", "installed", ".deb", "holds (MiB)"], package_rows()))
    rows: list[list[object]] = []
    runs = [("amd64 (native)", [str(REPO / "build" / "bin" / "modd-pubbroker")])]
    if ARM64_PUBBROKER.exists():
        runs.append(("arm64 (qemu-aarch64-static)", ["qemu-aarch64-static", str(ARM64_PUBBROKER)]))
    else:
        print(f"\n(no {ARM64_PUBBROKER}: runtime/cpp/scripts/test-arm64.sh builds it)")
    for name, command in runs:
        med, peak = pubbroker_rss(command, a.seconds)
        rows.append(["modd-pubbroker", name, round(med / 1024, 1), round(peak / 1024, 1)])
    print(f"\n## Drone RSS at scenario 1 ({a.seconds:.0f} s sampled, MiB)\n")
    print(table(["process", "build", "RSS median", "RSS peak"], rows))


if __name__ == "__main__":
    main()

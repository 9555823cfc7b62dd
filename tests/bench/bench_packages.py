"""The Debian packages (`make package`, packaging/README.md) and the drone on arm64:

1. each package's installed size per architecture (Installed-Size of its control file),
   its .deb size, and what it holds (the biggest parts of its tree); checks that the
   drone package carries no backend, workbench, planner solver or browser assets;
2. resident memory (VmRSS every 0.5 s, median and peak) of the link's processes, each
   build as the packages hold it: the aarch64 ones under qemu-user (the PubBroker
   binary; the SubBroker and modd-sensors from the arm64 packages' own Python trees,
   run by Debian's arm64 python3.11, tests/bench/arm64-python.sh), beside amd64:
   - the PubBroker and the SubBroker at scenario 1 (75 samples/s from the load
     generator, linked over TCP);
   - modd-sensors reading an NMEA GNSS (GGA and RMC at 10 Hz on a pseudo-terminal,
     latitude and longitude) into that PubBroker's ingress.
   Under qemu-user that is the emulator's RSS (guest memory + qemu's own, its
   translation cache included): an upper bound of the board's figure. Time and CPU
   under emulation mean nothing and are not reported.

    make package && .venv/bin/python tests/bench/bench_packages.py [--seconds 30] [--memory-only]"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(REPO / "tests" / "subbroker"))
sys.path.insert(0, str(REPO / "tests" / "sensors"))  # instruments on ptys

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


def arm64_python() -> Path:
    """Debian's arm64 python3.11, unpacked (tests/bench/arm64-python.sh, cached)."""
    out = subprocess.run(
        [str(HERE / "arm64-python.sh")], capture_output=True, text=True, check=True
    ).stdout
    return Path(out.strip())


def arm64_tree(package: str) -> Path:
    """The private Python tree of the arm64 PACKAGE: the tree `make package` packed
    (build/package/root), else its .deb's, unpacked once per build."""
    built = PACKAGES / "root" / f"{package}-arm64" / "usr/lib/modd/python"
    if (built / "modd").is_dir():
        return built
    deb = sorted(PACKAGES.glob(f"{package}_*_arm64.deb"))[-1]
    dest = REPO / "build" / "arm64-python" / deb.stem
    if not (dest / "usr/lib/modd/python").is_dir():
        subprocess.run(["dpkg-deb", "-x", str(deb), str(dest)], check=True)
    return dest / "usr/lib/modd/python"


def python_command(arch: str, package: str, module: str) -> list[str]:
    """MODULE's main() as the package runs it: amd64 from this checkout's environment
    (the same code), arm64 from the arm64 package's tree under qemu-user (-I: nothing
    of this machine's Python on its path; its children, e.g. modd-sensors' model check,
    run through a wrapper that starts qemu again: no binfmt_misc here)."""
    if arch == "amd64":
        return [sys.executable, "-m", module]
    sysroot, tree = arm64_python(), arm64_tree(package)
    qemu = ["qemu-aarch64-static", "-L", str(sysroot), f"{sysroot}/usr/bin/python3.11"]
    wrapper = sysroot.parent / "python3.11-qemu"
    wrapper.write_text("#!/bin/sh\nexec " + " ".join(qemu) + ' "$@"\n')
    wrapper.chmod(0o755)
    code = f"import os, sys; sys.executable = {str(wrapper)!r}; "
    code += f"os.environ['PYTHONPATH'] = {str(tree)!r}; sys.path.insert(0, {str(tree)!r}); "
    code += f"from {module} import main; sys.exit(main())"
    return [*qemu, "-I", "-c", code]


def pubbroker_command(arch: str) -> list[str]:
    if arch == "amd64":
        return [str(REPO / "build" / "bin" / "modd-pubbroker")]
    return ["qemu-aarch64-static", str(ARM64_PUBBROKER)]


def sample(pids: dict[str, int], seconds: float) -> dict[str, tuple[int, int]]:
    """(median, peak) VmRSS in kB of each process, sampled together for SECONDS."""
    samplers = {name: Sampler(pid).start() for name, pid in pids.items()}
    time.sleep(seconds)
    fps = {name: s.stop() for name, s in samplers.items()}
    return {name: (fp.rss_median_kb, fp.rss_peak_kb) for name, fp in fps.items()}


def scenario_1_rss(arch: str, seconds: float) -> dict[str, tuple[int, int]]:
    """The PubBroker and the SubBroker of ARCH at scenario 1, linked over TCP."""
    from subbroker_harness import (
        Proc,
        free_port,
        model_copy,
        processes,
        start_load,
        start_pubbroker,
        subbroker_config,
    )

    with tempfile.TemporaryDirectory(prefix="modd-bench-pkg-") as d:
        tmp = Path(d)
        link, ingress, zport = free_port(), free_port(), free_port()
        model = model_copy(tmp, "scenario1.modd")
        pb = start_pubbroker(tmp, model, link, ingress, command=pubbroker_command(arch))
        sb_cmd = python_command(arch, "modd-base", "modd.subbroker.cli")
        config = subbroker_config(tmp, model, link, zport)
        sb = Proc("sb", [*sb_cmd, "--config", str(config)], tmp / "sb.log")
        load = None
        try:
            assert sb.wait_log("config 1 running", 300), sb.log()
            load = start_load(tmp, model, ingress, seconds + 4)
            time.sleep(3)  # the load running, windows flowing
            return sample({"modd-pubbroker": pb.pid, "modd-subbroker": sb.pid}, seconds)
        finally:
            with processes(pb, sb, *([load] if load else [])):
                pass


GNSS_MODEL = """Drone usv { Sensors { Sensor gnss kind nmea on "DEV" { baud = 9600; } measures {
    lat("deg", float64) from sentence GGA.lat; lon("deg", float64) from sentence GGA.lon; } } }
PubBroker onboard("127.0.0.1":1, "/tmp/unused");
SubBroker base("127.0.0.1":2, "/tmp/unused");
Publishers { Publisher nav(0.1, "usv.gnss.lat", "usv.gnss.lon"); }
Subscriptions { Subscriber lat("usv.gnss.lat", 1.0, LAST); }
"""


def feed_gnss(device: object, stop: threading.Event) -> None:
    """GGA and RMC at 10 Hz, as a GNSS receiver's fix epoch sends them."""
    from devices import nmea

    i = 0
    while not stop.wait(0.1):
        t = f"1015{i // 100 % 60:02d}.{i % 100:02d}"
        lat = f"47{42 + i % 1000 * 0.0001:07.4f}"
        device.write(nmea(f"GNGGA,{t},{lat},N,00321.0000,W,1,09,0.9,4.2,M,,M,,"))  # type: ignore[attr-defined]
        device.write(nmea(f"GNRMC,{t},A,{lat},N,00321.0000,W,0.1,,051226,,,A"))  # type: ignore[attr-defined]
        i += 1


def sensors_rss(arch: str, seconds: float) -> dict[str, tuple[int, int]]:
    """modd-sensors of ARCH reading a 10 Hz GNSS into the PubBroker of ARCH."""
    from devices import PtyDevice
    from modd_model import load_text
    from subbroker_harness import Proc, free_port, processes, start_pubbroker

    with tempfile.TemporaryDirectory(prefix="modd-bench-sens-") as d:
        tmp = Path(d)
        gnss = PtyDevice(tmp / "gnss")
        result = load_text(GNSS_MODEL.replace("DEV", str(tmp / "gnss")), "gnss.modd")
        assert result.ok and result.model is not None, [str(x) for x in result.diagnostics]
        model = tmp / "gnss.json"
        model.write_text(json.dumps(result.model))
        link, ingress = free_port(), free_port()
        pb = start_pubbroker(tmp, model, link, ingress, command=pubbroker_command(arch))
        cmd = python_command(arch, "modd-drone", "modd.sensors.cli")
        cmd += ["--model", str(model), "--ingress", f"tcp:127.0.0.1:{ingress}"]
        sensors = Proc("sensors", [*cmd, "--status-file", str(tmp / "s.json")], tmp / "s.log")
        stop = threading.Event()
        feeder = threading.Thread(target=feed_gnss, args=(gnss, stop), daemon=True)
        try:
            feeder.start()
            wait_values(tmp / "s.json", 300, sensors)
            return sample({"modd-sensors": sensors.pid}, seconds)
        finally:
            stop.set()
            with processes(pb, sensors):
                pass
            gnss.close()


def wait_values(status: Path, timeout_s: float, proc: object) -> None:
    """Until modd-sensors says it has read values (its --status-file)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            if json.loads(status.read_text())["sensors"]["gnss"]["values"] > 20:
                return
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.5)
    raise AssertionError(f"modd-sensors read nothing: {proc.log()[-2000:]}")  # type: ignore[attr-defined]


def memory_rows(seconds: float) -> list[list[object]]:
    rows: list[list[object]] = []
    archs = ["amd64"]
    if ARM64_PUBBROKER.exists() and list(PACKAGES.glob("*arm64*")):
        archs.append("arm64")
    else:
        print(f"\n(no {ARM64_PUBBROKER} or arm64 package: run make package)")
    for arch in archs:
        build = "amd64 (native)" if arch == "amd64" else "arm64 (qemu-aarch64-static)"
        for name, (med, peak) in {
            **scenario_1_rss(arch, seconds),
            **sensors_rss(arch, seconds),
        }.items():
            rows.append([name, build, round(med / 1024, 1), round(peak / 1024, 1)])
    return rows


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
    rows = memory_rows(a.seconds)
    print(f"\n## RSS at scenario 1 and a 10 Hz GNSS ({a.seconds:.0f} s sampled, MiB)\n")
    print(table(["process", "build", "RSS median", "RSS peak"], rows))


if __name__ == "__main__":
    main()

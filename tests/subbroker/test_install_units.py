"""The packaged units, run as systemd would run them (issue 39, item 5, on an installed
drone; issue 43): the amd64 `modd-drone` and `modd-base` of `make package` installed
offline into two clean Debian roots (as test_install_root.py), then every link unit
started from its own installed unit file — `ExecStartPre=` and `ExecStart=` read from
/lib/systemd/system, `EnvironmentFile=` loaded and `$VAR`/`${VAR}` expanded
(unit_exec.py), as its `User=` (chroot + setpriv), `RuntimeDirectory=` made for it:
the drone's `modd-pubbroker`, `modd-sensors` and `modd-mavlink` and the base station's
`modd-subbroker`. A signed deploy adds a depth sounder (a pseudo-terminal the root
sees): the deploy's reply carries what `modd-sensors` and `modd-mavlink` did, the
sounder's values reach the archive (read with the official `mcap` reader, the
sentences decoded by pynmea2); a second deploy removes it: its reader stops (the
sensors process no longer holds the device) and no later value is archived. No
process is restarted. Run with `make package-test`; skips when the packages are not
built."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pynmea2  # type: ignore[import-untyped]
import pytest
from modd.subbroker.client import request
from modd.zenoh_session import wait_connected
from modd_model import load_text
from modd_model.ingress import ingress_of
from subbroker_harness import (
    KEY,
    Proc,
    free_port,
    processes,
    shared_credentials,
    signed,
    wait_port,
)
from test_install_root import CLEAN_ENV, fresh_root, in_root, install_offline, modd_ids, ok
from unit_exec import Unit, read_unit

TESTS = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TESTS / "sensors"))  # the instruments on pseudo-terminals
sys.path.insert(0, str(TESTS / "mavlink"))  # the archive read with the official MCAP reader
from devices import PtyDevice, nmea, wait_until  # noqa: E402
from mavlink_harness import read_archive  # noqa: E402

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

DEV = "/var/lib/modd/dev"  # the instruments' links, inside the drone's root
GNSS = """Sensor gnss kind nmea on "{dev}/gnss" { baud = 9600; } measures {
        lat("deg", float64) from sentence GGA.lat; }"""
SOUNDER = """Sensor sounder kind nmea on "{dev}/sounder" { baud = 4800; } measures {
        depth(METER) from sentence DBT.depth_meters; }"""


def boat(sensors: list[str], topics: list[str], link: int) -> dict[str, Any]:
    """The drone's model: its archive in /var/lib/modd, its ingress the generated default
    (a unix socket in /tmp, which the drone's units share: JoinsNamespaceOf=)."""
    quoted = ", ".join(f'"usv.{t}"' for t in topics)
    text = (
        "Drone usv { Sensors { " + "\n".join(sensors).replace("{dev}", DEV) + " } }\n"
        f'PubBroker onboard("127.0.0.1":{link}, "/var/lib/modd/archive");\n'
        'SubBroker base("127.0.0.1":2, "/var/lib/modd/base");\n'
        f"Publishers {{ Publisher nav(0.1, {quoted}); }}\n"
        'Subscriptions { Subscriber lat("usv.gnss.lat", 1.0, LAST); }\n'
    )
    result = load_text(text, "boat.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def configure(drone: Path, base: Path, model: dict[str, Any], ports: dict[str, int]) -> None:
    """The operator's files (/etc/modd) of both machines, before the install."""
    for root in (drone, base):
        etc = root / "etc/modd"
        etc.mkdir(parents=True)
        (etc / "model.json").write_text(json.dumps(model))
        (etc / "link.key").write_text(KEY + "\n")
    topics = [{"name": "usv.gnss.lat", "type": "float64"}]
    pb = {
        "name": "usv",
        "link": {"host": "127.0.0.1", "port": ports["link"], "key": "file:/etc/modd/link.key"},
        "ingress": {"unix_path": ingress_of(model).unix_socket},  # as modd generate writes
        "archive": {"dir": "/var/lib/modd/archive", "flush_interval_ms": 200},
        "topics": topics,
        "status_period_s": 60,
    }
    (drone / "etc/modd/pubbroker.json").write_text(json.dumps(pb))
    (base / "etc/modd/subbroker.toml").write_text(f"""
model = "/etc/modd/model.json"
state_dir = "/var/lib/modd/state"
[link]
endpoint = "127.0.0.1:{ports["link"]}"
key = "file:/etc/modd/link.key"
[zenoh]
listen = ["tcp/127.0.0.1:{ports["zenoh"]}"]
credentials_dir = "/var/lib/modd/credentials"
[delivery]
tcp = false
status_period_s = 0.5
""")
    (base / "var/lib/modd").mkdir(parents=True)
    subprocess.run(
        ["cp", "-a", str(shared_credentials().dir), str(base / "var/lib/modd/credentials")],
        check=True,
    )


def after_install(drone: Path, mavlink_port: int) -> None:
    """The operator's edit of the conffile drone.env (the autopilot's port: a UDP port
    nobody sends to, so modd-mavlink runs idle), the instruments' folder, and the
    state the services own."""
    env = drone / "etc/modd/drone.env"
    text = env.read_text().replace(
        "MODD_MAVLINK_CONNECT=/dev/ttyAMA0,921600",
        f"MODD_MAVLINK_CONNECT=udpin:127.0.0.1:{mavlink_port}",
    )
    assert text != env.read_text(), text
    env.write_text(text)
    (drone / DEV.lstrip("/")).mkdir(mode=0o755)
    for root in (drone,):
        ok(in_root(root, "/bin/chown", "-R", "modd:modd", "/var/lib/modd"))


def unit_argv(root: Path, unit: Unit, argv: list[str]) -> list[str]:
    """ARGV as the unit's User=/Group= in the root: a mount namespace of its own with
    /proc, a /dev/shm of 1777 and the host's /dev/pts (the instruments' ptys), the unit's
    environment (EnvironmentFile=) and nothing else, its WorkingDirectory=."""
    user, group = unit.one("User"), unit.one("Group")
    assert (user, group) == ("modd", "modd"), unit  # never root
    shell = (
        f'mount -t proc proc "{root}/proc" && mkdir -p "{root}/dev/shm" "{root}/dev/pts" && '
        f'mount -t tmpfs -o mode=1777 shm "{root}/dev/shm" && '
        f'mount --bind /dev/pts "{root}/dev/pts" && exec chroot "{root}" "$@"'
    )
    setpriv = ["/usr/bin/setpriv", f"--reuid={user}", f"--regid={group}", "--init-groups", "--"]
    env = [f"{k}={v}" for k, v in unit.env.items()]
    cd = ["/bin/sh", "-c", 'cd "$0" && exec "$@"', unit.one("WorkingDirectory", "/")]
    ns = ["unshare", "-m", "--propagation", "private", "sh", "-c", shell, "sh"]
    return [*ns, *CLEAN_ENV, "HOME=/var/lib/modd", *env, *setpriv, *cd, *argv]


def start_unit(root: Path, tmp: Path, name: str) -> Proc:
    """The installed unit NAME started as systemd would: its RuntimeDirectory= made
    for its user, its ExecStartPre= run to success, then its ExecStart=."""
    unit = read_unit(root, f"{name}.service")
    uid, gid = modd_ids(root)
    for d in unit.one("RuntimeDirectory").split():
        run = root / "run" / d
        run.mkdir(mode=0o755, parents=True, exist_ok=True)
        os.chown(run, uid, gid)
    for pre in unit.exec_start_pre:
        r = subprocess.run(unit_argv(root, unit, pre), capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, (name, pre, r.stdout, r.stderr)
    print(name, unit.exec_start)
    return Proc(name, unit_argv(root, unit, unit.exec_start), tmp / f"{name}.log")


def deploy(session: Any, model: dict[str, Any], revision: int) -> dict[str, Any]:
    body = {"text": json.dumps(model), "format": "json", "project_id": 1, "revision": revision}
    reply: dict[str, Any] = request(session, "modd/usv/deploy", signed(body), timeout_s=60)
    return reply


def holds(pid: int, device: str) -> bool:
    """Whether process PID has DEVICE open (the same character device behind one of
    its descriptors: their paths differ across the chroot)."""
    rdev = os.stat(device).st_rdev
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            st = os.stat(fd)
        except OSError:
            continue
        if st.st_rdev == rdev and not st.st_size and (st.st_mode & 0o170000) == 0o020000:
            return True
    return False


def test_the_units_own_command_lines_follow_a_deploy_without_a_restart(
    tmp_path: Path, zenoh_client: Any
) -> None:
    drone = fresh_root(tmp_path, "drone", "modd-drone")
    base = fresh_root(tmp_path, "base", "modd-base")
    ports = {k: free_port() for k in ("link", "zenoh", "mavlink")}
    v1 = boat([GNSS], ["gnss.lat"], ports["link"])
    configure(drone, base, v1, ports)
    print(install_offline(drone, "modd-drone"))
    print(install_offline(base, "modd-base"))
    ok(in_root(base, "/bin/chown", "-R", "modd:modd", "/var/lib/modd"))
    after_install(drone, ports["mavlink"])
    uid, _ = modd_ids(drone)
    sounder = PtyDevice(drone / DEV.lstrip("/") / "sounder")
    gnss = PtyDevice(drone / DEV.lstrip("/") / "gnss")
    for dev in (sounder, gnss):
        os.chown(os.ttyname(dev.slave), uid, -1)  # as dialout gives it on the boat
    onboard = drone / "var/lib/modd/onboard"
    pb = start_unit(drone, tmp_path, "modd-pubbroker")
    with processes(pb):
        wait_port(ports["link"], 30)
        sensors = start_unit(drone, tmp_path, "modd-sensors")
        mavlink = start_unit(drone, tmp_path, "modd-mavlink")
        sb = start_unit(base, tmp_path, "modd-subbroker")
        with processes(sensors, mavlink, sb):
            wait_port(ports["zenoh"], 120)  # the installed SubBroker's first start
            session = zenoh_client(ports["zenoh"])
            assert wait_connected(session)
            assert sb.wait_log("config 1 running", 90), sb.log() + pb.log()
            wait_until(
                lambda: (
                    (onboard / "applied/sensors.json").exists()
                    and (onboard / "applied/mavlink.json").exists()
                ),
                30,
                "modd-sensors and modd-mavlink following the on-board model file",
            )
            pids = {p.name: p.pid for p in (pb, sensors, mavlink, sb)}
            run_deploys(session, (pb, sensors, mavlink, sb), sounder, ports)
            assert {p.name: p.pid for p in (pb, sensors, mavlink, sb) if p.alive()} == pids
            time.sleep(0.6)  # the last samples reach the archive before the stop
    check_archive(drone, sounder)
    sounder.close()
    gnss.close()


DEPTHS = [3.5, 4.5, 5.5]


def run_deploys(session: Any, procs: Any, sounder: PtyDevice, ports: dict[str, int]) -> None:
    pb, sensors, _mavlink, sb = procs
    v2 = boat([GNSS, SOUNDER], ["gnss.lat", "sounder.depth"], ports["link"])
    reply = deploy(session, v2, 2)
    assert reply["status"] == "ACKED", (reply, sb.log(), pb.log())
    onboard = reply["onboard"]
    assert onboard["sensors"]["ok"], onboard
    assert {s["sensor"]: s["action"] for s in onboard["sensors"]["sensors"]} == {
        "gnss": "unchanged",
        "sounder": "started",
    }, onboard
    assert "mavlink" in onboard, onboard  # modd-mavlink followed the deploy too
    slave = os.ttyname(sounder.slave)
    wait_until(lambda: holds(sensors.pid, slave), 5, "modd-sensors opening the sounder")
    for depth in DEPTHS:
        sounder.write(nmea(f"SDDBT,11.48,f,{depth:.2f},M,1.91,F"))
        time.sleep(0.1)
    status = Path(f"/proc/{sensors.pid}/root/run/modd/sensors.json")  # its --status-file
    wait_until(
        lambda: json.loads(status.read_text())["sensors"]["sounder"]["values"] == len(DEPTHS),
        5,
        "the sounder's values read",
    )
    time.sleep(0.6)  # published, archived (flush_interval_ms 200)
    v3 = boat([GNSS], ["gnss.lat"], ports["link"])
    reply = deploy(session, v3, 3)
    assert reply["status"] == "ACKED" and reply["onboard"]["sensors"]["ok"], reply
    actions = {s["sensor"]: s["action"] for s in reply["onboard"]["sensors"]["sensors"]}
    assert actions == {"gnss": "unchanged", "sounder": "stopped"}, reply
    wait_until(lambda: not holds(sensors.pid, slave), 3, "the sounder's reader stopping")
    sounder.write(nmea("SDDBT,11.48,f,99.00,M,1.91,F"))  # read by nobody
    assert "config 3 accepted" in pb.log(), pb.log()


def check_archive(drone: Path, sounder: PtyDevice) -> None:
    archive = read_archive(drone / "var/lib/modd/archive")
    depths = [v for _, v in archive.get("usv.sounder.depth", [])]
    sentences = [nmea(f"SDDBT,11.48,f,{d:.2f},M,1.91,F").decode().strip() for d in DEPTHS]
    decoded = [float(pynmea2.parse(s, check=True).depth_meters) for s in sentences]
    assert depths == decoded, archive.keys()

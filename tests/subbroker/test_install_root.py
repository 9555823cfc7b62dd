"""The install test (issue 43): the amd64 packages of `make package` installed into
clean Debian roots, a drone's and a base station's (bookworm minbase,
packaging/test-root.sh), with the network cut
(`unshare -n`: no registry reachable), so that the maintainer scripts really run; then
scenario 1 from the installed files as the service user (chroot + setpriv to `modd`):
the installed PubBroker and SubBroker on loopback with a configuration of the test's,
a publisher load into the PubBroker's ingress, a zenoh subscriber outside the root.
Every delivered window equals the archive the installed PubBroker wrote (read with the
official `mcap` reader), the archive grows, and no process of the root runs as root.
Then an upgrade to a newer build keeps the archive and /etc/modd, and a purge says what
it leaves. Run it with `make package-test` (it is not part of `make test`: the packages
take minutes to build); it skips, saying so, when the packages are not built."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_session import client_settings, open_session, wait_connected
from modd_model import load_model
from modd_model.query import topics
from subbroker_harness import (
    KEY,
    REPO,
    Proc,
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    shared_credentials,
    start_load,
    wait_port,
)

from conftest import Collector

pytestmark = [pytest.mark.e2e, pytest.mark.slow]

PACKAGES = REPO / "build" / "package"
RUN_S = 8.0
SUBBROKER_TOML = "/etc/modd/subbroker.toml"
PUBBROKER_JSON = "/etc/modd/pubbroker.json"
CLEAN_ENV = ["/usr/bin/env", "-i", "PATH=/usr/sbin:/usr/bin:/sbin:/bin", "LANG=C.UTF-8"]


def built(name: str) -> Path:
    found = sorted(PACKAGES.glob(f"{name}_*_amd64.deb"))
    if not found:
        pytest.skip(f"{PACKAGES}/{name}_*_amd64.deb is not built: run `make package`")
    return found[-1]


def in_root(root: Path, *cmd: str, net: bool = True) -> subprocess.CompletedProcess[str]:
    """CMD in the root as root, /proc mounted in a mount namespace of its own;
    net=False: in a new network namespace too (no interface but a down loopback)."""
    shell = f'mount -t proc proc "{root}/proc" && exec chroot "{root}" "$@"'
    ns = ["unshare", "-m", "--propagation", "private", *([] if net else ["-n"])]
    return subprocess.run(
        [*ns, "sh", "-c", shell, "sh", *CLEAN_ENV, *cmd],
        capture_output=True,
        text=True,
        timeout=300,
    )


def ok(r: subprocess.CompletedProcess[str]) -> str:
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout + r.stderr


def as_modd(root: Path, tmp: Path, tag: str, *cmd: str) -> Proc:
    """An installed command run from the root as the service user (the units' User=)."""
    # /proc and a /dev/shm of 1777 as a booted machine has them (zenoh's shared memory)
    shell = (
        f'mount -t proc proc "{root}/proc" && mkdir -p "{root}/dev/shm" && '
        f'mount -t tmpfs -o mode=1777 shm "{root}/dev/shm" && exec chroot "{root}" "$@"'
    )
    setpriv = ["/usr/bin/setpriv", "--reuid=modd", "--regid=modd", "--init-groups", "--"]
    argv = ["unshare", "-m", "--propagation", "private", "sh", "-c", shell, "sh"]
    return Proc(tag, [*argv, *CLEAN_ENV, "HOME=/var/lib/modd", *setpriv, *cmd], tmp / f"{tag}.log")


def fresh_root(tmp: Path, name: str, package: str) -> Path:
    """A clean root from the cached bookworm tarball, the package's .deb in its /tmp."""
    tar = subprocess.run(
        [str(REPO / "packaging" / "test-root.sh")], capture_output=True, text=True, check=True
    ).stdout.strip()
    root = tmp / name
    root.mkdir()
    subprocess.run(["tar", "-xf", tar, "-C", str(root)], check=True)
    shutil.copy(built(package), root / "tmp")
    return root


def install_offline(root: Path, package: str) -> str:
    probe = "import socket; socket.create_connection(('deb.debian.org', 80), 3)"
    offline = in_root(root, "/usr/bin/python3", "-c", probe, net=False)
    assert offline.returncode != 0, "the registry is reachable from the install namespace"
    return ok(in_root(root, "/usr/bin/dpkg", "-i", f"/tmp/{built(package).name}", net=False))


def configure(drone: Path, base: Path, tmp: Path, link: int, ingress: int, zport: int) -> Path:
    """The operator's files in each root's /etc/modd (before the install: postinst makes
    the key 0600 modd) and the zenoh credentials the test's subscriber shares."""
    model = model_copy(tmp, "scenario1.modd")
    m = load_model(model)
    for root in (drone, base):
        etc = root / "etc" / "modd"
        etc.mkdir(parents=True)
        (etc / "model.json").write_text(model.read_text())
        (etc / "link.key").write_text(KEY + "\n")
        os.chmod(etc / "link.key", 0o644)  # a careless copy: postinst closes it
    pb = {
        "name": m["drone"]["name"],
        "link": {"host": "127.0.0.1", "port": link, "key": "file:/etc/modd/link.key"},
        "ingress": {"host": "127.0.0.1", "port": ingress},
        "archive": {"dir": "/var/lib/modd/archive", "flush_interval_ms": 200},
        "topics": [{"name": t.name, "type": t.type} for t in topics(m).values()],
        "status_period_s": 60,
    }
    (drone / "etc/modd/pubbroker.json").write_text(json.dumps(pb))
    (base / "etc/modd/subbroker.toml").write_text(f"""
model = "/etc/modd/model.json"
state_dir = "/var/lib/modd/state"
[link]
endpoint = "127.0.0.1:{link}"
key = "file:/etc/modd/link.key"
[zenoh]
listen = ["tcp/127.0.0.1:{zport}"]
credentials_dir = "/var/lib/modd/credentials"
[delivery]
tcp = false
status_period_s = 0.5
""")
    shutil.copytree(shared_credentials().dir, base / "var/lib/modd/credentials")
    return model


def installed(root: Path, package: str) -> int:
    """Offline install; what postinst made checked; the modd uid."""
    print(install_offline(root, package))
    uid, gid = modd_ids(root)
    assert uid != 0 and gid != 0
    key = (root / "etc/modd/link.key").stat()
    assert (key.st_mode & 0o777, key.st_uid) == (0o600, uid)
    state = (root / "var/lib/modd").stat()
    assert (state.st_mode & 0o777, state.st_uid) == (0o750, uid)
    ok(in_root(root, "/bin/chown", "-R", "modd:modd", "/var/lib/modd"))
    return uid


def modd_ids(root: Path) -> tuple[int, int]:
    line = next(
        ln for ln in (root / "etc/passwd").read_text().splitlines() if ln.startswith("modd:")
    )
    return int(line.split(":")[2]), int(line.split(":")[3])


def root_processes(root: Path) -> dict[int, int]:
    """pid -> real uid of every process whose root directory is `root`."""
    out: dict[int, int] = {}
    for p in Path("/proc").iterdir():
        if not p.name.isdigit():
            continue
        try:
            if os.readlink(p / "root") == str(root):
                uid = next(
                    ln for ln in (p / "status").read_text().splitlines() if ln.startswith("Uid:")
                )
                out[int(p.name)] = int(uid.split()[1])
        except (OSError, StopIteration):
            continue
    return out


def archive_bytes(root: Path) -> int:
    return sum(f.stat().st_size for f in (root / "var/lib/modd/archive").glob("*.mcap"))


def test_installed_offline_then_scenario_1_as_modd_then_upgrade_and_purge(tmp_path: Path) -> None:
    """The drone and the base station are two machines: two roots (their private
    Python trees share /usr/lib/modd/python, so one machine holds one of them)."""
    drone = fresh_root(tmp_path, "drone", "modd-drone")
    base = fresh_root(tmp_path, "base", "modd-base")
    link, ingress, zport = free_port(), free_port(), free_port()
    model = configure(drone, base, tmp_path, link, ingress, zport)
    uids = {drone: installed(drone, "modd-drone"), base: installed(base, "modd-base")}
    run_scenario_1(drone, base, tmp_path, model, (link, ingress, zport), uids)
    upgrade_keeps_archive(drone, "modd-drone")
    upgrade_keeps_archive(base, "modd-base")
    for root, package in ((drone, "modd-drone"), (base, "modd-base")):
        out = ok(in_root(root, "/usr/bin/dpkg", "--purge", package, net=False))
        assert "Left in place" in out and "/var/lib/modd" in out, out
        assert not (root / "usr/lib/modd/python").exists()
        assert (root / "etc/modd/model.json").exists()
    assert list((drone / "var/lib/modd/archive").glob("*.mcap"))  # the data stays


def run_scenario_1(
    drone: Path, base: Path, tmp: Path, model: Path, ports: tuple[int, int, int], uids: Any
) -> None:
    link, ingress, zport = ports
    pb = as_modd(drone, tmp, "pb", "/usr/bin/modd-pubbroker", "--config", PUBBROKER_JSON)
    with processes(pb):
        wait_port(link, 20)
        sb = as_modd(base, tmp, "sb", "/usr/bin/modd-subbroker", "--config", SUBBROKER_TOML)
        with processes(sb):
            wait_port(zport, 60)
            session = zenoh_client_of(zport)
            got = Collector()
            session.declare_subscriber("modd/usv/**", got.on_sample)
            assert sb.wait_log("config 1 running", 60), sb.log() + pb.log()
            before = archive_bytes(drone)
            load = start_load(tmp, model, ingress, RUN_S)
            with processes(load):
                time.sleep(RUN_S / 2)
                for root, proc in ((drone, pb), (base, sb)):
                    running = root_processes(root)
                    assert proc.pid in running, running
                    assert set(running.values()) == {uids[root]}, running  # nothing as root
                load.p.wait(RUN_S + 20)
            time.sleep(1.5)
            values = got.snapshot()
            session.close()
    assert archive_bytes(drone) > before, pb.log()
    assert len(values) == 7, (sorted(values), sb.log())
    checked = check_against_archive(values, read_archive(drone / "var/lib/modd/archive", model))
    assert checked >= 7


def zenoh_client_of(port: int) -> Any:
    s = open_session(
        client_settings(f"tcp/127.0.0.1:{port}", shared_credentials().cred_file("backend"))
    )
    assert wait_connected(s)
    return s


def newer(root: Path, name: str) -> str:
    """The same build under a higher version: dpkg sees an upgrade (prerm upgrade,
    the new postinst configure with the old version, the conffiles compared)."""
    deb = built(name)
    work = root.parent / f"repack-{name}"
    subprocess.run(["dpkg-deb", "-R", str(deb), str(work)], check=True)
    control = work / "DEBIAN" / "control"
    text = control.read_text()
    version = next(ln.split(": ", 1)[1] for ln in text.splitlines() if ln.startswith("Version:"))
    control.write_text(text.replace(f"Version: {version}", f"Version: {version}.1"))
    out = root / "tmp" / f"{name}_{version}.1_amd64.deb"
    subprocess.run(
        ["dpkg-deb", "--root-owner-group", "-b", str(work), str(out)],
        check=True,
        capture_output=True,
    )
    return f"/tmp/{out.name}"


def upgrade_keeps_archive(root: Path, package: str) -> None:
    state = {str(f): f.stat().st_size for f in (root / "var/lib/modd").rglob("*") if f.is_file()}
    conffile = next((root / "etc/modd").glob("*.env"))
    conffile.write_text(conffile.read_text() + "# edited by the operator\n")
    etc = {f.name: f.read_bytes() for f in (root / "etc/modd").iterdir()}
    out = ok(in_root(root, "/usr/bin/dpkg", "-i", newer(root, package), net=False))
    assert "Preparing to unpack" in out, out
    status = ok(in_root(root, "/usr/bin/dpkg-query", "-W", "-f", "${Version}\\n", package))
    assert status.strip().endswith(".1"), status
    after = {str(f): f.stat().st_size for f in (root / "var/lib/modd").rglob("*") if f.is_file()}
    assert after == state
    assert {f.name: f.read_bytes() for f in (root / "etc/modd").iterdir()} == etc
    assert (root / "etc/modd/link.key").stat().st_mode & 0o777 == 0o600

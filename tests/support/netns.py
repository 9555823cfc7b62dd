"""Network namespaces joined by veth links, made and deleted by one test.

Every namespace and link is created here and deleted in :meth:`Fabric.close`; the
addresses (10.44.<link>.1 and .2, a /30 per link) exist **only inside these
namespaces**: nothing is added to the host's own namespace. A link is cut and
healed with ``ip link set down/up`` on both of its ends.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time

import pytest


def _ip(*args: str) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(["ip", *args], capture_output=True, timeout=10)


def netns_works() -> bool:
    """Whether this process may make a namespace and move a veth end into it."""
    if shutil.which("ip") is None or os.geteuid() != 0:
        return False
    name = f"m44probe{os.getpid() % 100000}"
    try:
        if _ip("netns", "add", name).returncode != 0:
            return False
        return _ip("-n", name, "link", "add", "p0", "type", "veth", "peer", "p1").returncode == 0
    finally:
        _ip("netns", "del", name)


#: The mark of a test that needs :func:`netns_works`.
needs_netns = pytest.mark.skipif(
    not netns_works(), reason="no network namespaces with veth links (needs root and ip netns)"
)


class Fabric:
    """Named namespaces (``ns(name)``) and the veth links between them."""

    def __init__(self) -> None:
        self.tag = f"m{os.getpid() % 100000}"
        self.spaces: dict[str, str] = {}
        self.links: dict[frozenset[str], tuple[str, str, str, str]] = {}

    def ns(self, name: str) -> str:
        """The namespace for ``name`` (made on first use, its loopback up)."""
        if name not in self.spaces:
            full = f"{self.tag}{name}"
            self._run("netns", "add", full)
            self._run("-n", full, "link", "set", "lo", "up")
            self.spaces[name] = full
        return self.spaces[name]

    def link(self, a: str, b: str) -> tuple[str, str]:
        """A veth link between a and b; returns (a's address, b's address)."""
        n = len(self.links) + 1
        ea, eb = f"{self.tag}{n}a", f"{self.tag}{n}b"
        na, nb = self.ns(a), self.ns(b)
        self._run("-n", na, "link", "add", ea, "type", "veth", "peer", eb, "netns", nb)
        ips = (f"10.44.{n}.1", f"10.44.{n}.2")
        for space, end, addr in ((na, ea, ips[0]), (nb, eb, ips[1])):
            self._run("-n", space, "addr", "add", f"{addr}/30", "dev", end)
            self._run("-n", space, "link", "set", end, "up")
        self.links[frozenset((a, b))] = (na, ea, nb, eb)
        return ips

    def set_link(self, a: str, b: str, up: bool) -> None:
        """Cut (up=False) or heal the link between a and b, both ends."""
        na, ea, nb, eb = self.links[frozenset((a, b))]
        for space, end in ((na, ea), (nb, eb)):
            self._run("-n", space, "link", "set", end, "up" if up else "down")

    def prefix(self, name: str) -> list[str]:
        """The command prefix that runs a program in ``name``'s namespace."""
        return ["ip", "netns", "exec", self.ns(name)]

    def wait_port(self, name: str, host: str, port: int, timeout_s: float = 15.0) -> None:
        probe = f"exec 3<>/dev/tcp/{host}/{port}"
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            cmd = [*self.prefix(name), "bash", "-c", probe]
            if subprocess.run(cmd, capture_output=True, timeout=5).returncode == 0:
                return
            time.sleep(0.1)
        raise TimeoutError(f"nothing listens on {host}:{port} in namespace {name}")

    def close(self) -> None:
        """Delete every namespace (their veth ends go with them)."""
        for full in self.spaces.values():
            _ip("netns", "del", full)
        self.spaces.clear()
        self.links.clear()

    def _run(self, *args: str) -> None:
        done = _ip(*args)
        if done.returncode != 0:
            raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.decode().strip()}")

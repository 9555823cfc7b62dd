"""What the tests that make their own namespaces need of this machine."""

from __future__ import annotations

import shutil
import subprocess

import pytest


def mount_namespace_works() -> bool:
    """Whether ``unshare -rm`` gives an unprivileged mount namespace where a
    small tmpfs can be mounted (the full-disk tests fill one)."""
    if shutil.which("unshare") is None:
        return False
    return (
        subprocess.run(
            ["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt"],
            capture_output=True,
        ).returncode
        == 0
    )


#: The mark of a test that needs :func:`mount_namespace_works`.
needs_mount_namespace = pytest.mark.skipif(
    not mount_namespace_works(), reason="no unprivileged mount namespace (unshare -rm)"
)

"""Rehearsing an outage: the simulated link of ``modd up --simulate`` (``make
run``) cut and restored on request, for training, without touching a socket
by hand. ``modd up`` gives the SubBroker a rehearsal folder
(``<workdir>/rehearsal``); while the file ``link-cut`` is in it, the SubBroker
drops its link to the PubBroker and does not reconnect, exactly as a radio
outage looks from the base station: the PubBroker keeps archiving, the
windows missed are gaps for *Fill gaps* after the link is restored (the file
removed). ``modd link cut|restore|status`` and the workbench's Monitor
(``/api/drones/<drone>/rehearsal``) write and remove that file.

>>> import tempfile; d = Path(tempfile.mkdtemp())
>>> switch = CutSwitch(d); switch.cut
False
>>> set_cut(d, True); CutSwitch(d, check_s=0).cut
True
"""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path

log = logging.getLogger("modd.subbroker")

FOLDER = "rehearsal"
CUT_FILE = "link-cut"


def set_cut(folder: Path, cut: bool) -> None:
    """Cut (the file made) or restore (removed) the link of the run the folder belongs to."""
    path = folder / CUT_FILE
    if cut:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW, 0o600)
        os.close(fd)
    else:
        path.unlink(missing_ok=True)


def is_cut(folder: Path) -> bool:
    return (folder / CUT_FILE).exists()


class CutSwitch:
    """Whether the link is cut for a rehearsal, read from the folder at most
    every ``check_s`` (the link thread asks at each turn of its loop)."""

    def __init__(self, folder: Path, check_s: float = 0.2) -> None:
        self.folder = folder
        self._check_s = check_s
        self._at = -1e9
        self._cut = False

    @property
    def cut(self) -> bool:
        now = time.monotonic()
        if now - self._at >= self._check_s:
            self._at = now
            was, self._cut = self._cut, is_cut(self.folder)
            if self._cut != was:
                log.warning(
                    "rehearsal: the link is %s",
                    "cut (no frame in or out until it is restored)" if self._cut else "restored",
                )
        return self._cut

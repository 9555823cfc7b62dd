"""No window twice on the wire after a station's kill -9 (issue 44, docs/fleet.md,
"Exactly once at the subscriber"), real processes on loopback: a station router, its
SubBroker (``station`` set, the drone heard by it alone: no standby hears its values),
the C++ PubBroker fed by scenario 1's load, and a viewer counting the **raw** zenoh
samples (no subscriber API in between). The SubBroker is killed with -9 three times
while it delivers, each time restarted; then it fills every subscriber's gaps
(``backfill --gaps``). Before the window journal (window_journal.py), the windows
delivered within the record's 1-s save period before each kill were backfilled again
and reached the viewer twice (0-20 a run); now: none twice, every window of every
epoch there, each equal to the aggregate recomputed from the drone's archive.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fleet.test_fleet import (  # noqa: E402
    Listener,
    assert_every_window,
    backfill,
    identities,
    mesh,
    procs,  # noqa: F401  (the fixture)
    start_subbroker,
    subbroker_toml,
)
from subbroker_harness import (  # noqa: E402
    PUBBROKER,
    check_against_archive,
    free_port,
    model_copy,
    read_archive,
    start_load,
    start_pubbroker,
)

KILLS = 3
LOAD_S = 60
SUBSCRIBERS = ("sub_1", "sub_2", "sub_3", "sub_4", "sub_5", "sub_6", "sub_7")


@pytest.mark.timeout(300)
def test_a_station_killed_while_delivering_sends_no_window_twice(
    tmp_path: Path,
    procs: list[Any],  # noqa: F811
) -> None:
    assert PUBBROKER.exists(), f"{PUBBROKER} is not built: run make build"
    a = mesh(tmp_path, "a")["a"]
    procs.append(a.start())
    link, ingress = free_port(), free_port()
    model = model_copy(tmp_path, "scenario1.modd")
    procs.append(start_pubbroker(tmp_path, model, link, ingress))
    viewer = Listener(a, "modd/usv/sub/*")
    procs.append(viewer)
    config = subbroker_toml(tmp_path, model, link, a, state=str(tmp_path / "st"))
    procs.append(sb := start_subbroker(tmp_path, config, "sb-0"))
    assert sb.wait_log("station a serves usv", 20), sb.log()
    procs.append(load := start_load(tmp_path, model, ingress, LOAD_S))
    for n in range(1, KILLS + 1):
        time.sleep(LOAD_S / (KILLS + 2))
        sb.kill9()  # while it delivers: its record was saved up to 1 s before
        procs.append(sb := start_subbroker(tmp_path, config, f"sb-{n}"))
        assert sb.wait_log("station a serves usv", 20), sb.log()
    load.p.wait(LOAD_S + 60)
    time.sleep(2)
    for sub in SUBSCRIBERS:
        # a 2-s window is due only when it ends before the next epoch: a kill ~1.3 s
        # before the restart's epoch may leave none of them missing (no gap: DONE at once)
        derived = sub in ("sub_1", "sub_2")
        job = backfill(
            a,
            {"op": "start", "subscriber": sub, "gaps": True},
            expect=("RUNNING", "DONE") if derived else "RUNNING",
        )
        assert sb.wait_log(f"backfill {job['id']} for {sub}: DONE", 60), sb.log()[-3000:]
    time.sleep(2)
    values = viewer.values()
    ids = identities(values)
    twice = len(ids) - len(set(ids))
    filled = sum(v.backfilled for v in values)
    print(f"{len(ids)} windows on the wire, {filled} backfilled, {twice} twice")
    assert twice == 0, f"{twice} windows reached the raw subscriber twice"
    assert filled > 0, "the kills left gaps that were filled"
    assert check_against_archive({"a": values}, read_archive(tmp_path / "archive", model)) > 500
    for sub in SUBSCRIBERS[2:]:  # the 0.25-s ones: every window of every epoch
        assert_every_window([v for v in values if v.subscriber == sub], epochs=KILLS + 1)

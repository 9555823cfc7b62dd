"""Live QARTOD flags for the Monitor (liveqc.py): the windows a subscriber
delivers, a spike and a stuck value among them, are flagged as ``ioos_qc``
flags the whole series when called here directly (the oracle); the tests come
from what runs on the drone (its last acknowledged deployment) and the
project's saved dataset metadata."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from ioos_qc import qartod
from modd_backend.db import Store
from modd_backend.hub import SubscriptionHub
from modd_backend.live import LiveRelay
from modd_backend.liveqc import live_tests
from modd_backend.tables import DatasetMetadataVersion, Deployment, ModelVersion, Project

TESTS: dict[str, dict[str, Any]] = {
    "spike_test": {"suspect_threshold": 1.0, "fail_threshold": 3.0},
    "flat_line_test": {"suspect_threshold": 5.0, "fail_threshold": 8.0, "tolerance": 1e-6},
}
T0 = 1_790_000_000 * 10**9


def _series() -> tuple[np.ndarray, np.ndarray]:
    """2 s windows: a gentle wave, a spike at 10, a stuck value from 20 to 31."""
    t = T0 + np.arange(40, dtype=np.int64) * 2 * 10**9
    v = 10 + 0.3 * np.sin(np.arange(40) / 3)
    v[10] += 8.0
    v[20:32] = v[20]
    return t, v


def _oracle(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    inp = np.ma.masked_invalid(v)
    flags = [
        qartod.spike_test(inp=inp, **TESTS["spike_test"]),
        qartod.flat_line_test(inp=inp, tinp=t.astype("datetime64[ns]"), **TESTS["flat_line_test"]),
    ]
    return np.asarray(qartod.qartod_compare(flags))


def test_windows_are_flagged_as_ioos_qc_flags_the_series() -> None:
    hub = SubscriptionHub()
    relay = LiveRelay(hub, "usv", 1000)
    relay.subscribe("sub_temp", {"sub_temp": TESTS})
    relay.subscribe("sub_other", {"sub_temp": TESTS})  # no tests: no flags
    t, v = _series()
    for a, x in zip(t, v, strict=True):
        payload = {"start_ns": int(a) - 2 * 10**9, "end_ns": int(a), "value": float(x), "count": 10}
        hub.on_value("modd/usv/sub/sub_temp", json.dumps(payload).encode())
        hub.on_value("modd/usv/sub/sub_other", json.dumps(payload).encode())
    messages = relay.queue.drain()
    other = [m for m in messages if m["subscriber"] == "sub_other"]
    assert other and all("qc" not in m for m in other)
    # The last word on each window (its flag as the next window revised it).
    shown: dict[int, int] = {}
    for m in messages:
        for at, flag in m.get("qc", []):
            shown[at] = flag
    want = _oracle(t, v)
    # Each window is flagged on a series that ends one window after it (the oracle
    # sees the whole series): the spike's and the flat line's flags agree.
    assert shown[int(t[10])] == want[10] == qartod.QartodFlags.FAIL
    assert [shown[int(a)] for a in t[20:32]] == want[20:32].tolist()
    assert shown[int(t[31])] == qartod.QartodFlags.FAIL  # stuck for 22 s > 8 s
    assert shown[int(t[5])] == want[5] == qartod.QartodFlags.GOOD
    assert [shown[int(a)] for a in t[:-1]] == want[:-1].tolist()
    relay.close()


def test_the_tests_of_what_runs_on_the_drone(tmp_path: Path) -> None:
    store = Store.open(f"sqlite:///{tmp_path / 'store.db'}")
    model = {
        "drone": {
            "name": "usv",
            "sensors": [
                {
                    "name": "ctd",
                    "variables": [{"name": "t", "validMin": -2, "validMax": 40}],
                }
            ],
        },
        "subscribers": [
            {"name": "sub_t", "topic": "usv.ctd.t"},
            {"name": "sub_x", "topic": "usv.imu.x"},
        ],
    }
    with store.session() as db:
        assert live_tests(db, "usv") == {}  # nothing deployed
        db.add(Project(id=1, name="bay", created_by="ana"))
        db.flush()
        db.add(
            ModelVersion(
                project_id=1, revision=1, model_json=json.dumps(model), valid=True, author="ana"
            )
        )
        db.flush()
        db.add(
            Deployment(project_id=1, revision=1, drone="usv", requested_by="ana", status="acked")
        )
        db.commit()
        assert live_tests(db, "usv") == {"sub_t": {"gross_range_test": {"fail_span": [-2, 40]}}}
        qc = {"usv.ctd.t": {"spike_test": {"suspect_threshold": 1}}}
        db.add(
            DatasetMetadataVersion(
                project_id=1, revision=1, metadata_json=json.dumps({"qc": qc}), author="ana"
            )
        )
        db.commit()
        assert live_tests(db, "usv") == {
            "sub_t": {
                "gross_range_test": {"fail_span": [-2, 40]},
                "spike_test": {"suspect_threshold": 1.0},
            }
        }
    store.close()

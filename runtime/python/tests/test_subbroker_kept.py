"""What the SubBroker keeps in its state directory across restarts (kept.py,
docs/subbroker.md "State"): the acknowledged deployment and the dynamic
subscriptions, read back as written; an older file, a torn one, a foreign one."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest
from modd.subbroker.kept import Deployment, StateDir, same_model

MODEL = {"name": "m", "drone": {"name": "usv"}, "layout": {"x": 1}}
SUB = {"name": "d1", "topic": "usv.t", "period_s": "1", "aggregation": "MAX", "owner": "ann"}


def test_a_deployment_is_read_back_as_kept(tmp_path: Path) -> None:
    state = StateDir(tmp_path / "state")
    meta = Deployment.from_request(
        {
            "project_id": 4,
            "revision": 9,
            "nonce": "n" * 200,
            "deployed_by": "ann",
            "revision_note": True,
        }
    ).acked()
    state.save_deployment(MODEL, meta)
    on_disk = json.loads((tmp_path / "state" / "deployed.json").read_text())
    assert on_disk["model"] == MODEL and on_disk["deployment"]["revision"] == 9
    kept = state.load_deployment()
    assert kept is not None
    model, back = kept
    assert model == MODEL and back.source == "kept" and back.resumed_at_ns is not None
    assert (back.project_id, back.revision, back.deployed_by) == (4, 9, "ann")
    assert back.nonce == "n" * 128  # bounded as the request was
    assert back.deployed_at_ns == meta.deployed_at_ns
    assert back.describe().startswith("revision 9 of project 4, deployed at ")


def test_an_older_file_a_torn_one_and_no_directory(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    state = StateDir(tmp_path)
    (tmp_path / "deployed.json").write_text(json.dumps(MODEL))  # the bare model, as before
    kept = state.load_deployment()
    assert kept is not None and kept[0] == MODEL and kept[1].revision is None
    (tmp_path / "deployed.json").write_text('{"model": {"na')
    with caplog.at_level(logging.ERROR, logger="modd.subbroker"):
        assert state.load_deployment() is None
    assert "cannot be used" in caplog.text and "deployed.json" in caplog.text
    assert not (tmp_path / "deployed.json").exists()  # set aside, kept for a look
    assert len(list(tmp_path.glob("deployed.json.bad-*"))) == 1
    nowhere = StateDir(None)
    nowhere.save_deployment(MODEL, Deployment.configured())
    assert nowhere.load_deployment() is None and nowhere.load_dynamic() == []


def test_dynamic_subscriptions_keep_only_whole_entries(tmp_path: Path) -> None:
    state = StateDir(tmp_path)
    state.save_dynamic([SUB])
    assert state.load_dynamic() == [SUB]
    broken = {**SUB, "owner": 3}
    (tmp_path / "dynamic.json").write_text(json.dumps({"subscriptions": [SUB, broken, "x"]}))
    assert state.load_dynamic() == [SUB]


def test_the_layout_does_not_make_a_model_differ() -> None:
    assert same_model(MODEL, {**MODEL, "layout": {"x": 2}})
    assert not same_model(MODEL, {**MODEL, "name": "other"})

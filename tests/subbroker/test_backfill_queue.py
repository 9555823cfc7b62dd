"""Backfill as a queue and across configs, end to end (issue 28), real processes on
loopback. Oracle: the PubBroker's archive read by the official `mcap` package.

- 13 concurrent `modd backfill --gaps` (one per subscriber of scenario 2) after an
  outage the link cannot repair all end DONE, every missed window delivered once with
  the archive's value, within the paced time docs/subbroker.md predicts.
- After a SubBroker outage (stopped, then started again: a new config epoch), after a
  PubBroker restart and after a link outage followed by a redeploy, `--gaps` fills the
  windows of the earlier config.

The outage lasts MODD_BACKFILL_CUT_S seconds (4 in `make test`).
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import request
from modd.subbroker.payload import DeliveredValue
from subbroker_harness import (
    PYTHON,
    Blackhole,
    Proc,
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    shared_credentials,
    signed,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)
from test_backfill import check_complete, listen, run_cli, wait_live

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

CUT_S = float(os.environ.get("MODD_BACKFILL_CUT_S", "4"))
RATE_BPS = 3600  # the emulated radio of the issue
SECOND = 1_000_000_000


def with_budget(path: Path) -> Path:
    doc = json.loads(path.read_text())
    doc.setdefault("link", {})["rateBps"] = RATE_BPS
    path.write_text(json.dumps(doc))
    return path


def cli_at_once(zport: int, names: list[str]) -> dict[str, tuple[int, str, str]]:
    env = {**os.environ, "MODD_ZENOH_CREDENTIALS": str(shared_credentials().cred_file("backend"))}
    procs = {
        n: subprocess.Popen(
            [
                str(PYTHON),
                "-m",
                "modd_model.cli",
                "backfill",
                "--drone",
                "usv",
                "--connect",
                f"tcp/127.0.0.1:{zport}",
                "--subscriber",
                n,
                "--gaps",
                "--json",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        for n in names
    }
    out = {}
    deadline = time.monotonic() + 120  # all of them (on main: 5 ended, 8 stalled > 5 min)
    for n, p in procs.items():
        try:
            o, e = p.communicate(timeout=max(1.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            p.kill()
            o, e = p.communicate()
        out[n] = (p.returncode, o, e)
    return out


def merged(collectors: list[tuple[Any, int]]) -> dict[str, list[DeliveredValue]]:
    """What each listener got while its SubBroker ran (delivered before ``until_ns``)."""
    values: dict[str, list[DeliveredValue]] = {}
    for got, until_ns in collectors:
        for name, vals in got.snapshot().items():
            values.setdefault(name, []).extend(v for v in vals if v.delivered_ns < until_ns)
    for vals in values.values():
        vals.sort(key=lambda v: v.end_ns)
    return values


def check_epochs(values: list[DeliveredValue], period_ns: int, until_ns: int) -> None:
    """Every window once up to ``until_ns``, config after config: each config's windows
    contiguous on its grid, and none missing where one config gives way to the next."""
    mine = [v for v in values if v.end_ns <= until_ns]
    keys = [(v.config_id, v.end_ns) for v in mine]
    assert len(keys) == len(set(keys)), "a window delivered twice"
    for a, b in zip(mine, mine[1:], strict=False):
        if a.config_id == b.config_id:
            assert b.end_ns - a.end_ns == period_ns, f"windows missing after {a}"
        else:  # the earlier config's windows up to the next epoch, not one missing
            assert 0 <= b.start_ns - a.end_ns < period_ns, (a, b)


def test_thirteen_concurrent_gaps_all_done(tmp_path: Path, zenoh_client: Any) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    model = with_budget(model_copy(tmp_path, "scenario2.modd"))
    names = [f"sub_{i}" for i in range(1, 14)]
    pb = start_pubbroker(tmp_path, model, link, ingress)
    proxy = Blackhole(link)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, proxy.port, zport))
    load = None
    try:
        wait_port(zport, 60)
        got = listen(zenoh_client, zport)
        assert sb.wait_log("running", 60)
        load = start_load(tmp_path, model, ingress, CUT_S + 180)
        wait_live(got, "sub_13", 0)
        proxy.drop()  # the link goes; TCP cannot repair what it missed
        time.sleep(2 * CUT_S)
        proxy.restore()
        assert sb.wait_log("resuming config 1", 30), sb.log()
        wait_live(got, "sub_13", time.time_ns())
        asked = time.time_ns() - SECOND
        t0 = time.monotonic()
        results = cli_at_once(zport, names)
        took = time.monotonic() - t0
    finally:
        with processes(*(x for x in (pb, sb, load) if x is not None)):
            proxy.close()
    figures = {}
    for name, (code, out, err) in results.items():
        assert code == 0, (name, out, err[-500:], sb.log()[-3000:])
        figures[name] = json.loads(out.strip().splitlines()[-1])
        assert figures[name]["duplicates"] == 0
        assert figures[name]["windows"] >= 2 * CUT_S - 1.5, (name, figures[name])
    values = got.snapshot()
    for name in names:
        check_complete(values[name], SECOND, asked)  # every window once, none missing
        assert sum(v.backfilled for v in values[name]) == figures[name]["windows"]
    archive = read_archive(tmp_path / "archive", model)
    assert check_against_archive({n: values[n] for n in names}, archive) > 13 * 2 * CUT_S
    # the docs' prediction: the bytes at the spare budget, plus one round trip per run
    # (a loaded machine: a generous second per job for the CLI's start and polling)
    spare = RATE_BPS - 19 * 8  # the plan's live bytes/s is well under 10 B per stream
    total = sum(f["bytes"] for f in figures.values())
    assert took < total / spare + 13 * 1.0 + 30, (took, total, figures)
    print(
        f"13 concurrent backfills: {sum(f['windows'] for f in figures.values())} windows,"
        f" {total} B in {took:.1f} s with the CLIs' start-up, the longest job"
        f" {max(f['seconds'] for f in figures.values()):.2f} s in the SubBroker"
    )


def gaps_cli(zport: int, sb: Proc) -> dict[str, Any]:
    code, out, err = run_cli(zport, "--subscriber", "sub_5", "--gaps", "--json")
    assert code == 0, (out, err, sb.log()[-3000:])
    fig: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    assert fig["duplicates"] == 0, fig
    return fig


def redeployed(model: Path) -> dict[str, Any]:
    """The model with sub_6 changed (MAX to AVERAGE): a new config, sub_5 as it was."""
    doc = json.loads(model.read_text())
    for sub in doc["subscribers"]:
        if sub["name"] == "sub_6":
            sub["aggregation"] = "AVERAGE"
    return signed({"text": json.dumps(doc), "format": "json"})


def test_gaps_fill_the_earlier_configs_after_restarts(tmp_path: Path, zenoh_client: Any) -> None:
    """Config 1 → SubBroker outage → config 2 → PubBroker restart → config 3 → link
    outage → redeploy → config 4: each `--gaps` fills the windows of the earlier one."""
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp_path, "scenario1.modd")
    state = tmp_path / "state"
    proxy = Blackhole(link)
    config = subbroker_config(tmp_path, model, proxy.port, zport, state_dir=state)
    pb = start_pubbroker(tmp_path, model, link, ingress)
    procs: list[Proc] = [pb]
    first = second = None
    try:
        sb = start_subbroker(tmp_path, config)
        procs.append(sb)
        wait_port(zport, 60)
        first = listen(zenoh_client, zport)
        assert sb.wait_log("config 1 running", 60)
        procs.append(start_load(tmp_path, model, ingress, 3 * CUT_S + 120))
        wait_live(first, "sub_5", 0)
        first_ns = time.time_ns()
        # 1. a SubBroker outage: stopped, started again (a new CONFIG, a new epoch)
        sb.stop()
        stopped_ns = time.time_ns()
        time.sleep(CUT_S)
        sb = start_subbroker(tmp_path, config, tag="sb2")
        procs.append(sb)
        wait_port(zport, 60)
        second = listen(zenoh_client, zport)
        assert sb.wait_log("config 2 running", 60), sb.log()
        wait_live(second, "sub_5", time.time_ns())
        asked = time.time_ns() - SECOND
        fig = gaps_cli(zport, sb)
        assert fig["windows"] >= (CUT_S - 1.5) * 4, fig
        both = [(first, stopped_ns), (second, 1 << 63)]
        check_epochs([v for v in merged(both)["sub_5"] if v.end_ns > first_ns], 250_000_000, asked)
        # 2. a PubBroker restart: the SubBroker stays, the drone runs a new config
        pb.stop()
        time.sleep(1)
        pb = start_pubbroker(tmp_path, model, link, ingress, tag="pb2")
        procs.append(pb)
        procs.append(start_load(tmp_path, model, ingress, CUT_S + 120, tag="load2"))
        assert sb.wait_log("config 3 running", 60), sb.log()
        wait_live(second, "sub_5", time.time_ns())
        asked = time.time_ns() - SECOND
        fig2 = gaps_cli(zport, sb)
        assert fig2["windows"] >= 2, fig2
        # 3. a link outage under config 3, then a redeploy (config 4) before anyone fills it
        proxy.drop()
        time.sleep(CUT_S)
        proxy.restore()
        assert sb.wait_log("resuming config 3", 30), sb.log()
        session = zenoh_client(zport)
        reply = request(session, "modd/usv/deploy", redeployed(model))
        assert reply["status"] == "ACKED" and reply["config_id"] == 4, reply
        wait_live(second, "sub_5", time.time_ns())
        asked = time.time_ns() - SECOND
        fig3 = gaps_cli(zport, sb)
        assert fig3["windows"] >= (CUT_S - 1.5) * 4, fig3
    finally:
        with processes(*procs):
            proxy.close()
    assert first is not None and second is not None
    values = merged([(first, stopped_ns), (second, 1 << 63)])["sub_5"]
    check_epochs([v for v in values if v.end_ns > first_ns], 250_000_000, asked)
    back = [v for v in values if v.backfilled]  # the mission's first windows may be too
    assert len(back) == fig["windows"] + fig2["windows"] + fig3["windows"]
    assert {v.config_id for v in back} == {1, 2, 3}  # the earlier configs' windows
    assert check_against_archive({"sub_5": back}, read_archive(tmp_path / "archive", model))
    print(
        f"after a {CUT_S:.0f} s SubBroker outage: {fig['windows']} windows filled in"
        f" {fig['seconds']:.1f} s; after a PubBroker restart: {fig2['windows']} in"
        f" {fig2['seconds']:.1f} s; after a link outage and a redeploy: {fig3['windows']} in"
        f" {fig3['seconds']:.1f} s"
    )

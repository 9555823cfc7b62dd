"""Config file, payload, deploy requests, dynamic registry, planning, keys."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from modd.link.frames import Aggregation, ValueType
from modd.subbroker.config import ConfigError, config_from_model, load_config, resolve_key
from modd.subbroker.deploy import parse_request
from modd.subbroker.dynamic import DynamicSubscriptions
from modd.subbroker.fanout import FanOut
from modd.subbroker.keys import deploy_key, status_key, sub_key, subscribe_key
from modd.subbroker.payload import DeliveredValue
from modd.subbroker.planning import config_for, plan_for
from modd.zenoh_session import ZenohSettings
from modd_model import load_model
from modd_plan.windows import split_window

S1 = Path(__file__).resolve().parents[3] / "metamodel" / "examples" / "scenarios" / "scenario1.modd"


def test_keys() -> None:
    assert sub_key("usv", "sub_1") == "modd/usv/sub/sub_1"
    assert status_key("usv") == "modd/usv/status"
    assert deploy_key("usv") == "modd/usv/deploy"
    assert subscribe_key("usv") == "modd/usv/subscribe"
    with pytest.raises(ValueError, match="identifier"):
        sub_key("usv", "a/*")


def test_config_file_full(tmp_path: Path) -> None:
    (tmp_path / "m.modd").write_text(S1.read_text())
    cfg_file = tmp_path / "sb.toml"
    cfg_file.write_text("""
model = "m.modd"
state_dir = "state"
[link]
endpoint = "127.0.0.1:9000"
key = "env:K"
backoff_max_s = 2
[zenoh]
mode = "client"
connect = ["tcp/127.0.0.1:7448"]
listen = []
[zenoh.settings]
"transport/auth/usrpwd/user" = "base"
[delivery]
tcp = false
status_period_s = 0.5
""")
    cfg = load_config(cfg_file)
    assert cfg.drone == "usv" and cfg.endpoint == ("127.0.0.1", 9000) and cfg.key_ref == "env:K"
    assert cfg.link.backoff_max_s == 2.0 and not cfg.delivery.tcp
    assert cfg.state_dir == tmp_path / "state"
    ins = cfg.zenoh.inserts()
    assert ins["mode"] == '"client"' and ins["connect/endpoints"] == '["tcp/127.0.0.1:7448"]'
    assert ins["transport/auth/usrpwd/user"] == '"base"'
    assert ins["scouting/multicast/enabled"] == "false" and ins["scouting/delay"] == "0"


def test_defaults_from_model() -> None:
    cfg = config_from_model(S1)
    assert cfg.endpoint == ("127.0.0.1", 7171)
    assert cfg.key_ref == "env:MODD_LINK_KEY"
    assert cfg.zenoh.inserts()["listen/endpoints"] == '["tcp/127.0.0.1:7447"]'
    assert cfg.zenoh.inserts()["mode"] == '"router"'  # authenticating its clients


@pytest.mark.parametrize(
    "body,message",
    [
        ('model = "m.modd"\nbogus = 1', "unknown key 'bogus'"),
        ('drone = "usv"', "missing key 'model'"),
        ('model = "m.modd"\n[link]\nendpoint = "nope"', "link.endpoint: expected host:port"),
        ('model = "m.modd"\n[link]\nping_count = "3"', "link.ping_count: expected int"),
        ('model = "m.modd"\n[zenoh]\nmode = "mesh"', "zenoh mode 'mesh'"),
        ('model = "m.modd"\ndrone = "uav"', "drone 'uav' but the model is for 'usv'"),
        ('model = "missing.modd"', "missing.modd"),
        ("model = [", "sb.toml"),
    ],
)
def test_config_errors_name_file_and_key(tmp_path: Path, body: str, message: str) -> None:
    (tmp_path / "m.modd").write_text(S1.read_text())
    (tmp_path / "sb.toml").write_text(body)
    with pytest.raises(ConfigError) as err:
        load_config(tmp_path / "sb.toml")
    assert message in str(err.value)


def test_resolve_key(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SB_KEY", "k1-of-16-bytes-at-least")
    assert resolve_key("env:SB_KEY") == b"k1-of-16-bytes-at-least"
    (tmp_path / "k").write_bytes(b"k2-of-16-bytes-at-least\n")
    assert resolve_key(f"file:{tmp_path / 'k'}") == b"k2-of-16-bytes-at-least"
    monkeypatch.setenv("SB_SHORT", "k")
    with pytest.raises(ConfigError, match="at least 16"):  # a 1-byte key was accepted
        resolve_key("env:SB_SHORT")
    for ref in ("env:SB_NOPE", f"file:{tmp_path / 'none'}", "k3"):
        with pytest.raises(ConfigError, match="link key"):
            resolve_key(ref)
    # key files: regular, bounded, no final symlink (docs/security.md, "Local surfaces")
    (tmp_path / "big").write_bytes(b"x" * (1 << 20))
    (tmp_path / "link").symlink_to(tmp_path / "k")
    for ref, why in (
        ("file:/dev/zero", "not a regular file"),
        (f"file:{tmp_path}/big", "bytes"),
        (f"file:{tmp_path}/link", "link"),
    ):
        with pytest.raises(ConfigError, match=why):
            resolve_key(ref)


def test_payload_roundtrip_and_versions() -> None:
    v = DeliveredValue("s", "d.s.x", "ALL", "0.25", "NONE", 3, 9, 1, 2, [1.0, 2.0], 2, 5)
    assert DeliveredValue.from_json(v.to_json()) == v
    assert json.loads(v.to_json())["v"] == 1
    with pytest.raises(ValueError, match="version"):
        DeliveredValue.from_dict({**v.to_dict(), "v": 2})
    with pytest.raises(ValueError, match="lacks"):
        DeliveredValue.from_json(b'{"subscriber": "s"}')
    assert split_window("COUNT", None) == (0, 0)
    assert split_window("ALL", [1, 2]) == ([1, 2], 2)
    assert split_window("MAX", 3.5) == (3.5, None)


def test_zenoh_settings_reject_bad_values() -> None:
    with pytest.raises(ValueError, match="unknown key"):
        ZenohSettings.from_mapping({"lisen": []})
    with pytest.raises(ValueError, match="list of endpoints"):
        ZenohSettings.from_mapping({"listen": "tcp/127.0.0.1:1"})


def test_deploy_request_parsing() -> None:
    text = S1.read_text()
    ok = parse_request(json.dumps({"text": text, "timeout_s": 3}).encode(), "usv")
    assert ok.model is not None and ok.timeout_s == 3
    as_json = parse_request(json.dumps({"model": ok.model}).encode(), "usv")
    assert as_json.model == ok.model
    assert parse_request(b"not json", "usv").reply["status"] == "ERROR"
    assert parse_request(b"[]", "usv").reply["status"] == "ERROR"
    assert parse_request(b"{}", "usv").reply["status"] == "ERROR"
    assert parse_request(b'{"text": "x", "timeout_s": -1}', "usv").reply["status"] == "ERROR"
    wrong = parse_request(json.dumps({"text": text}).encode(), "uav")
    assert wrong.reply["status"] == "REJECTED" and "'usv'" in wrong.reply["reason"]
    bad = parse_request(
        json.dumps({"text": text.replace("AVERAGE", "AVERAGED", 1), "filename": "m.modd"}).encode(),
        "usv",
    )
    assert bad.reply["status"] == "INVALID"
    diag = bad.reply["diagnostics"][0]
    assert diag["severity"] == "error" and "m.modd" in json.dumps(diag)


def test_planning_config_matches_plan_contract() -> None:
    model = load_model(S1)
    plan = plan_for(model, rtt_s=0.0001)
    cfg = config_for(plan, 7, 30)
    assert cfg.config_id == 7 and cfg.status_period_s == 30
    assert [t.name for t in cfg.topics] == [t.name for t in plan.topics]
    assert [t.buffer_size for t in cfg.topics] == [28, 28, 6]
    assert all(t.type == ValueType.FLOAT32 and t.period_us == 40_000 for t in cfg.topics)
    assert [(s.topic, s.aggregation, s.period_us) for s in cfg.streams] == [
        (0, Aggregation.AVERAGE, 250_000),
        (1, Aggregation.AVERAGE, 250_000),
        (2, Aggregation.MIN, 250_000),
        (2, Aggregation.MAX, 250_000),
    ]
    slow = plan_for(model, rtt_s=2.0)  # a slow link loosens the delay cap
    assert slow.constants.ping_s == 2
    with pytest.raises(ValueError):
        config_for(plan, 0)


class _Running:
    def __init__(self) -> None:
        self.plan = plan_for(load_model(S1), None)
        self.fanout = FanOut([s.stream for s in self.plan.sent_streams])

    def route(self, stream, sources, subscriber):  # type: ignore[no-untyped-def]
        self.fanout.route(stream, sources, subscriber)

    def unroute(self, subscriber: str) -> bool:
        return self.fanout.unroute(subscriber)


def test_dynamic_registry() -> None:
    reg = DynamicSubscriptions("usv", lambda: {"sub_1"})
    run = _Running()
    ask = {"topic": "usv.accelerometer.accel_x", "period_s": "4.0", "aggregation": "AVERAGE"}
    assert reg.handle(ask, None)["status"] == "NOT_AVAILABLE"
    ok = reg.handle(ask, run)
    assert ok["status"] == "ACCEPTED" and ok["key"] == f"modd/usv/sub/{ok['subscriber']}"
    assert ok["derived_from"] == "usv.accelerometer.accel_x/AVERAGE/0.25" and ok["factor"] == 16
    assert run.fanout.routes()["usv.accelerometer.accel_x/AVERAGE/4.0"] == (ok["subscriber"],)
    named = reg.handle({**ask, "period_s": 1, "subscriber": "mine"}, run)
    assert named["status"] == "ACCEPTED" and named["subscriber"] == "mine"
    assert reg.handle({**ask, "subscriber": "mine"}, run)["status"] == "ERROR"
    assert reg.handle({**ask, "subscriber": "sub_1"}, run)["status"] == "ERROR"
    no = reg.handle({**ask, "aggregation": "MIN"}, run)
    assert no["status"] == "NOT_AVAILABLE" and "AVERAGE every 0.25 s" in no["reason"]
    no = reg.handle({**ask, "period_s": "0.3"}, run)
    assert no["status"] == "NOT_AVAILABLE" and "multiple" in no["reason"]
    pct = reg.handle({**ask, "aggregation": "PERCENTILE(95)"}, run)  # needs ALL: not sent
    assert (
        pct["status"] == "NOT_AVAILABLE" and "PERCENTILE(95) every 4.0 s needs ALL" in pct["reason"]
    )
    bare = reg.handle({**ask, "aggregation": "PERCENTILE"}, run)
    assert bare["status"] == "NOT_AVAILABLE" and "PERCENTILE(p)" in bare["reason"], bare
    assert reg.handle({"topic": "x"}, run)["status"] == "ERROR"
    assert reg.handle({"action": "dance"}, run)["status"] == "ERROR"
    assert len(reg.handle({"action": "list"}, run)["subscriptions"]) == 2
    assert reg.handle({"action": "cancel", "subscriber": "mine"}, run)["status"] == "CANCELLED"
    assert "mine" not in str(run.fanout.routes())
    assert reg.handle({"action": "cancel", "subscriber": "mine"}, run)["status"] == "ERROR"
    assert reg.names() == [ok["subscriber"]]


def test_queries_bounded_before_parsing() -> None:
    from modd.subbroker.request import MAX_DEPLOY_BYTES, MAX_SMALL_BYTES, read_request

    deep = b"[" * 100_000 + b"]" * 100_000
    for payload, bound, words in (
        (deep, MAX_SMALL_BYTES * 10, "nested"),
        (b" " * (MAX_SMALL_BYTES + 1), MAX_SMALL_BYTES, "bytes"),
        (b"[1]", MAX_SMALL_BYTES, "object"),
        (b"{", MAX_SMALL_BYTES, "not JSON"),
    ):
        request, problem = read_request(payload, bound)
        assert request is None and problem is not None and words in problem, problem
    assert parse_request(deep, "usv").reply["status"] == "ERROR"
    assert "nested" in parse_request(deep, "usv").reply["reason"]
    huge = b" " * (MAX_DEPLOY_BYTES + 1)
    assert "bytes" in parse_request(huge, "usv").reply["reason"]

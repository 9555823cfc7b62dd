"""The fleet's pieces without processes (docs/fleet.md): the mesh's settings and access
control, the serving station's election, a station's name in the configuration."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, cast

import modd.subscriber
import pytest
from modd.subbroker.config import ConfigError, load_config
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix
from modd.subbroker.serving import Election
from modd.subscriber import Subscription
from modd.zenoh_auth import CredentialStore, acl
from modd.zenoh_mesh import STATION, Mesh, station_acl
from modd.zenoh_session import ZenohSettings, secured

MODEL = Path(__file__).resolve().parents[3] / "metamodel" / "examples" / "scenarios"


def test_a_mesh_table_gives_the_id_and_connects_to_every_peer() -> None:
    z = ZenohSettings.from_mapping(
        {"mode": "router", "mesh": {"id": "a1", "peers": {"b2": "tcp/127.0.0.2:7447"}}}
    )
    inserts = z.inserts()
    assert json.loads(inserts["id"]) == "a1"
    assert json.loads(inserts["connect/endpoints"]) == ["tcp/127.0.0.2:7447"]


@pytest.mark.parametrize(
    ("mesh", "said"),
    [
        ({"id": "a1", "peers": {"a1": "tcp/x:1"}}, "this station's own id"),
        ({"id": "zz"}, "not a zenoh id"),
        ({"id": "a1", "peers": {"b2": 7447}}, "zenoh.mesh.peers.b2: expected an endpoint"),
        ({"id": "a1", "port": 1}, "unknown key 'port'"),
    ],
)
def test_a_bad_mesh_table_is_refused_with_its_place(mesh: dict[str, object], said: str) -> None:
    with pytest.raises(ValueError, match=said):
        Mesh.from_mapping(mesh)


def test_a_station_lets_its_peers_in_by_user_and_by_zenoh_id(tmp_path: Path) -> None:
    store = CredentialStore(tmp_path / "cred")
    z = ZenohSettings(
        mode="router", listen=("tcp/127.0.0.1:0",), mesh=Mesh("a1", {"b2": "tcp/h:1"})
    )
    got = secured(z, store, "station", None)
    assert got.credentials is not None and got.credentials.user == STATION
    assert (tmp_path / "cred" / "station.cred").exists()
    assert any(line.startswith("station:") for line in store.dictionary.read_text().splitlines())
    rules = got.access_control
    assert rules is not None
    subjects = {s["id"]: s for s in rules["subjects"]}
    assert subjects["station_user"]["usernames"] == ["station"]
    assert subjects["station_peers"]["zids"] == ["b2"]
    # the drones' own rules are untouched: a station adds a policy, widens none
    assert rules["policies"][:3] == acl(None)["policies"]
    assert station_acl(acl(None), ())["subjects"][-1]["id"] == "station_user"


def test_a_store_without_a_mesh_makes_no_station_identity(tmp_path: Path) -> None:
    store = CredentialStore(tmp_path / "cred").ensure()
    assert not (tmp_path / "cred" / "station.cred").exists()
    assert "station:" not in store.dictionary.read_text()


def test_the_first_candidate_serves_the_next_waits_its_rank() -> None:
    a, b = Election("a", grace_s=2.0, settle_s=1.0), Election("b", grace_s=2.0, settle_s=1.0)
    a.candidates = b.candidates = {"a", "b"}
    assert (a.decide(0.0), b.decide(0.0)) == (False, False)  # the tokens settle
    assert (a.decide(1.0), b.decide(1.0)) == (True, False)
    assert b.decide(3.0)  # a never came up (it does not hear the drone): b tries


def test_after_a_partition_the_first_in_name_order_keeps_the_drone() -> None:
    a, b = Election("a"), Election("b")
    a.up = b.up = True
    a.serving = b.serving = {"a", "b"}
    assert a.decide(0.0) and not b.decide(0.0)


def test_a_station_that_serves_goes_on_while_no_other_does() -> None:
    b = Election("b")
    b.candidates = {"a", "b"}
    b.up = True
    assert b.decide(0.0)  # a came back: b keeps the drone (no handover back and forth)


def test_a_station_name_must_be_an_identifier(tmp_path: Path) -> None:
    cfg = tmp_path / "sb.toml"
    cfg.write_text(f'model = "{MODEL / "scenario1.modd"}"\nstation = "a/b"\n')
    with pytest.raises(ConfigError, match="station 'a/b' is not an identifier"):
        load_config(cfg)
    cfg.write_text(f'model = "{MODEL / "scenario1.modd"}"\nstation = "shore"\n')
    assert load_config(cfg).station == "shore"


class _Payload:
    def __init__(self, data: bytes) -> None:
        self.data = data

    def to_bytes(self) -> bytes:
        return self.data


class _Sample:
    def __init__(self, data: bytes) -> None:
        self.payload = _Payload(data)


@pytest.fixture(autouse=True)
def _plain_subscriber(monkeypatch: pytest.MonkeyPatch) -> None:
    """The fake session below stands for zenoh's: the Subscription declares a plain
    subscriber on it (zenoh's advanced one takes a real session only)."""
    monkeypatch.setattr(
        modd.subscriber, "values_subscriber", lambda s, key, cb: s.declare_subscriber(key, cb)
    )


class _Session:
    """What a Subscription asks of a zenoh session: one subscriber, its callback kept."""

    def declare_subscriber(self, key: str, callback: Any) -> Any:
        self.callback = callback
        return self

    def undeclare(self) -> None:
        pass


def test_a_subscriber_gets_a_window_once_whichever_station_sent_it() -> None:
    head = StreamPayload("usv.a.z", "MIN", "1", "M", 1, ("usv", 10**18, 10**9))
    line = subscriber_prefix("s") + head.tail(1, 10**18 + 10**9, 10**18 + 2 * 10**9, 1.5, None, 7)
    again = line.replace(b'"delivered_ns":7', b'"delivered_ns":9')  # another station's send
    old = subscriber_prefix("s") + StreamPayload("usv.a.z", "MIN", "1", "M", 1).tail(
        1, 0, 10**9, 2.5, None, 7
    )
    session = _Session()
    sub = Subscription(cast(Any, session), "modd/usv/sub/s")
    for data in (line, again, old, old):
        session.callback(_Sample(data))
    got = [sub.get(0.1), sub.get(0.1), sub.get(0.1), sub.get(0.1)]
    assert [v.value if v else None for v in got] == [1.5, 2.5, 2.5, None]
    assert sub.duplicates == 1  # a payload without identity (an older SubBroker) is kept


def _repeats() -> list[dict[str, Any]]:
    vectors = MODEL.parents[2] / "contracts" / "vectors" / "delivered_value.json"
    cases: list[dict[str, Any]] = json.loads(vectors.read_text())["repeats"]["sequence"]
    return cases


def test_the_subscriber_api_passes_each_window_once() -> None:
    session = _Session()
    got: list[bytes] = []
    sub = Subscription(
        cast(Any, session), "modd/*/sub/*", callback=lambda v: got.append(v.to_json())
    )
    for case in _repeats():
        session.callback(_Sample(case["line"].encode()))
    assert got == [c["line"].encode() for c in _repeats() if c["first"]]
    assert sub.duplicates == sum(not c["first"] for c in _repeats())


def test_latest_is_the_newest_live_value_whatever_comes_late() -> None:
    """``Subscription.latest``: a backfilled window, older or newer, never becomes it;
    a live one newer than it does (each window once: the identity differs)."""

    def win(k: int, value: float, backfilled: bool = False) -> DeliveredValue:
        return DeliveredValue(
            "s", "t", "LAST", "1", "M", 1, k, (k - 1) * 10**9, k * 10**9, value, None, 1,
            backfilled, "usv", 5, k + (1000 if backfilled else 0),
        )  # fmt: skip

    lasts: list[float | None] = []
    session = _Session()
    sub = Subscription(cast(Any, session), "modd/usv/sub/s", lambda v: None)
    assert sub.latest is None
    for v in (win(1, 1.0), win(9, 9.0), win(3, -3.0, True), win(12, -12.0, True), win(10, 10.0)):
        session.callback(_Sample(v.to_json()))
        lasts.append(None if sub.latest is None else sub.latest.value)
    assert lasts == [1.0, 9.0, 9.0, 9.0, 10.0]

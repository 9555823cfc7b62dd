"""The generated broker configs are the files the runtime really reads: the
SubBroker's own loader accepts the generated TOML (the PubBroker binary reads
its JSON in test_cpp_driver_e2e.py)."""

from __future__ import annotations

import json
from pathlib import Path

from modd.subbroker.config import load_config
from modd_gen import generate, write_artifacts
from modd_model import load_model

EXAMPLES = Path(__file__).resolve().parents[2] / "metamodel" / "examples"


def test_generated_subbroker_config_loads(scenarios_dir: Path, tmp_path: Path) -> None:
    model = load_model(scenarios_dir / "scenario1.modd")
    write_artifacts(tmp_path, generate(model, "operator"))
    cfg = load_config(tmp_path / "operator" / "subbroker.toml")
    assert cfg.drone == "usv"
    assert cfg.model == model
    assert cfg.endpoint == ("127.0.0.1", 7171)
    assert cfg.key_ref == "env:MODD_LINK_KEY"
    assert cfg.zenoh.listen == ("tcp/127.0.0.1:7447",)


def test_pubbroker_config_has_planned_buffer_sizes(scenarios_dir: Path, tmp_path: Path) -> None:
    model = load_model(scenarios_dir / "scenario1.modd")
    write_artifacts(tmp_path, generate(model, "operator"))
    config = json.loads((tmp_path / "operator" / "pubbroker.json").read_text())
    assert {t["name"]: t["buffer_size"] for t in config["topics"]} == {
        "usv.accelerometer.accel_x": 28,
        "usv.accelerometer.accel_y": 28,
        "usv.accelerometer.accel_z": 6,
    }
    assert config["link"] == {"host": "127.0.0.1", "port": 7171, "key": "env:MODD_LINK_KEY"}
    assert config["archive"]["dir"] == "/tmp/modd/logs"


def test_toml_writer_round_trips_hostile_strings() -> None:
    import tomllib

    from modd_gen.tomlwriter import dumps

    doc = {
        "a": 'x"\n[zenoh]\nlisten = ["tcp/0.0.0.0:1"]\n#\\',
        "b": "\x00\x1f\x7f\t\r µ 米 🚁",
        "n": 3,
        "t": True,
        "f": 0.5,
        "l": ["p\nq", "r"],
        "zenoh": {"mode": "peer", "weird key\n": "v", "sub": {"k": "\u2028"}},
    }
    assert tomllib.loads(dumps(doc)) == doc


def test_campaign_station_configs_load_as_one_mesh(scenarios_dir: Path, tmp_path: Path) -> None:
    """``--station``: one SubBroker configuration per station, read by the SubBroker's own
    loader: each names its station, is a router, and dials every other station that has
    an endpoint; the one behind a cellular link is dialled by none (docs/operations.md)."""
    from modd_gen.targets.stations import artifacts, parse_station

    model = load_model(scenarios_dir / "scenario1.modd")
    given = ["shore=tcp/shore.example:7447", "boat", "cliff=tcp/cliff.example:7448"]
    stations = [parse_station(t) for t in given]
    write_artifacts(tmp_path, [*generate(model, "operator"), *artifacts(model, stations)])
    cfgs = {
        s.name: load_config(tmp_path / "operator" / "stations" / s.name / "subbroker.toml")
        for s in stations
    }
    zid = {s.name: s.zid for s in stations}
    assert len(set(zid.values())) == 3
    for name, cfg in cfgs.items():
        assert cfg.station == name and cfg.model == model and cfg.zenoh.mode == "router"
        mesh = cfg.zenoh.mesh
        assert mesh is not None and mesh.station == zid[name]
        want = {
            zid[o]: e
            for o, e in (("shore", "tcp/shore.example:7447"), ("cliff", "tcp/cliff.example:7448"))
            if o != name
        }
        assert dict(mesh.peers) == want, name
    assert cfgs["cliff"].zenoh.listen == ("tcp/0.0.0.0:7448",)


def test_campaign_stations_get_a_router_and_a_subbroker_per_vehicle(tmp_path: Path) -> None:
    """A model with a campaign: per station, the router's ``station.toml`` (read by
    ``modd.station``'s loader: the mesh as for one drone) and each vehicle's SubBroker
    (read by its loader: a client of that router, the vehicle's own model beside it,
    drone name, state, link and key), laid out as the station's /etc/modd. (Run as they are:
    tests/fleet/test_fleet_generated.py.)"""
    from modd.station import read_config
    from modd_gen.targets.stations import artifacts, parse_station
    from modd_model.campaign import expand

    model = load_model(EXAMPLES / "campaign.modd")
    stations = [parse_station(t) for t in ("shore=tcp/shore.example:7447", "boat")]
    names = [p.path for p in artifacts(model, stations)]
    assert len(names) == len(set(names))
    write_artifacts(tmp_path, [*generate(model, "operator"), *artifacts(model, stations)])
    fleet = expand(model)
    top = tmp_path / "operator" / "stations"
    zid = {s.name: s.zid for s in stations}
    for s in stations:
        router = read_config(top / s.name / "station.toml")
        assert router.mesh is not None and router.mesh.station == zid[s.name]
        others = {"shore": {}, "boat": {zid["shore"]: "tcp/shore.example:7447"}}
        assert dict(router.mesh.peers) == others[s.name]
        assert router.listen == ("tcp/0.0.0.0:7447",)
        assert not (top / s.name / "subbroker.toml").exists()
        keys = set()
        for v, vm in fleet.items():
            cfg = load_config(top / s.name / "vehicles" / v / "subbroker.toml")
            assert cfg.drone == v and cfg.station == s.name and cfg.model == vm
            assert cfg.zenoh.mode == "client" and cfg.zenoh.connect == ("tcp/127.0.0.1:7447",)
            ep = vm["pubBroker"]["endpoint"]
            assert cfg.endpoint == (ep["host"], ep["port"])
            assert cfg.state_dir == Path(vm["subBroker"]["configPath"])
            keys.add(cfg.key_ref)
        assert keys == {f"env:MODD_LINK_KEY_{v.upper()}" for v in fleet}


def test_vehicles_on_the_missions_subbroker_path_get_a_state_folder_each(tmp_path: Path) -> None:
    """Vehicles that give no SubBroker path of their own share the mission's; at one
    station their SubBrokers would share one window record. Each gets a folder named
    after it; a vehicle with its own path keeps it."""
    from modd_gen.targets.stations import artifacts, parse_station

    model = load_model(EXAMPLES / "campaign.modd")
    for v in model["campaign"]["vehicles"][:2]:
        del v["subBroker"]["path"]
    stations = [parse_station(t) for t in ("shore=tcp/shore.example:7447", "boat")]
    write_artifacts(tmp_path, artifacts(model, stations))
    top = tmp_path / "operator" / "stations" / "shore" / "vehicles"
    got = {v: load_config(top / v / "subbroker.toml").state_dir for v in ("usv1", "usv2", "usv3")}
    mission = Path(model["subBroker"]["configPath"])
    assert got["usv1"] == mission / "usv1" and got["usv2"] == mission / "usv2"
    third = model["campaign"]["vehicles"][2]["subBroker"]["path"]
    assert got["usv3"] == Path(third)

"""The generated broker configs are the files the runtime really reads: the
SubBroker's own loader accepts the generated TOML (the PubBroker binary reads
its JSON in test_cpp_driver_e2e.py)."""

from __future__ import annotations

import json
from pathlib import Path

from modd.subbroker.config import load_config
from modd_gen import generate, write_artifacts
from modd_model import load_model


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
    from modd_gen.context import build_context
    from modd_gen.targets.stations import artifacts, parse_station

    model = load_model(scenarios_dir / "scenario1.modd")
    given = ["shore=tcp/shore.example:7447", "boat", "cliff=tcp/cliff.example:7448"]
    stations = [parse_station(t) for t in given]
    write_artifacts(
        tmp_path, [*generate(model, "operator"), *artifacts(build_context(model), stations)]
    )
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

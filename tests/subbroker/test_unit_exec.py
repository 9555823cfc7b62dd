"""The packaged units' command lines as systemd expands them (unit_exec.py), read from
packaging/*/units with the packages' own environment files: the drone's on-board
processes follow a deploy (the PubBroker writes the on-board model file, modd-sensors
and modd-mavlink watch it) and the base station's SubBroker sends it over the link
(issue 39, item 5). Fast: no package built. The installed units are run in
test_install_units.py (`make package-test`)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from subbroker_harness import REPO
from unit_exec import UnitError, command, read_unit

PACKAGING = REPO / "packaging"
ONBOARD = "/var/lib/modd/onboard/model.json"


@pytest.fixture
def root(tmp_path: Path) -> Path:
    """A tree laid out as the two packages install it (units and conffiles)."""
    units = tmp_path / "lib/systemd/system"
    units.mkdir(parents=True)
    for f in PACKAGING.glob("*/units/*.service"):
        shutil.copy(f, units)
    (tmp_path / "etc/modd").mkdir(parents=True)
    for kind, env in (("drone", "drone.env"), ("base", "base.env")):
        shutil.copy(PACKAGING / kind / env, tmp_path / "etc/modd")
    return tmp_path


def test_the_drone_units_follow_the_on_board_model_file(root: Path) -> None:
    pb = read_unit(root, "modd-pubbroker.service")
    assert pb.exec_start == [
        "/usr/bin/modd-pubbroker",
        "--config",
        "/etc/modd/pubbroker.json",
        "--onboard-model",
        ONBOARD,
    ]
    for name in ("modd-pubbroker", "modd-sensors", "modd-mavlink"):
        unit = read_unit(root, f"{name}.service")
        assert unit.exec_start_pre == [["/usr/lib/modd/onboard-init"]], name
        assert unit.one("User") == "modd" and "/var/lib/modd" in unit.one("ReadWritePaths")
    sensors = read_unit(root, "modd-sensors.service").exec_start
    assert sensors[:4] == ["/usr/bin/modd-sensors", "--model", ONBOARD, "--watch"]
    assert sensors[-2:] == ["--status-file", "/run/modd/sensors.json"]  # empty ARGS: no word
    mavlink = read_unit(root, "modd-mavlink.service").exec_start
    assert mavlink == ["/usr/bin/modd-mavlink", "--model", ONBOARD, "--watch"] + [
        "--connect",
        "/dev/ttyAMA0,921600",
    ]


def test_the_subbroker_unit_sends_the_on_board_model_over_the_link(root: Path) -> None:
    sb = read_unit(root, "modd-subbroker.service")
    assert "--onboard-over-link" in sb.exec_start
    (root / "etc/modd/base.env").write_text('MODD_SUBBROKER_ARGS="--record-dir /var/lib/modd/r"\n')
    sb = read_unit(root, "modd-subbroker.service")
    assert sb.exec_start[-2:] == ["--record-dir", "/var/lib/modd/r"]  # $VAR: split in words


def test_the_station_unit_runs_the_router_of_the_generated_station_toml(root: Path) -> None:
    """A campaign station (docs/operations.md): the router from /etc/modd/station.toml,
    which `modd generate --station` writes, with the station's credentials; it reads
    that file with its own loader (the command's options are modd-station's)."""
    from modd.station import _parser

    unit = read_unit(root, "modd-station.service")
    assert unit.exec_start == [
        "/usr/bin/modd-station",
        "--config",
        "/etc/modd/station.toml",
        "--credentials",
        "/var/lib/modd/credentials",
    ]
    text = (root / "lib/systemd/system/modd-station.service").read_text()
    assert unit.one("User") == "modd" and "ConditionPathExists=/etc/modd/station.toml" in text
    args = _parser().parse_args(unit.exec_start[1:])
    assert (args.config, args.credentials) == (
        "/etc/modd/station.toml",
        "/var/lib/modd/credentials",
    )
    (root / "etc/modd/base.env").write_text('MODD_STATION_ARGS="--log-level DEBUG"\n')
    assert read_unit(root, "modd-station.service").exec_start[-2:] == ["--log-level", "DEBUG"]


def test_a_vehicles_subbroker_unit_runs_the_generated_vehicle_folder(
    root: Path, tmp_path: Path
) -> None:
    """A campaign station's vehicles (docs/operations.md): `modd generate --station`'s
    folder for the station copied to /etc/modd; modd-subbroker@<vehicle> runs that
    vehicle's subbroker.toml with the station's credentials, and the file loads with the
    SubBroker's own loader from there (its model beside it, its key from link.env)."""
    from modd.subbroker.cli import _parser
    from modd.subbroker.config import load_config
    from modd_gen import write_artifacts
    from modd_gen.targets.stations import artifacts, parse_station
    from modd_model import load_model
    from modd_model.campaign import drone_names

    model = load_model(REPO / "metamodel" / "examples" / "campaign.modd")
    stations = [parse_station(t) for t in ("shore=tcp/shore.example:7447", "boat")]
    write_artifacts(tmp_path / "gen", artifacts(model, stations))
    made = tmp_path / "gen" / "operator" / "stations" / "boat"
    shutil.copytree(made, root / "etc/modd", dirs_exist_ok=True)
    vehicles = drone_names(model)
    assert len(vehicles) == 3
    for v in vehicles:
        unit = read_unit(root, f"modd-subbroker@{v}.service")
        config = f"/etc/modd/vehicles/{v}/subbroker.toml"
        assert unit.exec_start == [
            "/usr/bin/modd-subbroker",
            "--config",
            config,
            "--credentials",
            "/var/lib/modd/credentials",
            "--onboard-over-link",
        ]
        args = _parser().parse_args(unit.exec_start[1:])
        assert args.config == config and args.onboard_over_link
        cfg = load_config(root / config.lstrip("/"))
        assert cfg.drone == v and cfg.station == "boat" and cfg.zenoh.mode == "client"
        assert cfg.key_ref == f"env:MODD_LINK_KEY_{v.upper()}"
    text = (root / "lib/systemd/system/modd-subbroker@.service").read_text()
    assert "ConditionPathExists=/etc/modd/vehicles/%i/subbroker.toml" in text
    assert "EnvironmentFile=-/etc/modd/link.env" in text


def test_expansion_follows_systemd_and_refuses_what_it_does_not_read() -> None:
    env = {"A": "one two", "B": ""}
    assert command("/x ${A} $A $B %t/%n %%", env, "u.service", "here") == [
        "/x",
        "one two",
        "one",
        "two",
        "/run/u.service",
        "%",
    ]
    for line, what in (
        ("/x %h", "specifier %h"),
        ("-/x", "prefix"),
        ("/x a$A", "inside a word"),
    ):
        with pytest.raises(UnitError, match=what):
            command(line, env, "u.service", "here")

"""A campaign's stations as ``modd generate --station`` writes them (docs/operations.md,
"Two base stations"), run as they are: scenario 1 made a campaign of two vehicles,
generated for stations a and b (loopback endpoints); each station's router started
from its ``station.toml`` (``modd-station --config``), each vehicle's
SubBroker from ``<station>/vehicles/<vehicle>/subbroker.toml`` with the station's credentials
directory, each vehicle's C++ PubBroker fed by the load generator. Station a serves
both drones; a viewer at station b gets each drone's windows through the mesh, once
each, equal to the aggregate recomputed from that drone's archive."""

from __future__ import annotations

import json
import subprocess
import sys
import time
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import subbroker_harness as h  # noqa: E402
from fleet.test_fleet import Listener, Station, campaign_credentials, identities  # noqa: E402
from modd_gen.tomlwriter import dumps  # noqa: E402
from modd_model import load_model  # noqa: E402

VEHICLES = ("usv1", "usv2")


def campaign_model(tmp: Path, links: dict[str, int]) -> Path:
    """Scenario 1 as a campaign of VEHICLES, each PubBroker on its free port and its
    SubBroker's state under ``tmp``."""
    model = load_model(h.model_copy(tmp, "scenario1.modd"))
    model["campaign"] = {
        "name": "pair",
        "vehicles": [
            {
                "name": v,
                "pubBroker": {
                    "endpoint": {"host": "127.0.0.1", "port": links[v]},
                    "path": str(tmp / v / "logs"),
                },
                "subBroker": {
                    "endpoint": {"host": "127.0.0.1", "port": h.free_port()},
                    "path": str(tmp / f"state-{v}"),
                },
            }
            for v in VEHICLES
        ],
    }
    path = tmp / "pair.json"
    path.write_text(json.dumps(model))
    return path


def test_generated_campaign_stations_run_as_one_mesh(tmp_path: Path) -> None:
    assert h.PUBBROKER.exists(), f"{h.PUBBROKER} is not built: run make build"
    creds = campaign_credentials(tmp_path, "ab")
    stations = {s: Station(tmp_path, s, "", creds[s]) for s in "ab"}
    links = {v: h.free_port() for v in VEHICLES}
    model = campaign_model(tmp_path, links)
    out = tmp_path / "out"
    given = [f"--station={s}={st.endpoint}" for s, st in stations.items()]
    made = subprocess.run(
        [str(Path(h.PYTHON).with_name("modd")), "generate", str(model), "--out", str(out)]
        + ["--role", "operator", *given],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert made.returncode == 0, made.stderr
    top = out / "operator" / "stations"
    procs: list[h.Proc | Listener] = []
    try:
        for s, st in stations.items():
            station = str(Path(h.PYTHON).with_name("modd-station"))
            cmd = [station, "--config", str(top / s / "station.toml")]
            # the file listens on 0.0.0.0 (a station's machine); a test stays on loopback
            cmd += ["--listen", st.endpoint, "--credentials", str(st.cred)]
            procs.append(h.Proc(f"router-{s}", cmd, tmp_path / f"router-{s}.log"))
            h.wait_port(st.port)
        viewer = Listener(stations["b"])
        procs.append(viewer)
        loads = []
        for i, v in enumerate(VEHICLES):
            home = tmp_path / v
            home.mkdir(exist_ok=True)
            vm = model_of(out, v)
            procs.append(h.start_pubbroker(home, vm, links[v], ingress := h.free_port()))
            loads.append(h.start_load(home, vm, ingress, 25, seed=i + 1))
            procs.append(loads[-1])
        for s in "ab":  # a first: it serves both; b stands by
            for v in VEHICLES:
                cfg = top / s / "vehicles" / v / "subbroker.toml"
                doc = tomllib.loads(cfg.read_text())
                assert doc["station"] == s and doc["zenoh"]["mode"] == "client", doc
                # the state directory is the model's (one per vehicle); one per station here
                doc["state_dir"] = str(tmp_path / f"state-{s}-{v}")
                ours = cfg.with_name("subbroker-test.toml")
                ours.write_text(dumps(doc))
                env = {doc["link"]["key"].removeprefix("env:"): h.KEY}
                cmd = [*h.SUBBROKER, "--config", str(ours), "--credentials", str(creds[s])]
                sb = h.Proc(f"sb-{s}-{v}", cmd, tmp_path / f"sb-{s}-{v}.log", env=env)
                procs.append(sb)
                if s == "a":
                    assert sb.wait_log(f"station a serves {v}", 20), sb.log()
        for load in loads:
            load.p.wait(60)
        time.sleep(2)
        for sb in (p for p in procs if isinstance(p, h.Proc) and p.name.startswith("sb-b-")):
            assert "serves" not in sb.log(), sb.log()
        values = viewer.values()
        for v in VEHICLES:
            mine = [x for x in values if x.drone == v]
            ids = identities(mine)
            assert len(ids) == len(set(ids)), f"a window of {v} twice at station b"
            archive = h.read_archive(tmp_path / v / "archive", model_of(out, v))
            assert h.check_against_archive({f"b/{v}": mine}, archive) > 50
    finally:
        for p in reversed(procs):
            if isinstance(p, Listener):
                p.close()
            else:
                p.stop()


def model_of(out: Path, vehicle: str) -> Path:
    return out / "operator" / "stations" / "a" / "vehicles" / vehicle / "model.json"

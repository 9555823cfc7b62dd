"""Generated output is deterministic and matches the reviewed golden files.
After an intended change, regenerate them with MODD_UPDATE_GOLDEN=1 and review
the diff. The C++ client carried into driver projects is checked against the
runtime's sources instead of being copied into the golden tree."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from modd_gen import generate, py_client
from modd_gen.targets.cpp_driver import client_sources
from modd_gen.targets.subscribers import delivered_value_header, subscriber_client_sources
from modd_model import load_model

GOLDEN = Path(__file__).parent / "golden"
DATA = Path(__file__).resolve().parents[2] / "metamodel" / "tests" / "data"
CARRIED = (
    "modd/include/modd/client/publisher.hpp",
    "modd/src/publisher.cpp",
    "modd/include/modd/client/subscriber.hpp",
    "modd/src/subscriber.cpp",
    "modd/include/modd/client/delivered_value.gen.hpp",
    "modd/include/modd/ingress/wire.hpp",
    "modd/include/modd/ingress/wire.gen.hpp",
)


def _models(scenarios_dir: Path) -> dict[str, Path]:
    return {
        "scenario1": scenarios_dir / "scenario1.modd",
        "scenario2": scenarios_dir / "scenario2.modd",
        "extended": DATA / "extended.modd",
    }


@pytest.mark.parametrize("name", ["scenario1", "scenario2", "extended"])
def test_output_matches_golden(scenarios_dir: Path, name: str) -> None:
    artifacts = generate(load_model(_models(scenarios_dir)[name]))
    carried = CARRIED + tuple(f"python/{name}" for name in py_client.ORIGINALS)
    produced = {a.path: a.content for a in artifacts if not a.path.endswith(carried)}
    root = GOLDEN / name
    if os.environ.get("MODD_UPDATE_GOLDEN"):
        shutil.rmtree(root, ignore_errors=True)
        for path, content in produced.items():
            (root / path).parent.mkdir(parents=True, exist_ok=True)
            (root / path).write_text(content, encoding="utf-8")
    golden = {
        str(p.relative_to(root)): p.read_text(encoding="utf-8")
        for p in root.rglob("*")
        if p.is_file()
    }
    assert sorted(produced) == sorted(golden)
    for path, content in produced.items():
        assert content == golden[path], f"{name}/{path} differs from the golden file"


def test_generation_is_deterministic(scenarios_dir: Path) -> None:
    model = load_model(scenarios_dir / "scenario2.modd")
    assert generate(model) == generate(model)


def test_carried_client_is_the_runtime_client(scenarios_dir: Path) -> None:
    repo = Path(__file__).resolve().parents[2]
    header, source = client_sources()
    artifacts = {a.path: a.content for a in generate(load_model(scenarios_dir / "scenario1.modd"))}
    assert artifacts["integrator/pub_1-driver/" + CARRIED[0]] == header
    assert artifacts["integrator/pub_1-driver/" + CARRIED[1]] == source
    assert artifacts["integrator/pub_1-driver/" + CARRIED[5]] == (
        repo / "runtime/cpp/include/modd/ingress/wire.hpp"
    ).read_text("utf-8")
    assert artifacts["integrator/pub_1-driver/" + CARRIED[6]] == (
        repo / "runtime/cpp/include/modd/ingress/wire.gen.hpp"
    ).read_text("utf-8")
    sub_header, sub_source = subscriber_client_sources()
    assert artifacts["scientist/cpp/sub_5/" + CARRIED[2]] == sub_header
    assert artifacts["scientist/cpp/sub_5/" + CARRIED[3]] == sub_source
    assert (
        artifacts["scientist/cpp/sub_5/" + CARRIED[4]]
        == delivered_value_header()
        == (repo / "runtime/cpp/include/modd/client/delivered_value.gen.hpp").read_text("utf-8")
    )


def test_carried_python_client_is_the_runtime_client(scenarios_dir: Path) -> None:
    repo = Path(__file__).resolve().parents[2]
    artifacts = {a.path: a.content for a in generate(load_model(scenarios_dir / "scenario1.modd"))}
    for name, original in py_client.ORIGINALS.items():
        assert artifacts[f"scientist/python/{name}"] == (repo / original).read_text("utf-8"), name


def test_roles_partition_the_output(scenarios_dir: Path) -> None:
    model = load_model(scenarios_dir / "scenario1.modd")
    everything = {a.path for a in generate(model)}
    by_role = [
        {a.path for a in generate(model, role)} for role in ("integrator", "operator", "scientist")
    ]
    assert set().union(*by_role) == everything
    assert sum(len(r) for r in by_role) == len(everything)
    assert all(p.startswith("integrator/") for p in by_role[0])
    with pytest.raises(ValueError, match="unknown role"):
        generate(model, "pilot")


def test_table2_doc_is_up_to_date() -> None:
    from modd_gen import table2

    assert table2.main(["--check"]) == 0, "run .venv/bin/python -m modd_gen.table2"


def test_code_lines_rule() -> None:
    from modd_gen.table2 import code_lines

    assert code_lines("a\n\n  // c\n# d\nb // e\n") == 2


def test_mavlink_topics_get_no_driver_stub() -> None:
    """The MAVLink bridge publishes a MAVLink sensor's topics (docs/mavlink.md):
    no C++ or Python read function is generated for them."""
    paths = [a.path for a in generate(load_model(DATA / "extended.modd"))]
    bridged = ("integrator/mavlink-driver/", "integrator/python/mavlink")
    assert not [p for p in paths if p.startswith(bridged)]
    assert "integrator/imu-driver/src/driver.cpp" in paths
    driven = "\n".join(
        a.content
        for a in generate(load_model(DATA / "extended.modd"))
        if a.path.startswith("integrator/")
    )
    assert "usv.autopilot." not in driven

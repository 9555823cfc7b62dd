"""The wire's enumerations, counts and limits are written once (the metamodel's
enums and ``modd_contracts/wire.json``) and generated for C++ and Python: a
value added there reaches both codecs and validation with no other edit.

The fake values are added to a copy of the metamodel's packages in a temporary
folder; the copy's typegen writes the copy's generated files, and a child
Python (the copy first on its path, the checkout's runtime after it) decodes,
encodes and validates with them. The C++ headers the copy generates are
compiled with assertions on the new values.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from modd_contracts import link_wire_gen, wiregen
from modd_model.schema import definition

REPO = Path(__file__).resolve().parents[2]
#: The fake aggregation's wire code: the next one.
FAKE_CODE = len(definition("Aggregation")["enum"])

#: What the child Python checks with the copy's generated modules.
CHILD = r"""
import sys
from pathlib import Path

from modd.link import codec, frames
from modd_contracts import link_wire_gen
from modd_contracts.aggregations_gen import Aggregation
from modd_model import load_text

assert Aggregation.FAKE == @CODE@
assert link_wire_gen.MsgType.FAKE_FRAME == 0x7E and link_wire_gen.MAX_FAKE == 42
# a counter appended to STATUS is named by the SubBroker's decoder
assert frames.STATUS_FIELDS[-1] == "fake_counter", frames.STATUS_FIELDS
# the Python codec takes the new aggregation code both ways
config = frames.Config(1, 0, (frames.TopicSpec("d.s.v", frames.ValueType.FLOAT32, 4),),
                       (frames.StreamSpec(0, Aggregation.FAKE, 250_000),))
raw = codec.encode(config)
(frame,) = codec.FrameSplitter().feed(raw)
assert codec.decode(frame) == config, codec.decode(frame)
# validation accepts it in a model, and still refuses a name the contract lacks
text = Path(sys.argv[1]).read_text(encoding="utf-8")
fake = load_text(text.replace("0.250, AVERAGE)", "0.250, FAKE)"), "m.modd")
assert fake.model is not None and not fake.errors, fake.errors
assert fake.model["subscribers"][3]["aggregation"] == "FAKE"
bogus = load_text(text.replace("0.250, AVERAGE)", "0.250, BOGUS)"), "m.modd")
assert bogus.errors, "BOGUS accepted"
print("ok")
"""

#: What the copy's C++ headers must say, checked by the compiler.
CPP = """
#include "modd/link/aggregation_table.gen.hpp"
#include "modd/link/wire.gen.hpp"
static_assert(static_cast<int>(modd::link::Aggregation::Fake) == @CODE@);
static_assert(modd::link::table::kAggregationCount == @CODE@ + 1);
static_assert(static_cast<int>(modd::link::MsgType::FakeFrame) == 0x7E);
static_assert(modd::link::kMaxFake == 42);
static_assert(modd::link::kStatusFieldCount == 38);
static_assert(static_cast<int>(modd::link::StatusField::FakeCounter) == 37);
int main() { return 0; }
"""


def _fake_tree(root: Path) -> Path:
    """A copy of the metamodel's packages with a fake aggregation in the schema and
    a fake frame type, limit and STATUS counter in wire.json; its typegen run. Returns its src."""
    src = root / "metamodel" / "src"
    for pkg in ("modd_model", "modd_plan", "modd_contracts"):
        shutil.copytree(
            REPO / "metamodel" / "src" / pkg,
            src / pkg,
            ignore=shutil.ignore_patterns("__pycache__"),
        )
    schema = json.loads((REPO / "metamodel" / "modd.schema.json").read_text(encoding="utf-8"))
    agg = schema["$defs"]["Aggregation"]
    agg["enum"].append("FAKE")
    agg["x-table"].append(
        {**agg["x-table"][0], "name": "FAKE", "code": FAKE_CODE, "derivableFrom": ["FAKE"]}
    )
    (root / "metamodel" / "modd.schema.json").write_text(json.dumps(schema), encoding="utf-8")
    wire_file = src / "modd_contracts" / "wire.json"
    wire = json.loads(wire_file.read_text(encoding="utf-8"))
    link = wire["groups"][0]
    link["constants"].append({"name": "MAX_FAKE", "type": "size_t", "value": 42, "doc": "Fake."})
    enums = {e["name"]: e for e in link["enums"]}
    enums["MsgType"]["values"].append({"name": "FAKE_FRAME", "value": "0x7E"})
    counters = enums["StatusField"]["values"]
    counters.append({"name": "FAKE_COUNTER", "value": len(counters)})
    wire_file.write_text(json.dumps(wire), encoding="utf-8")
    run = subprocess.run(
        [sys.executable, "-m", "modd_contracts.typegen"],
        cwd=root,
        env={**os.environ, "PYTHONPATH": str(src)},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    return src


def test_a_fake_value_reaches_both_codecs_and_validation(tmp_path: Path) -> None:
    src = _fake_tree(tmp_path)
    path = os.pathsep.join([str(src), str(REPO / "runtime" / "python" / "src")])
    model = REPO / "metamodel" / "tests" / "data" / "scenario1_datacollector.modd"
    run = subprocess.run(
        [sys.executable, "-c", CHILD.replace("@CODE@", str(FAKE_CODE)), str(model)],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": path},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr
    # setup.sh installs the C++ toolchain (make check and make test need it)
    compiler = shutil.which("g++") or shutil.which("clang++")
    assert compiler is not None, "no C++ compiler: run scripts/setup.sh"
    (tmp_path / "fake.cpp").write_text(CPP.replace("@CODE@", str(FAKE_CODE)), encoding="utf-8")
    include = tmp_path / "runtime" / "cpp" / "include"
    cc = subprocess.run(
        [compiler, "-std=c++20", "-fsyntax-only", f"-I{include}", str(tmp_path / "fake.cpp")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert cc.returncode == 0, cc.stderr


def test_generated_python_matches_the_contract() -> None:
    """Every constant and enum member of wire.json, with its value, in the module."""
    for group in wiregen.load()["groups"]:
        if group["py"] != "link_wire_gen":
            continue
        for c in group["constants"]:
            assert getattr(link_wire_gen, c["name"]) == int(str(c["value"]), 0)
        for enum in group["enums"]:
            members = {m.name: int(m) for m in getattr(link_wire_gen, enum["name"])}
            if "fromSchema" in enum:
                want = {str(n).upper(): i for i, n in enumerate(definition("ValueType")["enum"])}
            else:
                want = {v["name"]: int(str(v["value"]), 0) for v in enum["values"]}
            assert members == want


def test_a_model_topic_name_fits_the_link() -> None:
    """A topic is drone.sensor.variable, each a schema Name: the longest one a
    valid model can have fits in a CONFIG's topic name (MAX_NAME bytes)."""
    longest = 3 * int(definition("Name")["maxLength"]) + 2
    assert longest <= link_wire_gen.MAX_NAME


#: Hand-written wire numbers the contract replaced, by file: none may come back.
LITERALS = {
    "runtime/cpp/src/link/codec.cpp": [r"\ba > 7\b", r"\bty > 3\b", r"366", r"1'000'000", r"86400"],
    "runtime/cpp/include/modd/util/bytes.hpp": [r"shift < 70", r"than 10 bytes"],
    "runtime/cpp/src/link/datagram.cpp": [r"> 255\b"],
    "runtime/python/src/modd/link/datagram.py": [r"> 255\b", r"<= 65535"],
    "runtime/cpp/src/link/backfill.cpp": [r"\ba > 7\b", r"\bty > 3\b", r"366"],
    "runtime/cpp/src/ingress/codec.cpp": [r"\bt[y]? > 3\b", r"65535", r"\b255\b"],
    "runtime/cpp/src/broker/dgram_link.cpp": [r"= 0x09", r"kMaxNackRanges = 32", r"65535"],
    "runtime/python/src/modd/link/codec.py": [
        r"86400",
        r"\ba > 7\b",
        r"\bty > 3\b",
        r"366",
        r"\b255\b",
        r"\b70\b",
    ],
    "runtime/python/src/modd/link/backfill.py": [r"\bagg > 7\b", r"\bty > 3\b", r"366"],
    "runtime/python/src/modd/ingress.py": [r"\bt > 3\b", r"65535", r"\b255\b", r"= 0x8"],
}


@pytest.mark.parametrize("rel", sorted(LITERALS))
def test_no_wire_number_written_by_hand(rel: str) -> None:
    text = (REPO / rel).read_text(encoding="utf-8")
    found = [p for p in LITERALS[rel] if re.search(p, text)]
    assert not found, f"{rel}: {found} (take them from modd_contracts/wire.json)"


def test_the_model_s_packet_bounds_are_the_link_s() -> None:
    """link.maxPacket is validated (schema) with the bounds the PubBroker's config
    and the radio use (wire.json), and the planner's defaults are the contract's."""
    from modd_plan.linkbudget import DEFAULT_PACKET

    prop = definition("Link")["properties"]["maxPacket"]
    assert (prop["minimum"], prop["maximum"]) == (
        link_wire_gen.MIN_PACKET,
        link_wire_gen.MAX_PACKET,
    )
    assert DEFAULT_PACKET["udp"] == link_wire_gen.DEFAULT_UDP_PACKET
    assert DEFAULT_PACKET["serial"] == link_wire_gen.DEFAULT_SERIAL_PACKET

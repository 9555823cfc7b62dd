"""The contracts home (modd_contracts): key vectors, schemas that are valid
JSON Schemas, generated files up to date, the aggregation table consistent
with the metamodel, and what the producers in this package (the plan, the
generator's pubbroker.json) write keeps to its schema."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
from jsonschema import Draft202012Validator
from modd_contracts import keys
from modd_contracts.aggregations_gen import AGGREGATIONS, BY_NAME
from modd_contracts.events import EVENT_AGGREGATIONS
from modd_contracts.owners_gen import MODEL_PART_OWNERS
from modd_contracts.schema import NAMES, load, validate
from modd_contracts.typegen import part_owners, stale_outputs
from modd_model import load_model
from modd_model.schema import definition, load_schema
from modd_plan import make_plan
from modd_plan.derive import PAIR_SOURCE_RULES, SINGLE_SOURCE_RULES, aggregate, derive_value

REPO = Path(__file__).resolve().parents[2]
VECTORS = REPO / "contracts" / "vectors"
EXAMPLES = sorted((REPO / "metamodel" / "examples").glob("**/*.modd"))


def _vectors(name: str) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((VECTORS / f"{name}.json").read_text())
    return data


def test_key_vectors() -> None:
    v = _vectors("keys")
    for case in v["builds"]:
        assert getattr(keys, case["builder"])(*case["args"]) == case["key"], case
    for bad in v["refuses"]:
        for builder in (keys.deploy_key, keys.status_key, keys.subscribe_key, keys.values_of):
            with pytest.raises(ValueError, match="not an identifier"):
                builder(bad)
        with pytest.raises(ValueError):
            keys.sub_key("usv", bad)


def test_keys_parse_back() -> None:
    assert keys.parse_sub_key(keys.sub_key("usv", "sub_1")) == ("usv", "sub_1")
    assert keys.parse_status_key(keys.status_key("usv")) == "usv"
    for bad in ("modd/usv/status", "modd/*/sub/x", "other/usv/sub/x", "modd/usv/sub/x/y"):
        with pytest.raises(ValueError):
            keys.parse_sub_key(bad)
        assert keys.match_sub_key(bad) is None
    for bad in ("modd/*/status", "modd/usv/status/x", "modd/usv/sub/x", "x/usv/status"):
        assert keys.match_status_key(bad) is None
        with pytest.raises(ValueError):
            keys.parse_status_key(bad)
    assert keys.match_status_key("modd/usv/status") == "usv"


def test_queryables_are_the_builders() -> None:
    assert keys.queryables_of("usv") == [
        keys.deploy_key("usv"),
        keys.subscribe_key("usv"),
        keys.backfill_key("usv"),
    ]
    assert keys.queryables_of(None) == ["modd/*/deploy", "modd/*/subscribe", "modd/*/backfill"]


def test_every_model_part_has_an_owner() -> None:
    """A new top-level part of the schema must name its owning role."""
    root = load_schema()
    assert set(root["properties"]) <= {p.split("/")[1] for p in MODEL_PART_OWNERS}
    assert part_owners() == MODEL_PART_OWNERS
    assert MODEL_PART_OWNERS["/drone/sensors"] == "integrator"
    assert set(MODEL_PART_OWNERS.values()) <= {"designer", "integrator", "scientist", None}


def test_key_names_are_the_metamodels() -> None:
    name = definition("Name")
    assert name["pattern"] == "^[A-Za-z_][A-Za-z0-9_]*$" and name["maxLength"] == 64
    assert keys.NAME.pattern == r"[A-Za-z_][A-Za-z0-9_]{0,63}"


@pytest.mark.parametrize("name", NAMES)
def test_schemas_are_valid_and_versioned(name: str) -> None:
    schema = load(name)
    Draft202012Validator.check_schema(schema)
    assert isinstance(schema["x-version"], int) and schema["title"]


def test_generated_files_are_fresh() -> None:
    assert stale_outputs() == [], "run python -m modd_contracts.typegen"


def test_invalid_vectors_fail_as_documented() -> None:
    for name in ("delivered_value", "status"):
        for case in _vectors(name)["invalid"]:
            assert case["error"] in validate(name, case["document"]), case["name"]


def test_status_vectors_conform() -> None:
    for case in _vectors("status")["vectors"]:
        assert validate("status", case["document"]) == [], case["name"]


# -- the aggregation table -----------------------------------------------------------


def test_aggregation_table_is_the_metamodels_enum() -> None:
    assert [a.name for a in AGGREGATIONS] == definition("Aggregation")["enum"]
    assert [a.code for a in AGGREGATIONS] == list(range(len(AGGREGATIONS)))
    for a in AGGREGATIONS:
        assert set(a.result) == {"float32", "float64", "int", "bool"}
        # a window that cannot be merged (MEDIAN, STDDEV, RANGE) comes from ALL only;
        # an event subscription (its state spans windows) from nothing
        assert a.name in a.derivable_from or a.derivable_from == (
            () if a.name in EVENT_AGGREGATIONS else ("ALL",)
        )
        assert set(a.derivable_from) <= set(BY_NAME)


def test_derivability_rules_hold_on_samples() -> None:
    """Every 'derivable from' of the table computes what aggregating the raw
    samples computes (the independent oracle: :func:`aggregate` on the whole)."""
    halves = ([1.0, 4.0, -2.0], [3.5, 0.5])
    for name, sources in SINGLE_SOURCE_RULES.items():
        if name in EVENT_AGGREGATIONS:
            assert not sources  # derived from nothing
            continue
        target = "PERCENTILE(95)" if name == "PERCENTILE" else name  # a stream's label
        whole = aggregate(target, [*halves[0], *halves[1]])
        for source in sources:
            windows = [aggregate(source, h) for h in halves]
            got = derive_value(target, [(source, windows)])
            assert got == pytest.approx(whole), (target, source)
    for target, (a, b) in PAIR_SOURCE_RULES.items():
        got = derive_value(
            target, [(a, [aggregate(a, h) for h in halves]), (b, [aggregate(b, h) for h in halves])]
        )
        assert got == pytest.approx(aggregate(target, [*halves[0], *halves[1]]))


def test_cpp_enum_follows_the_table() -> None:
    """The C++ enum is the generated header's, in wire-code order; messages.hpp
    has no copy of its own."""
    messages = (REPO / "runtime/cpp/include/modd/link/messages.hpp").read_text()
    assert "enum class Aggregation" not in messages
    assert '#include "modd/link/aggregation_table.gen.hpp"' in messages
    text = (REPO / "runtime/cpp/include/modd/link/aggregation_table.gen.hpp").read_text()
    enum = re.search(r"enum class Aggregation : uint8_t \{([^}]*)\}", text)
    assert enum is not None
    names = [n.split("=")[0].strip() for n in enum.group(1).split(",") if n.strip()]
    names = [re.sub(r"(?<=[a-z])(?=[A-Z])", "_", n).upper() for n in names]  # OnChange
    assert names == [a.name for a in AGGREGATIONS]


# -- producers in this package --------------------------------------------------------


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_plan_json_conforms(path: Path) -> None:
    plan = make_plan(load_model(path)).to_json()
    assert validate("plan", plan) == []


def _cpp_defaults() -> dict[str, str]:
    """``name = value`` default initialisers of config.hpp's BrokerConfig."""
    text = (REPO / "runtime/cpp/include/modd/broker/config.hpp").read_text()
    found = re.findall(r"\b(\w+)\s*=\s*([^;]+);", text)  # an initialiser may wrap
    return {k: v.strip().strip('"').replace("'", "") for k, v in found}


def test_pubbroker_defaults_are_the_pubbrokers() -> None:
    """Each schema default is what config.hpp initialises the field to."""
    cpp = _cpp_defaults()
    schema = load("pubbroker")
    fields = {  # schema (object, key) -> config.hpp member
        ("", "name"): "name",
        ("PubBrokerLink", "host"): "link_host",
        ("PubBrokerLink", "port"): "link_port",
        ("PubBrokerLink", "handshake_timeout_ms"): "handshake_timeout_ms",
        ("PubBrokerIngress", "host"): "ingress_host",
        ("PubBrokerIngress", "port"): "ingress_port",
        ("PubBrokerIngress", "max_future_ms"): "max_future_ms",
        ("PubBrokerIngress", "max_past_ms"): "max_past_ms",
        ("PubBrokerArchive", "prefix"): "archive_prefix",
        ("PubBrokerArchive", "rotate_s"): "rotate_s",
        ("PubBrokerArchive", "flush_interval_ms"): "flush_interval_ms",
        ("PubBrokerArchive", "queue_limit_samples"): "queue_limit_samples",
        ("PubBrokerArchive", "message_index"): "message_index",
        ("PubBrokerArchive", "low_space_mb"): "low_space_mb",
        ("PubBrokerArchive", "retry_max_ms"): "retry_max_ms",
        ("", "default_buffer_size"): "default_buffer_size",
        ("", "accept_unknown_topics"): "accept_unknown_topics",
        ("", "status_period_s"): "status_period_s",
        ("", "log_period_s"): "log_period_s",
        ("PubBrokerLog", "keep"): "log_keep",
    }
    for (obj, key), member in fields.items():
        props = schema["properties"] if not obj else schema["$defs"][obj]["properties"]
        default = props[key]["default"]
        expected = str(default).lower() if isinstance(default, bool) else str(default)
        assert cpp[member] == expected, (obj, key, cpp[member], default)
    assert (
        eval(cpp["rotate_bytes"].replace("ull", ""))
        == (  # noqa: S307 (a constant)
            schema["$defs"]["PubBrokerArchive"]["properties"]["rotate_bytes"]["default"]
        )
    )

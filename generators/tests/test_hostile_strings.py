"""No model string can inject into generated code or configs (issue: a unit
`m\\n#include <cstdlib>\\nint p=std::system("id>PWNED");//` ran `id` in the
scientist's C++ subscriber; a SubBroker configPath added a [zenoh.settings]
table to subbroker.toml).

Every target of every role is generated from a model whose every free-text
field holds the most hostile string the schema accepts (quotes, comment ends,
triple quotes, ${}, $(), backquotes, backslashes, trigraphs, printf
directives, non-Latin scripts); the C++ projects are built with CMake, the
Python is compiled, the configs are parsed (subbroker.toml by the SubBroker's
own loader), and each hostile string is found whole inside its literal. What
the schema forbids (a newline in a unit, a TOML table in a path) is rejected
with a located error, and rendered inert even when generation is handed an
unvalidated model."""

from __future__ import annotations

import ast
import json
import re
import subprocess
import tomllib
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.config import load_config
from modd_gen import generate, py_client, write_artifacts
from modd_model import validate

# Most hostile strings the schema accepts (no control characters; each within its maxLength).
UNIT = '*/"\\"""\'\'\'${HOME}$(id)`id`??/%n%s\\ std::system("id")//米🚁'
PATH = '/tmp/x"]\n'.replace("\n", "") + ' [zenoh.settings] a="${HOME}$(id)`id`\'\'\'"""\\ Ωμ米 %n'
DESCRIPTION = 'line "one" */ """\n#include <cstdlib>\n\tint p=std::system("id");// ${x} $(id) \\'
KEY_REF = 'file:/k "] [zenoh] x="$(id)`id`\\ 米'
ATTACK_UNIT = 'm\n#include <cstdlib>\nint p=std::system("id>PWNED");//'
ATTACK_PATH = '/conf"\n[zenoh.settings]\nlisten = ["tcp/0.0.0.0:1"]\nx = "'
ATTACK_HOST = '127.0.0.1:1"\n[zenoh.settings]\ny = "'


def hostile_model(unit: str = UNIT, path: str = PATH, host: str = "127.0.0.1") -> dict[str, Any]:
    # Names are identifiers (a keyword of C++ or Python where one fits): the
    # generators must still produce valid identifiers.
    ep = {"host": "127.0.0.1"}
    return {
        "schemaVersion": "1.0",
        "drone": {
            "name": "int",
            "description": DESCRIPTION,
            "sensors": [
                {
                    "name": "class",
                    "description": DESCRIPTION,
                    "variables": [
                        {"name": "def", "unit": unit, "description": DESCRIPTION},
                        {"name": "lambda", "unit": unit, "type": "int"},
                    ],
                }
            ],
        },
        "pubBroker": {
            "name": "namespace",
            "endpoint": {"host": host, "port": 7171},
            "logPath": PATH,
            "ingress": {"unixSocket": PATH},
        },
        "subBroker": {"endpoint": {"host": "base-station.local", "port": 7272}, "configPath": path},
        "link": {"keyRef": KEY_REF},
        "publishers": [
            {"name": "new", "periodS": "0.5", "topics": ["int.class.def", "int.class.lambda"]}
        ],
        "subscribers": [
            {
                "name": "None",
                "endpoint": {**ep, "port": 7401},
                "topic": "int.class.def",
                "periodS": "1",
                "aggregation": "AVERAGE",
            },
            {
                "name": "delete",
                "endpoint": {**ep, "port": 7402},
                "topic": "int.class.lambda",
                "periodS": "1",
                "aggregation": "ALL",
            },
        ],
        "layout": {"nodes": {DESCRIPTION.replace("\n", " ").replace("\t", " "): {"x": 0, "y": 0}}},
    }


def _build(project: Path) -> Path:
    build = project / "build"
    for cmd in (
        ["cmake", "-S", str(project), "-B", str(build), "-G", "Ninja"],
        ["cmake", "--build", str(build)],
    ):
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout + run.stderr
    (exe,) = [
        p for p in build.iterdir() if p.is_file() and p.name.endswith(("_driver", "_subscriber"))
    ]
    return exe


def _imports(exe: Path) -> set[str]:
    out = subprocess.run(
        ["nm", "-D", "--undefined-only", str(exe)], capture_output=True, text=True, check=True
    ).stdout
    return {line.split()[-1].split("@")[0] for line in out.splitlines() if line.strip()}


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    model = hostile_model()
    # The schema takes the hostile unit; UDUNITS-2 then refuses it (modd_model/units.py),
    # and the generators must stay inert with it all the same.
    errors = [d for d in validate(model) if d.severity == "error"]
    assert all("is not a UDUNITS-2 unit" in d.message for d in errors), [str(d) for d in errors]
    out = tmp_path_factory.mktemp("hostile")
    write_artifacts(out, generate(model))
    return out


def test_every_role_is_generated(generated: Path) -> None:
    roles = {p.relative_to(generated).parts[0] for p in generated.rglob("*") if p.is_file()}
    assert roles == {"integrator", "operator", "scientist"}


def _generated_python(root: Path) -> list[Path]:
    """The Python the model's strings reach: not the client carried beside the stubs
    (modd_gen.py_client, the runtime's own modules, the same for every model)."""
    carried = {root / "scientist" / "python" / name for name in py_client.ORIGINALS}
    return sorted(f for f in root.rglob("*.py") if f not in carried)


def test_python_compiles_and_holds_the_strings_as_constants(generated: Path) -> None:
    files = _generated_python(generated)
    assert len(files) == 3  # the publisher and the two subscribers
    for f in files:
        source = f.read_text(encoding="utf-8")
        tree = ast.parse(source, str(f))
        compile(tree, str(f), "exec")
        top = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
        top |= {
            t.id
            for n in tree.body
            if isinstance(n, ast.Assign)
            for t in n.targets
            if isinstance(t, ast.Name)
        }
        if f.parent.name == "python" and f.parent.parent.name == "integrator":
            assert top == {
                "PUBLISHER",
                "DEFAULT_INGRESS",
                "PERIOD_S",
                "TOPICS",
                "read_def_",
                "read_lambda_",
                "main",
            }
            constants = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)}
            assert f"unix:{PATH}" in constants and "int.class.def" in constants
            comments = [
                line.split("  # ", 1)[1]
                for line in source.splitlines()
                if "  # " in line and "米" in line
            ]
            # each comment is the unit quoted and escaped (?\? keeps a ?? from being a trigraph)
            assert len(comments) == 2 and all(
                ast.literal_eval(c.replace("?\\?", "??")) == UNIT for c in comments
            )
        else:
            # CONNECT and VIEWER_CREDENTIALS: None here (no running deployment to name)
            assert top == {"DRONE", "SUBSCRIBER", "CONNECT", "VIEWER_CREDENTIALS", "main"}
            doc = ast.get_docstring(tree, clean=False)
            assert doc is not None and f"({UNIT})" in doc


def test_cpp_driver_builds_and_prints_the_exact_string(generated: Path) -> None:
    exe = _build(generated / "integrator" / "new-driver")
    assert "system" not in _imports(exe)
    usage = subprocess.run([str(exe), "--help"], capture_output=True, timeout=30).stdout
    assert f"default: $MODD_INGRESS or unix:{PATH})".encode() in usage


def test_cpp_subscriber_builds_without_injected_code(generated: Path) -> None:
    exe = _build(generated / "scientist" / "cpp" / "None")
    assert "system" not in _imports(exe)
    header = (generated / "scientist" / "cpp" / "None" / "src" / "main.cpp").read_text()
    assert header.count("\n") == (
        generated / "scientist" / "cpp" / "delete" / "src" / "main.cpp"
    ).read_text().count("\n")


def test_configs_parse_to_the_model_strings(tmp_path: Path) -> None:
    # The SubBroker loads only a valid model: every hostile string but the unit, which
    # UDUNITS-2 refuses (the generated fixture keeps it, for the generators).
    model = hostile_model(unit="m s-1")
    write_artifacts(tmp_path, generate(model))
    operator = tmp_path / "operator"
    cfg = load_config(operator / "subbroker.toml")
    assert cfg.state_dir == operator / PATH
    assert cfg.key_ref == KEY_REF
    raw = tomllib.loads((operator / "subbroker.toml").read_text())
    assert set(raw) == {"model", "drone", "state_dir", "link", "zenoh", "delivery"}
    assert raw["zenoh"] == {"mode": "peer", "listen": ["tcp/127.0.0.1:7447"]}
    pub = json.loads((operator / "pubbroker.json").read_text())
    assert pub["archive"]["dir"] == PATH and pub["ingress"]["unix_path"] == PATH
    assert pub["link"]["key"] == KEY_REF
    assert json.loads((operator / "model.json").read_text()) == model


def test_markdown_tables_keep_their_cells(generated: Path) -> None:
    for readme in generated.rglob("README.md"):
        rows = [line for line in readme.read_text().splitlines() if line.startswith("| ")]
        widths = {len(re.findall(r"(?<!\\)\|", row)) for row in rows}
        assert len(widths) == 1, (readme, rows)
        assert "<" not in "".join(rows)


# -- the attacks of the issue -----------------------------------------------------


@pytest.mark.parametrize(
    "field,model",
    [
        ("/drone/sensors/0/variables/0/unit", hostile_model(unit=ATTACK_UNIT)),
        ("/subBroker/configPath", hostile_model(path=ATTACK_PATH)),
        ("/pubBroker/endpoint/host", hostile_model(host=ATTACK_HOST)),
    ],
)
def test_the_issue_attacks_are_rejected_at_their_field(field: str, model: dict[str, Any]) -> None:
    errors = [d for d in validate(model) if d.severity == "error"]
    assert errors and any(d.pointer.startswith(field) for d in errors), [str(d) for d in errors]


def test_the_unit_attack_is_inert_even_unvalidated(tmp_path: Path) -> None:
    """Generation handed the issue's unit without validation: the code builds and
    never calls system(); the unit stays inside comments."""
    write_artifacts(tmp_path, generate(hostile_model(unit=ATTACK_UNIT)))
    driver = tmp_path / "integrator" / "new-driver"
    header = (driver / "generated" / "new_topics.hpp").read_text()
    assert "\n#include <cstdlib>" not in header
    assert "system" not in _imports(_build(driver))
    for f in _generated_python(tmp_path):
        tree = ast.parse(f.read_text(), str(f))
        calls = [n for n in ast.walk(tree) if isinstance(n, ast.Name) and n.id == "p"]
        assert calls == []


def test_the_toml_attacks_are_inert_even_unvalidated(tmp_path: Path) -> None:
    write_artifacts(
        tmp_path,
        generate(hostile_model(path=ATTACK_PATH, host=ATTACK_HOST)),
    )
    raw = tomllib.loads((tmp_path / "operator" / "subbroker.toml").read_text())
    assert raw["state_dir"] == ATTACK_PATH
    assert raw["link"]["endpoint"] == f"{ATTACK_HOST}:7171"
    assert raw["zenoh"] == {"mode": "peer", "listen": ["tcp/127.0.0.1:7447"]}

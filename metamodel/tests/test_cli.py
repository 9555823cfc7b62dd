"""The `modd` command line, run as users run it (a subprocess of .venv/bin/modd)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

MODD = [sys.executable, "-m", "modd_model.cli"]


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*MODD, *args], capture_output=True, text=True, timeout=60)


def test_validate_ok_and_failures(scenarios_dir: Path, tmp_path: Path) -> None:
    ok = run(
        "validate", str(scenarios_dir / "scenario1.modd"), str(scenarios_dir / "scenario2.modd")
    )
    assert ok.returncode == 0, ok.stderr
    bad = tmp_path / "bad.modd"
    bad.write_text((scenarios_dir / "scenario1.modd").read_text().replace("MIN", "MEAN"))
    res = run("validate", str(bad))
    assert res.returncode == 1
    assert f"{bad}:23:" in res.stderr and "unknown aggregation 'MEAN'" in res.stderr


def test_convert_both_ways(scenarios_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "s1.json"
    res = run("convert", str(scenarios_dir / "scenario1.modd"), "--to", "json", "-o", str(out))
    assert res.returncode == 0, res.stderr
    assert json.loads(out.read_text())["drone"]["name"] == "usv"
    back = run("convert", str(out), "--to", "modd")
    assert back.returncode == 0
    assert back.stdout.startswith("Drone usv {")
    assert (
        'Subscriber sub_7("127.0.0.1":7407, "usv.accelerometer.accel_z", 0.25, MAX);' in back.stdout
    )


def test_fmt_check_and_rewrite(scenarios_dir: Path, tmp_path: Path) -> None:
    src = tmp_path / "wrapped.modd"
    shutil.copy(Path(__file__).parent / "data" / "scenario1_datacollector.modd", src)
    check = run("fmt", "--check", str(src))
    assert check.returncode == 1 and "not in canonical form" in check.stderr
    # the file has comments: the canonical form keeps them
    comments = [line.strip() for line in src.read_text().splitlines() if "//" in line]
    assert comments and run("fmt", str(src)).returncode == 0
    assert run("fmt", "--check", str(src)).returncode == 0
    kept = src.read_text()
    assert [line.strip() for line in kept.splitlines() if "//" in line] == comments
    assert run("fmt", "--drop-comments", str(src)).returncode == 0
    printed = run("convert", str(scenarios_dir / "scenario1.modd"), "--to", "modd").stdout
    assert src.read_text() == printed


def test_console_script_is_installed() -> None:
    modd = Path(sys.executable).parent / "modd"
    assert modd.exists()
    res = subprocess.run([str(modd), "--help"], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0 and "validate" in res.stdout


def test_write_atomic_leaves_the_original_on_a_failed_write(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A full disk during `modd fmt` or `convert -o`: the user's file is untouched,
    no temporary file is left behind."""
    import errno
    import os

    from modd_model.io import write_atomic

    target = tmp_path / "mission.modd"
    target.write_text("original\n")

    def full(_fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OSError):
        write_atomic(target, "x" * 100_000)
    assert target.read_text() == "original\n"
    assert [p.name for p in tmp_path.iterdir()] == ["mission.modd"]
    monkeypatch.undo()
    write_atomic(target, "new\n")
    assert target.read_text() == "new\n"


def _modules_after(*argv: str) -> set[str]:
    """Modules imported by ``modd ARGV`` (run in a fresh interpreter)."""
    code = (
        "import sys, json, contextlib, io\n"
        "from modd_model.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        f"        main({list(argv)!r})\n"
        "    except SystemExit:\n"
        "        pass\n"
        "print(json.dumps(sorted(sys.modules)))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    ).stdout
    return {m.split(".")[0] for m in json.loads(out.strip().splitlines()[-1])}


HEAVY = {
    "fastapi",
    "sqlalchemy",
    "starlette",
    "pydantic",
    "cvxpy",
    "zenoh",
    "modd_backend",
    "modd_gen",
    "modd",
}


def test_help_imports_no_plugin() -> None:
    """``modd --help`` lists the commands without importing any of them."""
    loaded = _modules_after("--help")
    assert not loaded & (HEAVY | {"lark", "jsonschema", "numpy", "modd_plan"})


def test_plan_imports_only_the_planner(scenarios_dir: Path) -> None:
    loaded = _modules_after("plan", str(scenarios_dir / "scenario1.modd"))
    assert "modd_plan" in loaded
    assert not loaded & HEAVY


def test_builtin_commands_are_the_declared_entry_points() -> None:
    """``modd`` loads its own commands without the entry-point scan: the table
    must say what the metamodel's pyproject.toml declares."""
    from importlib.metadata import entry_points

    from modd_model.cli import BUILTIN

    declared = {
        ep.name: ep.value for ep in entry_points(group="modd.commands") if ep.name in BUILTIN
    }
    assert declared == BUILTIN


def test_plan_reads_no_entry_points(scenarios_dir: Path) -> None:
    """``modd plan`` of a small model: no entry-point scan, no lark (the
    parser is generated), no jsonschema (the compiled validator), no numpy."""
    code = (
        "import sys, contextlib, io\n"
        "from modd_model.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    main(['plan', {str(scenarios_dir / 'scenario1.modd')!r}])\n"
        "print(sorted(m for m in ('importlib.metadata', 'lark', 'jsonschema', 'numpy')\n"
        "             if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    ).stdout
    assert out.strip().splitlines()[-1] == "[]"

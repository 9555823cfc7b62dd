"""``modd plan``: registered through the entry point, text and JSON output."""

from __future__ import annotations

import argparse
import io
import json
from pathlib import Path

import pytest
from modd_plan.cli import register, run_plan


def _parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="modd")
    register(parser.add_subparsers(dest="command", required=True))
    return parser.parse_args(["plan", *argv])


def _run(argv: list[str]) -> tuple[int, str]:
    out = io.StringIO()
    args = _parse(argv)
    assert args.func is run_plan
    return run_plan(args, out), out.getvalue()


def test_json_output(scenarios_dir: Path) -> None:
    code, text = _run([str(scenarios_dir / "scenario1.modd"), "--json"])
    j = json.loads(text)
    assert code == 0
    assert j["buffer_sizes"]["usv.accelerometer.accel_z"] == 6
    assert j["messages_per_hyperperiod"] == 8 and j["infeasible"] == []


def test_text_output(scenarios_dir: Path) -> None:
    code, text = _run([str(scenarios_dir / "scenario1.modd")])
    assert code == 0
    assert "hyperperiod 2.0 s, 8 messages per hyperperiod" in text
    assert (
        "usv.accelerometer.accel_x/AVERAGE/2.0 <- 8 x usv.accelerometer.accel_x/AVERAGE/0.25"
        in text
    )
    assert "usv.accelerometer.accel_x: 28" in text and "sub_1: 0.88 s" in text
    assert "plain pub/sub:" in text


def test_overrides_and_infeasible_exit_code(scenarios_dir: Path) -> None:
    code, text = _run(
        [str(scenarios_dir / "scenario1.modd"), "--ping", "0.1", "--json", "--method", "cvxpy"]
    )
    j = json.loads(text)
    assert code == 3
    assert [x["topic"] for x in j["infeasible"]] == [
        "usv.accelerometer.accel_x",
        "usv.accelerometer.accel_y",
    ]
    assert j["constants"]["ping_s"] == "0.1"
    code, text = _run([str(scenarios_dir / "scenario1.modd"), "--ping", "0.1"])
    assert code == 3 and "INFEASIBLE" in text
    code, text = _run([str(scenarios_dir / "scenario1.modd"), "--max-buffer", "5", "--json"])
    assert json.loads(text)["buffer_sizes"]["usv.accelerometer.accel_x"] == 5


def test_bad_arguments_and_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        _parse(["x.modd", "--ping", "abc"])
    with pytest.raises(SystemExit):
        _parse(["x.modd", "--max-buffer", "0"])
    capsys.readouterr()
    assert _run([str(tmp_path / "missing.modd")])[0] == 1
    bad = tmp_path / "bad.modd"
    bad.write_text("Drone {")
    assert _run([str(bad)])[0] == 1
    assert "bad.modd:" in capsys.readouterr().err


def test_registered_in_the_modd_command(
    scenarios_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from modd_model.cli import main

    assert main(["plan", str(scenarios_dir / "scenario2.modd"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["messages_per_hyperperiod"] == 1

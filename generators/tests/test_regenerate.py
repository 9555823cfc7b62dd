"""Regenerating after a model change rewrites generated files and keeps the
integrator's own files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path


def _generate(model: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "modd_model.cli", "generate", str(model), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_user_files_survive_regeneration(scenarios_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "gen"
    first = _generate(scenarios_dir / "scenario1.modd", out)
    assert first.returncode == 0, first.stderr
    driver = out / "integrator/pub_1-driver/src/driver.cpp"
    topics = out / "integrator/pub_1-driver/generated/pub_1_topics.hpp"
    driver.write_text(driver.read_text() + "\n// my sensor code\n")
    topics.write_text("// tampered\n")

    changed = tmp_path / "changed.modd"
    changed.write_text((scenarios_dir / "scenario1.modd").read_text().replace("0.04", "0.02"))
    second = _generate(changed, out)
    assert second.returncode == 0, second.stderr
    assert driver.read_text().endswith("// my sensor code\n")
    assert "kPeriod{20000}" in topics.read_text()
    assert "src/driver.cpp (yours: kept)" in second.stdout
    index = json.loads((out / "INDEX.json").read_text())
    kept = {f["path"] for f in index["files"] if f["action"] == "kept"}
    users = {f["path"] for f in index["files"] if f["ownership"] == "user"}
    assert kept == users
    assert {
        "integrator/pub_1-driver/src/driver.cpp",
        "integrator/pub_1-driver/user.cmake",
        "scientist/cpp/sub_5/src/main.cpp",
    } <= kept


def test_invalid_model_generates_nothing(tmp_path: Path) -> None:
    bad = tmp_path / "bad.modd"
    bad.write_text("Drone d { }")
    res = _generate(bad, tmp_path / "out")
    assert res.returncode == 1 and "no PubBroker block" in res.stderr
    assert not (tmp_path / "out").exists()

"""The scientist's download runs where scientists run it (issue 42): a fresh
virtual environment that holds only the client's third-party packages
(eclipse-zenoh, pandas) and no access to the checkout, the stub started with
plain ``python`` as its README says, against a live ``modd up`` drone. The
MoDD client it imports is the one carried beside it (modd_gen.py_client)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import sysconfig
from collections.abc import Callable
from pathlib import Path

import pandas  # type: ignore[import-untyped]
import zenoh
from modd_gen import generate, write_artifacts
from modd_model import load_model


def _fresh_venv(root: Path) -> Path:
    """A venv of the base interpreter whose only extra path holds zenoh and pandas: this
    environment's site-packages added as a plain path, so its ``.pth`` files (the
    editable installs of the checkout) are not read, and ``import modd`` finds nothing."""
    subprocess.run([sys._base_executable, "-m", "venv", "--without-pip", str(root)], check=True)  # type: ignore[attr-defined]
    python = root / "bin" / "python"
    site = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    deps = {str(Path(zenoh.__file__).parents[1]), str(Path(pandas.__file__).parents[1])}
    (Path(site) / "client-deps.pth").write_text("".join(f"{d}\n" for d in sorted(deps)))
    assert sysconfig.get_paths()["purelib"] in deps  # the deps are plain packages there
    return python


def test_the_stub_runs_in_a_fresh_venv_by_its_readme(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model_path = tmp_path / "model.modd"
    model_path.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}')
    )
    write_artifacts(tmp_path / "gen", generate(load_model(model_path), "scientist"))
    stubs = tmp_path / "gen" / "scientist"
    readme = (stubs / "README.md").read_text()
    assert 'python3 -m pip install "eclipse-zenoh>=1.4,<2" pandas' in readme
    python = _fresh_venv(tmp_path / "venv")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    isolated = subprocess.run(
        [str(python), "-c", "import modd"], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert isolated.returncode != 0 and "No module named 'modd'" in isolated.stderr
    zenoh_ep = f"tcp/127.0.0.1:{free_port()}"
    run = tmp_path / "run"
    up = subprocess.Popen(
        [
            modd_cmd,
            "up",
            str(model_path),
            "--simulate",
            "--workdir",
            str(run),
            "--zenoh-listen",
            zenoh_ep,
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        wait_for(run / "logs" / "subbroker.log", "config 1 running", 30)
        sub = subprocess.run(
            [
                str(python),
                "python/sub_5.py",
                "--count",
                "3",
                "--connect",
                zenoh_ep,
                "--credentials",
                str(run / "credentials" / "viewer.cred"),
            ],
            cwd=stubs,
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
        )
        frame = subprocess.run(
            [
                str(python),
                "python/sub_1.py",
                "--dataframe",
                "5",
                "--connect",
                zenoh_ep,
                "--credentials",
                str(run / "credentials" / "viewer.cred"),
            ],
            cwd=stubs,
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
        )
    finally:
        up.send_signal(signal.SIGTERM)
        up.wait(60)
    assert sub.returncode == 0, sub.stderr
    lines = sub.stdout.strip().splitlines()
    assert len(lines) == 3 and all("usv.accelerometer.accel_z MIN" in line for line in lines)
    assert any(line.split(" = ")[1] != "no sample in window" for line in lines), lines
    assert frame.returncode == 0, frame.stderr
    rows = frame.stdout.strip().splitlines()
    header = rows[0].split(",")
    assert "value" in header and "topic" in header, rows[0]
    assert len(rows) >= 2, rows  # 5 s of a 2 s AVERAGE: at least one window

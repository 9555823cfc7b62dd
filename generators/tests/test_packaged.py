"""The generators work from installed wheels, with only the files each
Docker image copies: the COPY set of the image's Python stage is reproduced
in a temporary directory (no Docker), wheels of the metamodel and the
generators are built from it and installed, and the integrator download (the
C++ driver projects, which carry the publisher client) is generated from them,
outside the checkout. The client sources are not committed in the
generators: the wheel gets them from runtime/cpp at build time."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from modd_gen.cpp_client import ORIGINALS

REPO = Path(__file__).resolve().parents[2]
UV = shutil.which("uv")
_SCRIPT = r"""
import json, sys
import modd_gen, modd_model
from modd_gen.generate import generate
from modd_model import load_model
model = load_model(sys.argv[1])
files = {a.path: a.content for a in generate(model, "integrator")}
print(json.dumps({"modd_gen": modd_gen.__file__, "modd_model": modd_model.__file__,
                  "files": sorted(files),
                  "client": [p for p, c in files.items() if "class Publisher" in c]}))
"""


def copy_set(dockerfile: Path, stage: str) -> list[tuple[str, str]]:
    """``(source, destination)`` of the COPY lines of one stage (not --from)."""
    pairs, current = [], None
    for line in dockerfile.read_text().splitlines():
        m = re.match(r"FROM \S+ AS (\S+)", line)
        if m:
            current = m.group(1)
        elif current == stage and line.startswith("COPY ") and "--from" not in line:
            *sources, dest = line.split()[1:]
            pairs += [(s, dest) for s in sources]
    return pairs


def reproduce(pairs: list[tuple[str, str]], root: Path) -> None:
    for src, dest in pairs:
        target = root / dest if not dest.endswith("/") and dest not in ("./", ".") else root
        origin = REPO / src
        if origin.is_dir():
            shutil.copytree(
                origin,
                target,
                ignore=shutil.ignore_patterns("__pycache__", "tests", "node_modules", "*.egg-info"),
                dirs_exist_ok=True,
            )
        else:
            if dest.endswith("/") or dest in ("./", "."):
                target = target / origin.name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(origin, target)


@pytest.mark.parametrize(
    ("dockerfile", "stage"), [("backend.Dockerfile", "backend"), ("runtime.Dockerfile", "runtime")]
)
def test_integrator_download_from_installed_wheels(
    tmp_path: Path, dockerfile: str, stage: str
) -> None:
    if UV is None:  # make test installs it (scripts/setup.sh): missing is a setup bug
        pytest.fail("uv is missing: run scripts/setup.sh")
    image = tmp_path / "image"
    pairs = copy_set(REPO / "docker" / dockerfile, stage)
    assert ("generators", "generators") in pairs and ("metamodel", "metamodel") in pairs
    reproduce(pairs, image)
    # Of runtime/cpp, only the client sources the wheel carries (their one home).
    carried = [p.name for p in (image / "runtime" / "cpp").rglob("*") if p.is_file()]
    assert sorted(carried) == sorted(ORIGINALS)
    dist, site = tmp_path / "dist", tmp_path / "site"
    for member in ("metamodel", "generators"):
        subprocess.run(
            [str(UV), "build", "--wheel", "--quiet", "--out-dir", str(dist), str(image / member)],
            check=True,
            timeout=300,
            cwd=image,
        )
    shutil.rmtree(image / "runtime")  # the installed wheel must not need the checkout
    subprocess.run(
        [
            str(UV),
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--python",
            sys.executable,
            "--target",
            str(site),
            *map(str, dist.glob("*.whl")),
        ],
        check=True,
        timeout=300,
    )
    model = image / "metamodel" / "examples" / "demo.modd"
    env = {**os.environ, "PYTHONPATH": str(site)}
    out = subprocess.run(
        [sys.executable, "-c", _SCRIPT, str(model)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
        env=env,
    )
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["modd_gen"].startswith(str(site)) and got["modd_model"].startswith(str(site))
    assert got["client"], got["files"]  # the publisher client travelled in the wheel

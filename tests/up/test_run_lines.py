"""What `make run` prints (scripts/run-lines.sh, sourced by scripts/run.sh):
the URL and the login first, few lines, paths relative to the checkout; and a
second instance's data directory (MODD_PORT=8090: data-8090/, which holds the
admin password and the zenoh credentials) is ignored by git."""

from __future__ import annotations

import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def lines(script: str) -> list[str]:
    res = subprocess.run(
        ["bash", "-c", f". scripts/run-lines.sh; {script}"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
    )
    return res.stdout.splitlines()


def test_url_and_login_first_with_relative_paths() -> None:
    data = REPO / "data-8090"
    first = lines(f"say_workbench http://127.0.0.1:8090 s3cret {data}/admin-password {data}")
    cred = f"{data}/credentials/viewer.cred"
    rest = lines(f"say_running demo usv {data} tcp/127.0.0.1:7457 {cred} 8775 8875 8090")
    assert (
        first[0]
        == "modd: workbench at http://127.0.0.1:8090/  (API docs: http://127.0.0.1:8090/docs)"
    )
    assert first[1].startswith(
        "modd: login 'admin', password 's3cret' (kept in data-8090/admin-password)"
    )
    out = "\n".join(first + rest)
    assert str(REPO) not in out  # relative to the checkout
    assert out.count("viewer.cred") == 1 and "data-8090/credentials/viewer.cred" in out
    # with modd push's two lines, the build line and "Ctrl-C to stop": 8 at most
    assert len(first) + len(rest) + 4 <= 8, out
    assert all(len(line) <= 160 for line in first + rest), out


def test_run_prints_the_login_before_the_deploy() -> None:
    """run.sh says where the workbench is as soon as it answers, before
    `modd push` loads and deploys the demo (which takes seconds)."""
    text = (REPO / "scripts" / "run.sh").read_text()
    answered = text.index('if [ "$up" != 1 ]')
    login = text.index("say_workbench ")
    assert answered < login < text.index("modd push ")
    assert '>>"$DATA/up.log"' in text  # modd up's own lines go to its log


def test_second_instance_data_is_ignored_by_git() -> None:
    for path in (
        "data-8090/admin-password",
        "data-8081/credentials/viewer.cred",
        "data/backend.log",
    ):
        res = subprocess.run(["git", "check-ignore", "-q", path], cwd=REPO, timeout=30)
        assert res.returncode == 0, f"{path} is not ignored by git"

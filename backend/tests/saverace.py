"""Two saves racing on one project, many rounds: a designer's legitimate
edits of the link against a scientist who tries to change the link too
(someone else's part), basing the save on the head or on head+1 (the revision
the designer is about to commit). Oracle: the stored history itself, judged
with roles.owners_of_changes, independent of the route's own check."""

from __future__ import annotations

import threading
from collections import Counter
from typing import Any

from fastapi.testclient import TestClient
from modd_backend.roles import owners_of_changes

from .conftest import Headers


def race_saves(
    client: TestClient,
    admin: Headers,
    designer: Headers,
    scientist: Headers,
    text: str,
    rounds: int,
) -> tuple[list[int], Counter[str]]:
    """(scientist revisions that changed a part not theirs, scientist statuses)."""
    pid = client.post(
        "/api/projects", headers=admin, json={"name": "race", "model": {"text": text}}
    ).json()["id"]
    url = f"/api/projects/{pid}/model"
    statuses: Counter[str] = Counter()
    for i in range(rounds):
        head = client.get(url, headers=designer).json()
        rev, model = head["revision"], head["model"]
        legit = dict(model, link={"maxBuffer": 1000 + i})
        attack = dict(legit, link={"maxBuffer": 7})  # on top of the designer's next one
        honest = dict(model)
        honest["subscribers"] = [dict(s) for s in model["subscribers"]]
        honest["subscribers"][0]["periodS"] = str(2 + i % 3)
        go = threading.Barrier(3)
        got: dict[str, int] = {}

        def put(
            who: str,
            h: Headers,
            base: int,
            body: dict[str, Any],
            go: threading.Barrier = go,
            got: dict[str, int] = got,
        ) -> None:
            go.wait()
            got[who] = client.put(
                url, headers=h, json={"base_revision": base, "model": body}
            ).status_code

        threads = [
            threading.Thread(target=put, args=("designer", designer, rev, legit)),
            threading.Thread(target=put, args=("attack", scientist, rev + 1, attack)),
            threading.Thread(target=put, args=("honest", scientist, rev, honest)),
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        statuses[f"attack {got['attack']}"] += 1
        statuses[f"honest {got['honest']}"] += 1
    history = {
        v["revision"]: v
        for v in client.get(f"/api/projects/{pid}/versions", headers=designer).json()
    }
    bad = []
    for rev in sorted(history):
        if rev == 1 or history[rev]["author"] != "sci":
            continue
        before = client.get(url, headers=designer, params={"revision": rev - 1}).json()["model"]
        after = client.get(url, headers=designer, params={"revision": rev}).json()["model"]
        owners = set(owners_of_changes(before, after).values())
        if not owners <= {"scientist", None}:
            bad.append(rev)
    return bad, statuses

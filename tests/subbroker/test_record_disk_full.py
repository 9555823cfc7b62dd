"""The base-station record on a full disk (issue 23, docs/reliability.md): a write error
never reaches the link thread (live delivery goes on), the values not recorded are
counted, one log line per state change, and recording resumes in a new file once space
returns. The disk is a real 4 MiB tmpfs in a private mount namespace (`unshare -rm`)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from support.namespaces import needs_mount_namespace  # noqa: E402

CHILD = r"""
import json, logging, os, sys, time
from pathlib import Path
from modd.subbroker import record

logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(message)s")
record.RETRY_S = 0.2
root = Path(sys.argv[1])
filler = root / "filler"
with open(filler, "wb") as f:  # leave 256 KiB: the first 1 MiB chunk cannot be written
    free = os.statvfs(root).f_bavail * os.statvfs(root).f_frsize
    f.write(b"\0" * (free - 256 * 1024))
rec = record.BaseRecord(root, "usv")
rec.begin("m", time.time_ns())
out = {"raised": None}
def put(i):
    value = os.urandom(256).hex()  # incompressible: the chunk really takes room
    rec.put("s", json.dumps({"value": value, "start_ns": i, "end_ns": i + 1}).encode())
i = 0
try:
    while rec.dropped == 0 and i < 20000:
        put(i); i += 1
    out["failed_after"] = i
    for _ in range(50):
        put(i); i += 1
    out["dropped_while_full"] = rec.dropped
    first = rec.path
    filler.unlink()  # space back
    time.sleep(0.3)
    resumed_at = i
    for _ in range(2000):
        put(i); i += 1
    out["second_file"] = str(rec.path) if rec.path != first else None
    out["resumed_at"] = resumed_at
    out["dropped"] = rec.dropped
    rec.close()
except Exception as exc:
    out["raised"] = repr(exc)
print(json.dumps(out))
"""


@needs_mount_namespace
def test_a_full_disk_never_stops_delivery_and_the_record_resumes(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    root, out = tmp_path / "records", tmp_path / "out"
    root.mkdir()
    out.mkdir()
    script = (
        f"mount -t tmpfs -o size=4m tmpfs '{root}' || exit 97\n"
        f"'{sys.executable}' -c \"$CHILD\" '{root}'; rc=$?\n"
        f"rm -f '{root}/filler'; cp -a '{root}/.' '{out}/'; exit $rc\n"
    )
    r = subprocess.run(
        ["unshare", "-rm", "sh", "-c", script],
        capture_output=True,
        text=True,
        timeout=120,
        env={"CHILD": CHILD, "PATH": "/usr/bin:/bin"},
    )
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout.strip().splitlines()[-1])
    assert res["raised"] is None, res  # put() never raised into the link thread
    assert res["dropped_while_full"] > 0
    assert r.stderr.count("write failed") == 1, r.stderr  # one line per state change
    assert r.stderr.count("writing again") == 1, r.stderr
    assert res["second_file"], res
    second = out / Path(res["second_file"]).relative_to(root)
    with open(second, "rb") as f:  # the new file is whole, with what came after the space
        reader = make_reader(f)
        ends = [json.loads(m.data)["end_ns"] - 1 for _, _, m in reader.iter_messages()]
    assert ends == list(range(res["resumed_at"], res["resumed_at"] + 2000))
    assert res["dropped"] == res["dropped_while_full"]  # nothing dropped after the space came back

"""The pairing bundle and ``modd-pair``: a byte flipped anywhere, a bundle for
another drone, a wrong code, an older bundle, another station's, an expired
one are refused with their reason and nothing is written; a good one writes
the drone's files atomically with the key 0600."""

from __future__ import annotations

import json
import os
import pwd
import time
from pathlib import Path
from typing import Any

import pytest
from modd.link.auth import resolve_key
from modd.pairing import bundle as pb
from modd.pairing.cli import main

NOW = time.time_ns()
KEY = "5a" * 32
FILES: dict[str, Any] = {
    "pubbroker.json": {"name": "usv", "link": {"host": "127.0.0.1", "port": 7171, "key": "env:X"}},
    "model.json": {"drone": {"name": "usv"}},
    "link.key": KEY,
}


@pytest.fixture(scope="module")
def station() -> Any:
    return pb.new_signing_key()


@pytest.fixture(scope="module")
def sealed(station: Any) -> tuple[bytes, str]:
    return pb.seal(station, "usv", FILES, NOW)


def pair(tmp_path: Path, data: bytes, code: str, *extra: str, name: str = "b") -> tuple[int, str]:
    path = tmp_path / f"{name}.modd-pair"
    path.write_bytes(data)
    (tmp_path / "code").write_text(code + "\n")
    argv = [str(path), "--config-dir", str(tmp_path / "etc"), "--code-file", str(tmp_path / "code")]
    return main([*argv, *extra]), ""


def test_round_trip_writes_the_files(
    tmp_path: Path, sealed: tuple[bytes, str], capsys: pytest.CaptureFixture[str]
) -> None:
    data, code = sealed
    assert pair(tmp_path, data, code.lower().replace("-", " "))[0] == 0
    etc = tmp_path / "etc"
    assert (etc / "link.key").stat().st_mode & 0o777 == 0o600
    assert (etc / "pubbroker.json").stat().st_mode & 0o777 == 0o644
    config = json.loads((etc / "pubbroker.json").read_text())
    assert config["link"]["key"] == f"file:{etc.absolute() / 'link.key'}"
    assert resolve_key(config["link"]["key"]) == KEY.encode()  # as the brokers read it
    assert json.loads((etc / "model.json").read_text()) == FILES["model.json"]
    assert [p.name for p in etc.iterdir() if p.name.startswith(".")] == []  # no temporary left
    out = capsys.readouterr()
    assert (
        "paired with base station SHA256:" in out.out
        and "systemctl restart modd-pubbroker" in out.out
    )
    assert KEY not in out.out + out.err and code not in out.out + out.err


def test_every_flipped_byte_is_refused(sealed: tuple[bytes, str]) -> None:
    data, code = sealed
    for i in range(len(data)):
        for flip in (0x01, 0x20, 0x80):
            bad = bytearray(data)
            bad[i] ^= flip
            with pytest.raises(pb.BundleError) as err:
                pb.open_bundle(bytes(bad), code, NOW)
            why = str(err.value)
            assert any(w in why for w in ("altered", "not a pairing bundle", "version")), (i, why)


def test_each_field_changed_and_re_serialised_fails_the_signature(
    sealed: tuple[bytes, str],
) -> None:
    """A tamperer who writes a canonical file still meets the signature, field by field."""
    doc = json.loads(sealed[0])
    changes = {
        "drone": "asv",
        "issued_ns": NOW + 1,
        "expires_ns": NOW + 10**18,
        "station": {**doc["station"], "fingerprint": "SHA256:00"},
        "kdf": {**doc["kdf"], "salt": "AAAAAAAAAAAAAAAAAAAAAA=="},
        "aead": {**doc["aead"], "nonce": "AAAAAAAAAAAAAAAA"},
        "ciphertext": doc["ciphertext"][:-4] + "AAA=",
    }
    for name, value in changes.items():
        with pytest.raises(pb.BundleError, match="signature does not hold"):
            pb.verify(pb.canonical({**doc, name: value}))


def test_a_bundle_re_signed_by_another_key_is_refused_by_a_paired_drone(
    tmp_path: Path, sealed: tuple[bytes, str], capsys: pytest.CaptureFixture[str]
) -> None:
    data, code = sealed
    assert pair(tmp_path, data, code)[0] == 0
    other, other_code = pb.seal(pb.new_signing_key(), "usv", FILES, NOW + 1)
    assert pair(tmp_path, other, other_code, name="o")[0] == 1
    assert "signed by base station SHA256:" in capsys.readouterr().err
    assert pair(tmp_path, other, other_code, "--new-station", name="o")[0] == 0


def test_another_drone_s_bundle_names_both(
    tmp_path: Path, station: Any, sealed: tuple[bytes, str], capsys: pytest.CaptureFixture[str]
) -> None:
    data, code = sealed
    assert pair(tmp_path, data, code)[0] == 0  # this drone is usv now (its pubbroker.json)
    asv, asv_code = pb.seal(station, "asv", {**FILES, "model.json": {}}, NOW + 1)
    before = (tmp_path / "etc" / "pubbroker.json").read_bytes()
    assert pair(tmp_path, asv, asv_code, name="asv")[0] == 1
    err = capsys.readouterr().err
    assert "this bundle is for drone 'asv', but this drone is 'usv'" in err
    assert (tmp_path / "etc" / "pubbroker.json").read_bytes() == before
    assert pair(tmp_path, asv, asv_code, "--drone", "usv", name="asv")[0] == 1


def test_wrong_code_and_malformed_code(
    tmp_path: Path, sealed: tuple[bytes, str], capsys: pytest.CaptureFixture[str]
) -> None:
    data, code = sealed
    wrong = "0" * 20 if code.replace("-", "") != "0" * 20 else "1" * 20
    assert pair(tmp_path, data, wrong)[0] == 1
    assert "wrong pairing code" in capsys.readouterr().err
    assert pair(tmp_path, data, "12345")[0] == 1
    assert "should be 20 letters and digits" in capsys.readouterr().err
    assert not (tmp_path / "etc").exists()


def test_an_older_or_the_same_bundle_is_refused_after_a_newer(
    tmp_path: Path, station: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    old, old_code = pb.seal(station, "usv", FILES, NOW - 10**9)
    new, new_code = pb.seal(station, "usv", FILES, NOW)
    assert pair(tmp_path, new, new_code, name="new")[0] == 0
    for data, code in ((old, old_code), (new, new_code)):
        assert pair(tmp_path, data, code, name="again")[0] == 1
        assert "is not newer than the one imported last" in capsys.readouterr().err


def test_expired_and_future_bundles(station: Any) -> None:
    data, code = pb.seal(station, "usv", FILES, NOW)
    with pytest.raises(pb.BundleError, match="expired"):
        pb.open_bundle(data, code, NOW + (pb.LIFETIME_S + 1) * 10**9)
    with pytest.raises(pb.BundleError, match="in this drone's future"):
        pb.open_bundle(data, code, NOW - 3600 * 10**9)


def test_code_from_standard_input_and_owner(
    tmp_path: Path, sealed: tuple[bytes, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import io
    import sys

    data, code = sealed
    (tmp_path / "b.modd-pair").write_bytes(data)
    monkeypatch.setattr(sys, "stdin", io.StringIO(code + "\n"))
    me = pwd.getpwuid(os.getuid()).pw_name
    argv = [str(tmp_path / "b.modd-pair"), "--root", str(tmp_path / "img"), "--code-file", "-"]
    assert main([*argv, "--owner", me]) == 0
    key = tmp_path / "img" / "etc" / "modd" / "link.key"
    assert key.stat().st_uid == os.getuid() and key.stat().st_mode & 0o777 == 0o600
    assert main([*argv, "--owner", "no-such-user-here"]) == 1


def test_not_a_bundle_and_unexpected_files(tmp_path: Path, station: Any) -> None:
    with pytest.raises(pb.BundleError, match="not a pairing bundle"):
        pb.verify(b'{"format":"zip"}\n')
    with pytest.raises(pb.BundleError, match="more than"):
        pb.verify(b" " * (pb.MAX_BUNDLE_BYTES + 1))
    data, code = pb.seal(station, "usv", {**FILES, "../../etc/passwd": "x"}, NOW)
    assert pair(tmp_path, data, code)[0] == 1
    assert not (tmp_path / "etc").exists()

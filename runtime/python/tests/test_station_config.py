"""``python -m modd.station --config``: a station.toml's ``[zenoh]`` (as ``modd generate
--station`` writes it for a campaign), the command line's --listen/--id/--peer over it,
and a bad file refused with its place named."""

from __future__ import annotations

from pathlib import Path

import pytest
from modd.station import _parser, settings_of
from modd.zenoh_session import ZenohSettings

GOOD = """
[zenoh]
listen = ["tcp/0.0.0.0:7447"]
[zenoh.mesh]
id = "a1"
[zenoh.mesh.peers]
b2 = "tcp/station-b.example:7447"
"""


def settings(tmp_path: Path, text: str, *extra: str) -> ZenohSettings:
    path = tmp_path / "station.toml"
    path.write_text(text)
    return settings_of(_parser().parse_args(["--config", str(path), "--credentials", "x", *extra]))


def test_the_file_gives_the_router_its_listen_and_mesh(tmp_path: Path) -> None:
    s = settings(tmp_path, GOOD)
    assert s.mode == "router" and s.listen == ("tcp/0.0.0.0:7447",)
    assert s.mesh is not None and s.mesh.station == "a1"
    assert dict(s.mesh.peers) == {"b2": "tcp/station-b.example:7447"}


def test_the_command_line_replaces_what_the_file_says(tmp_path: Path) -> None:
    s = settings(tmp_path, GOOD, "--listen", "tcp/127.0.0.1:7500", "--id", "c3")
    assert s.listen == ("tcp/127.0.0.1:7500",)
    assert s.mesh is not None and s.mesh.station == "c3" and not s.mesh.peers


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("[zenoh\n", "station.toml: "),
        ('[link]\nendpoint = "x"\n', "unknown table 'link'"),
        ('[zenoh]\nmode = "client"\n', "zenoh.mode: a station is a router"),
        ("[zenoh]\nlisten = 7447\n", "zenoh.listen: expected a list"),
        ('[zenoh.mesh]\nid = "a1"\nwho = 1\n', "zenoh.mesh: unknown key 'who'"),
        ("[zenoh]\nverbose = true\n", "zenoh: unknown key 'verbose'"),
    ],
)
def test_a_bad_file_is_refused_with_its_place(tmp_path: Path, text: str, says: str) -> None:
    with pytest.raises(ValueError, match="station.toml") as err:
        settings(tmp_path, text)
    assert says in str(err.value)


def test_a_missing_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="nowhere.toml: cannot read"):
        settings_of(
            _parser().parse_args(["--config", str(tmp_path / "nowhere.toml"), "--credentials", "x"])
        )

"""Why ``assert_compliant`` allows one high-priority IOOS 1.2 result: the compliance
checker's "NDBC/GTS Ingest Requirements" fails on every file, an empty one too
(checkers.GTS). Should a release make it pass where nothing is marked for ingest,
this test fails, and the dataset tests must then ask for 0 high-priority failures."""

from __future__ import annotations

from pathlib import Path

from checkers import GTS, cc_results


def test_the_gts_listing_fails_on_an_empty_file(tmp_path: Path) -> None:
    import netCDF4

    empty = tmp_path / "empty.nc"
    netCDF4.Dataset(empty, "w").close()
    results = cc_results(empty, tmp_path / "cc.json", ("ioos:1.2",))
    (gts,) = [r for r in results["ioos:1.2"]["high_priorities"] if r["name"] == GTS]
    assert gts["value"][0] < gts["value"][1], gts  # failed, with nothing to ingest
    assert gts["msgs"] == ["The following variables qualified for NDBC/GTS Ingest: \n"], gts

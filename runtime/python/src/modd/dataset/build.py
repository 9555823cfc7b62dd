"""One call from request to file: pick the sink for the format, run the
export into a temporary file beside the output, and move it into place only
when it is complete (a failed export leaves nothing behind). Used by
``modd dataset`` and the backend's export route.

>>> make_dataset([Path("archive/")], model, "netcdf", Path("mission.nc"))  # doctest: +SKIP
"""

from __future__ import annotations

import os
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

from . import netcdf, tables, tracks
from .export import Options, Sink, Summary, export, find_files, print_progress
from .mcapread import ArchiveError, read_file
from .metadata import Metadata
from .plan import ExportPlan, PlanError, plan_export
from .received import plan_received, read_record
from .resample import Resampler, WideTable

#: GeoJSON and GPX are tracks: one point per period, this one unless resample_s says.
TRACK_PERIOD_S = 1.0
SUFFIXES = {
    "netcdf": ".nc",
    "parquet": ".parquet",
    "csv": ".csv",
    "geojson": ".geojson",
    "gpx": ".gpx",
}


def _notes_in_history(path: Path, notes: list[str]) -> None:
    """The export's notes (dropped glitches, sorted fixes, gaps, unnamed quantities) in
    the file too, after its ``history`` line: CF's audit trail of what was done to the
    data, which ERDDAP and the IOOS tools show."""
    if not notes:
        return
    import netCDF4

    with netCDF4.Dataset(path, "a") as ds:
        ds.setncattr("history", ds.getncattr("history") + "".join(f"\n  note: {n}" for n in notes))


def metadata_notes(plan: ExportPlan) -> list[str]:
    """What a data centre will ask for that the dataset metadata does not say."""
    unnamed = [v.topic for v in plan.variables.values() if not v.standard_name]
    out = (
        [
            f"no CF standard name for {', '.join(unnamed)} (ACDD asks for one; "
            "declare standardName in the model where the CF table has a name for it)"
        ]
        if unnamed
        else []
    )
    missing = plan.metadata.missing()
    if not missing:
        return out
    where = plan.metadata.source or "no dataset metadata (--metadata FILE, or dataset.yaml"
    where += "" if plan.metadata.source else " beside the model)"
    return out + [
        f"{where}: ACDD 1.3 / IOOS 1.2 ask for {', '.join(missing)}; "
        "left out (docs/user-guide/datasets.md, Metadata)"
    ]


class DatasetError(Exception):
    """Why a dataset could not be made, located (file and offset, topic, option)."""


def _sink(fmt: str, out: Path, resample_s: float | None) -> Sink:
    if fmt in ("geojson", "gpx"):
        write = tracks.write_geojson if fmt == "geojson" else tracks.write_gpx
        return Resampler(resample_s or TRACK_PERIOD_S, partial(write, out))
    if resample_s is None:
        return netcdf.NetcdfSink(out) if fmt == "netcdf" else tables.TableSink(out, fmt)
    if fmt == "netcdf":
        return Resampler(resample_s, partial(netcdf.write_wide, out))

    def wide(plan: ExportPlan, table: WideTable, summary: Summary) -> None:
        tables.write_wide(out, fmt, plan, table)

    return Resampler(resample_s, wide)


def make_dataset(
    paths: list[Path],
    model: dict[str, Any],
    fmt: str,
    out: Path,
    *,
    start_ns: int | None = None,
    end_ns: int | None = None,
    topics: list[str] | None = None,
    resample_s: float | None = None,
    progress: bool = False,
    options: Options | None = None,
    received: bool = False,
    metadata: Metadata | None = None,
    clock: str = "receive",
) -> Summary:
    """Writes the dataset to ``out``; raises DatasetError. With ``received``,
    ``paths`` are base-station records and the dataset holds the windows the
    subscribers received (``topics`` then names subscribers or their topics)."""
    if fmt not in SUFFIXES:
        raise DatasetError(f"unknown format {fmt!r}; one of {', '.join(SUFFIXES)}")
    tmp = out.with_name(f".{out.name}.{os.getpid()}.part")
    try:
        plan = (
            plan_received(model, topics, start_ns, end_ns)
            if received
            else plan_export(model, topics, start_ns, end_ns)
        )
        if metadata is not None:
            plan = replace(plan, metadata=metadata)
        plan = replace(plan, clock=clock)
        if clock == "instrument" and not plan.two_clocks:
            raise PlanError(
                "--time instrument: no sensor of the chosen topics declares "
                "clock = instrument (the archive has their receive time only)"
            )
        if fmt in ("geojson", "gpx") and plan.position is None:
            raise PlanError(
                f"a {fmt} track needs the platform's position, and the model "
                "declares none (Position { latitude = ...; longitude = ...; })"
            )
        files = find_files(paths)
        summary = export(
            files,
            plan,
            _sink(fmt, tmp, resample_s),
            options or Options(),
            print_progress if progress else None,
            read_record if received else read_file,
        )
        if summary.samples == 0:
            what = "window of the chosen subscribers" if received else "sample of the chosen topics"
            hint = (
                "; a record being written is read up to its last complete chunk" if received else ""
            )
            raise PlanError(f"nothing to export: no {what} in the range{hint}")
        if fmt == "netcdf":
            summary.notes += metadata_notes(plan)
            _notes_in_history(tmp, summary.notes)
        os.replace(tmp, out)
        return summary
    except (PlanError, ArchiveError) as exc:
        raise DatasetError(str(exc)) from None
    except OSError as exc:
        where = exc.filename or out
        raise DatasetError(f"{where}: {exc.strerror or exc}") from None
    finally:
        tmp.unlink(missing_ok=True)

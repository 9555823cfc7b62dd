"""Parquet and CSV, in two forms: long (tidy: one row per sample, columns
``time, topic, value, unit, lat, lon, alt``) and, with ``--resample``, wide
(one row per period, one column per topic, named ``<sensor>_<variable>``).
Written through Arrow in row groups of about a million rows, so memory stays
bounded; times are UTC timestamps in nanoseconds.

Parquet also carries what the data mean (tablemeta.py): each topic's unit,
standard and long name in the schema's ``modd`` metadata (and the wide
form's fields), the model's revision, and a GeoParquet 1.1 ``geometry``
column (WKB points, longitude and latitude). CSV writes a missing value as
an empty cell and times as ISO 8601 (``2026-11-27T10:00:00.000000000Z``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .export import NAT, Summary
from .plan import ExportPlan, Variable
from .position import Track
from .qc import location_config, qc_config
from .resample import WideTable
from .tablemeta import iso_times, schema_metadata, with_field_metadata, wkb_points

ROWS_PER_GROUP = 1 << 20


def _time_type(fmt: str) -> Any:
    import pyarrow as pa

    return pa.timestamp("ns", tz="UTC") if fmt == "parquet" else pa.string()


def _long_schema(
    fmt: str,
    other: str | None = None,
    qc: bool = False,
    historical: bool = False,
    location: bool = False,
) -> Any:
    import pyarrow as pa

    fields = [
        ("time", _time_type(fmt)),
        ("topic", pa.dictionary(pa.int32(), pa.string())),
        ("value", pa.float64()),
        ("unit", pa.dictionary(pa.int32(), pa.string())),
        ("lat", pa.float64()),
        ("lon", pa.float64()),
        ("alt", pa.float64()),
    ]
    if other is not None:  # the second clock (docs/user-guide/datasets.md, "Both clocks")
        fields.append((other, _time_type(fmt)))
    if qc:  # the aggregate QARTOD flag (qc.py); empty for a topic without tests
        fields.append(("qc_agg", pa.uint8()))
    if historical:  # a received window: 1 backfilled (delivered late), 0 live
        fields.append(("backfilled", pa.uint8()))
    if location:  # the location test's flag of the row's position (qc.py)
        fields.append(("location_qc_agg", pa.uint8()))
    if fmt == "parquet":
        fields.append(("geometry", pa.binary()))
    return pa.schema(fields)


def _times(time_ns: np.ndarray, csv: bool) -> Any:
    """A time column: ISO 8601 text for CSV, UTC ns for Parquet; NAT is null."""
    import pyarrow as pa

    missing = time_ns == NAT
    if csv:
        return pa.array(iso_times(time_ns), mask=missing if missing.any() else None)
    return pa.array(time_ns, pa.timestamp("ns", tz="UTC"), mask=missing if missing.any() else None)


class TableSink:
    """The long form into a Parquet (``fmt="parquet"``) or CSV file."""

    def __init__(self, path: Path, fmt: str) -> None:
        self.path, self.fmt = path, fmt
        self.writer: Any = None
        self.schema: Any = None
        self.parts: list[Any] = []
        self.rows = 0
        self.qc = False
        self.historical = False
        self.location = False

    def open(self, plan: ExportPlan, track: Track | None) -> None:
        import pyarrow.csv as pcsv
        import pyarrow.parquet as pq

        self.qc = bool(qc_config(plan))
        other = plan.other_clock if plan.two_clocks else None
        self.historical = plan.source == "received"
        self.location = location_config(plan) is not None
        self.schema = _long_schema(self.fmt, other, self.qc, self.historical, self.location)
        if self.fmt == "parquet":
            self.schema = self.schema.with_metadata(schema_metadata(plan, long_form=True))
            self.writer = pq.ParquetWriter(self.path, self.schema, compression="zstd")
        else:
            self.writer = pcsv.CSVWriter(self.path, self.schema)

    def write(
        self,
        var: Variable,
        time_ns: np.ndarray,
        value: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        other: np.ndarray | None = None,
        qc: np.ndarray | None = None,
        historical: np.ndarray | None = None,
        location: np.ndarray | None = None,
    ) -> None:
        import pyarrow as pa

        n = len(time_ns)
        topic = pa.DictionaryArray.from_arrays(np.zeros(n, np.int32), pa.array([var.topic]))
        unit = pa.DictionaryArray.from_arrays(np.zeros(n, np.int32), pa.array([var.unit]))
        csv = self.fmt == "csv"
        columns = [
            _times(time_ns, csv),
            topic,
            pa.array(value.astype(np.float64), from_pandas=csv),
            unit,
            pa.array(lat, from_pandas=csv),
            pa.array(lon, from_pandas=csv),
            pa.array(alt, from_pandas=csv),
        ]
        if other is not None:
            columns.append(_times(other, csv))
        if self.qc:
            columns.append(pa.array(qc) if qc is not None else pa.nulls(n, pa.uint8()))
        if self.historical:
            marks = historical if historical is not None else np.zeros(n, bool)
            columns.append(pa.array(marks.astype(np.uint8)))
        if self.location:
            columns.append(pa.array(location) if location is not None else pa.nulls(n, pa.uint8()))
        if not csv:
            columns.append(wkb_points(lon, lat))
        self.parts.append(pa.record_batch(columns, schema=self.schema))
        self.rows += n
        if self.rows >= ROWS_PER_GROUP:
            self._flush()

    def _flush(self) -> None:
        import pyarrow as pa

        if self.parts:
            table = pa.Table.from_batches(self.parts)
            if self.fmt == "parquet":
                self.writer.write_table(table, row_group_size=ROWS_PER_GROUP)
            else:
                self.writer.write_table(table)
        self.parts, self.rows = [], 0

    def close(self, plan: ExportPlan, summary: Summary) -> None:
        self._flush()
        self.writer.close()


def write_wide(path: Path, fmt: str, plan: ExportPlan, table: WideTable) -> None:
    """The wide form: ``time, lat, lon, alt`` then one column per topic, then
    (received windows) ``backfilled`` (Parquet: then ``geometry``)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    csv = fmt == "csv"
    cols: dict[str, Any] = {
        "time": _times(table.time_ns, csv),
        "lat": pa.array(table.lat, from_pandas=csv),
        "lon": pa.array(table.lon, from_pandas=csv),
        "alt": pa.array(table.alt, from_pandas=csv),
    }
    for var in plan.variables.values():
        cols[var.name] = pa.array(table.columns[var.topic], pa.float64(), from_pandas=csv)
    if table.historical is not None:  # received: 1 where a backfilled window is in the mean
        cols["backfilled"] = pa.array(table.historical, pa.uint8())
    if csv:
        pcsv.write_csv(pa.table(cols), path)
        return
    cols["geometry"] = wkb_points(table.lon, table.lat)
    arrow = pa.table(cols)
    meta = schema_metadata(plan, long_form=False, period_s=table.period_s)
    arrow = pa.Table.from_arrays(
        arrow.columns, schema=with_field_metadata(arrow.schema, plan).with_metadata(meta)
    )
    pq.write_table(arrow, path, compression="zstd")

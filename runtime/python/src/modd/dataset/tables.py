"""Parquet and CSV, in two forms: long (tidy: one row per sample, columns
``time, topic, value, unit, lat, lon, alt``) and, with ``--resample``, wide
(one row per period, one column per topic, named ``<sensor>_<variable>``).
Written through Arrow in row groups of about a million rows, so memory stays
bounded; times are UTC timestamps in nanoseconds.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .export import Summary
from .plan import ExportPlan, Variable
from .position import Track
from .resample import WideTable

ROWS_PER_GROUP = 1 << 20


def _long_schema() -> Any:
    import pyarrow as pa

    return pa.schema(
        [
            ("time", pa.timestamp("ns", tz="UTC")),
            ("topic", pa.dictionary(pa.int32(), pa.string())),
            ("value", pa.float64()),
            ("unit", pa.dictionary(pa.int32(), pa.string())),
            ("lat", pa.float64()),
            ("lon", pa.float64()),
            ("alt", pa.float64()),
        ]
    )


class TableSink:
    """The long form into a Parquet (``fmt="parquet"``) or CSV file."""

    def __init__(self, path: Path, fmt: str) -> None:
        self.path, self.fmt = path, fmt
        self.writer: Any = None
        self.parts: list[Any] = []
        self.rows = 0

    def open(self, plan: ExportPlan, track: Track | None) -> None:
        import pyarrow.csv as pcsv
        import pyarrow.parquet as pq

        schema = _long_schema()
        if self.fmt == "parquet":
            self.writer = pq.ParquetWriter(self.path, schema, compression="zstd")
        else:
            self.writer = pcsv.CSVWriter(self.path, schema)

    def write(
        self,
        var: Variable,
        time_ns: np.ndarray,
        value: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
    ) -> None:
        import pyarrow as pa

        n = len(time_ns)
        topic = pa.DictionaryArray.from_arrays(np.zeros(n, np.int32), pa.array([var.topic]))
        unit = pa.DictionaryArray.from_arrays(np.zeros(n, np.int32), pa.array([var.unit]))
        self.parts.append(
            pa.record_batch(
                [
                    pa.array(time_ns, pa.timestamp("ns", tz="UTC")),
                    topic,
                    pa.array(value.astype(np.float64)),
                    unit,
                    pa.array(lat),
                    pa.array(lon),
                    pa.array(alt),
                ],
                schema=_long_schema(),
            )
        )
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
    """The wide form: ``time, lat, lon, alt`` then one column per topic."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    cols: dict[str, Any] = {
        "time": pa.array(table.time_ns, pa.timestamp("ns", tz="UTC")),
        "lat": table.lat,
        "lon": table.lon,
        "alt": table.alt,
    }
    for var in plan.variables.values():
        cols[var.name] = table.columns[var.topic]
    arrow = pa.table(cols)
    meta = {f"unit:{v.name}": v.unit for v in plan.variables.values()}
    meta["resample_period_s"] = f"{table.period_s:g}"
    arrow = arrow.replace_schema_metadata(meta)
    if fmt == "parquet":
        pq.write_table(arrow, path, compression="zstd")
    else:
        pcsv.write_csv(arrow, path)

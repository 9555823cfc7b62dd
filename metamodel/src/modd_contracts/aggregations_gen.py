"""Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.

The aggregation table (metamodel/modd.schema.json, ``Aggregation`` x-table):
one row per aggregation, in wire-code order.

>>> BY_NAME["AVERAGE"].result["int"]
'float64'
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Final

#: Each aggregation's name, for code that compares or builds one
#: (``aggregation == AVERAGE``); typed as its ``Literal``.
MIN: Final = "MIN"
MAX: Final = "MAX"
AVERAGE: Final = "AVERAGE"
FIRST: Final = "FIRST"
LAST: Final = "LAST"
ALL: Final = "ALL"
COUNT: Final = "COUNT"
SUM: Final = "SUM"
MEDIAN: Final = "MEDIAN"
STDDEV: Final = "STDDEV"
RANGE: Final = "RANGE"
PERCENTILE: Final = "PERCENTILE"
ON_CHANGE: Final = "ON_CHANGE"
THRESHOLD: Final = "THRESHOLD"


class Aggregation(IntEnum):
    """The wire code of each aggregation (docs/protocol.md); the enum order is
    the stream-id order of the plan contract."""

    MIN = 0
    MAX = 1
    AVERAGE = 2
    FIRST = 3
    LAST = 4
    ALL = 5
    COUNT = 6
    SUM = 7
    MEDIAN = 8
    STDDEV = 9
    RANGE = 10
    PERCENTILE = 11
    ON_CHANGE = 12
    THRESHOLD = 13


@dataclass(frozen=True)
class AggregationSpec:
    """One aggregation: see the schema's ``x-table-doc`` for each field."""

    name: str
    code: int
    numeric_only: bool
    wire_count: bool
    keeps_samples: bool
    result: dict[str, str]
    derivable_from: tuple[str, ...]
    derivable_from_pair: tuple[str, str] | None


AGGREGATIONS: tuple[AggregationSpec, ...] = (
    AggregationSpec(
        name='MIN',
        code=0,
        numeric_only=False,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=('MIN', 'ALL'),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='MAX',
        code=1,
        numeric_only=False,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=('MAX', 'ALL'),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='AVERAGE',
        code=2,
        numeric_only=True,
        wire_count=True,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'float64', 'bool': 'float32'},
        derivable_from=('AVERAGE', 'ALL'),
        derivable_from_pair=('SUM', 'COUNT'),
    ),
    AggregationSpec(
        name='FIRST',
        code=3,
        numeric_only=False,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=('FIRST', 'ALL'),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='LAST',
        code=4,
        numeric_only=False,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=('LAST', 'ALL'),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='ALL',
        code=5,
        numeric_only=False,
        wire_count=False,
        keeps_samples=True,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=('ALL',),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='COUNT',
        code=6,
        numeric_only=False,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'int', 'float64': 'int', 'int': 'int', 'bool': 'int'},
        derivable_from=('COUNT', 'AVERAGE', 'ALL'),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='SUM',
        code=7,
        numeric_only=True,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'int'},
        derivable_from=('SUM', 'ALL'),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='MEDIAN',
        code=8,
        numeric_only=True,
        wire_count=False,
        keeps_samples=True,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'float64', 'bool': 'float32'},
        derivable_from=('ALL',),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='STDDEV',
        code=9,
        numeric_only=True,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'float64', 'bool': 'float32'},
        derivable_from=('ALL',),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='RANGE',
        code=10,
        numeric_only=True,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'int'},
        derivable_from=('ALL',),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='PERCENTILE',
        code=11,
        numeric_only=True,
        wire_count=False,
        keeps_samples=True,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'float64', 'bool': 'float32'},
        derivable_from=('ALL',),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='ON_CHANGE',
        code=12,
        numeric_only=False,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=(),
        derivable_from_pair=None,
    ),
    AggregationSpec(
        name='THRESHOLD',
        code=13,
        numeric_only=True,
        wire_count=False,
        keeps_samples=False,
        result={'float32': 'float32', 'float64': 'float64', 'int': 'int', 'bool': 'bool'},
        derivable_from=(),
        derivable_from_pair=None,
    ),
)
#: The rows by name.
BY_NAME: dict[str, AggregationSpec] = {a.name: a for a in AGGREGATIONS}
#: The names in wire-code order.
NAMES: tuple[str, ...] = tuple(a.name for a in AGGREGATIONS)

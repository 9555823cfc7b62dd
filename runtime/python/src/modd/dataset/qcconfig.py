"""The ``qc`` section of a dataset metadata file (qc.py runs the tests):
``{topic: {ioos_qc test: {parameter: value}}}``, checked with located errors;
the key ``position`` holds the platform position's ``location_test``.

>>> parse_qc({"usv.ctd.t": {"spike_test": {"suspect_threshold": 1}}}, "m.yaml")
{'usv.ctd.t': {'spike_test': {'suspect_threshold': 1.0}}}
>>> parse_qc({"usv.ctd.t": {"spike": {}}}, "m.yaml")
Traceback (most recent call last):
...
modd.dataset.qcconfig.QcConfigError: m.yaml: qc.usv.ctd.t: unknown test 'spike'; one of \
gross_range_test, spike_test, rate_of_change_test, flat_line_test
"""

from __future__ import annotations

import math
from typing import Any


class QcConfigError(ValueError):
    """A ``qc`` section that cannot be used, located (file, key)."""


#: The key of the platform's position in the ``qc`` section (not a topic: the position is
#: two topics, latitude and longitude), and its one test.
POSITION = "position"
LOCATION_TESTS: dict[str, dict[str, tuple[str, bool]]] = {
    "location_test": {"bbox": ("bbox", False)},
}
#: Each test's parameters: a number, or a pair of numbers (a span), and which are required.
TESTS: dict[str, dict[str, tuple[str, bool]]] = {
    "gross_range_test": {"fail_span": ("span", True), "suspect_span": ("span", False)},
    "spike_test": {"suspect_threshold": ("number", False), "fail_threshold": ("number", False)},
    "rate_of_change_test": {"threshold": ("number", True), "fail_threshold": ("number", False)},
    "flat_line_test": {
        "suspect_threshold": ("number", True),
        "fail_threshold": ("number", True),
        "tolerance": ("number", False),
    },
}
QcConfig = dict[str, dict[str, dict[str, Any]]]


def _param(value: Any, kind: str, where: str) -> Any:
    def number(v: Any) -> bool:
        return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)

    if kind == "number" and number(value):
        return float(value)
    if kind == "bbox" and isinstance(value, list) and len(value) == 4 and all(map(number, value)):
        if value[0] >= value[2] or value[1] >= value[3]:
            raise QcConfigError(
                f"{where}: [lon_min, lat_min, lon_max, lat_max], min < max, not {value}"
            )
        return [float(v) for v in value]
    if kind == "span" and isinstance(value, list) and len(value) == 2 and all(map(number, value)):
        if value[0] > value[1]:
            raise QcConfigError(f"{where}: [low, high] with low <= high, not {value}")
        return [float(value[0]), float(value[1])]
    want = {
        "number": "a number",
        "span": "a pair of numbers [low, high]",
        "bbox": "four numbers [lon_min, lat_min, lon_max, lat_max]",
    }[kind]
    raise QcConfigError(f"{where}: {want}, not {value!r}")


def _test(
    name: str, params: Any, where: str, tests: dict[str, dict[str, tuple[str, bool]]] = TESTS
) -> dict[str, Any]:
    if name not in tests:
        raise QcConfigError(f"{where}: unknown test {name!r}; one of {', '.join(tests)}")
    spec, here = tests[name], f"{where}.{name}"
    if not isinstance(params, dict):
        raise QcConfigError(f"{here}: a mapping of parameters ({', '.join(spec)})")
    unknown = sorted(str(k) for k in params if k not in spec)
    if unknown:
        raise QcConfigError(f"{here}: unknown parameter {unknown[0]!r}; one of {', '.join(spec)}")
    missing = [k for k, (_, required) in spec.items() if required and k not in params]
    if missing:
        raise QcConfigError(f"{here}: {missing[0]} is required")
    return {k: _param(v, spec[k][0], f"{here}.{k}") for k, v in params.items()}


def parse_qc(doc: Any, source: str) -> QcConfig:
    """The ``qc`` section: ``{topic: {test: {parameter: value}}}``; QcConfigError located."""
    if not isinstance(doc, dict):
        raise QcConfigError(f"{source}: qc: a mapping of topics to their tests")
    out: QcConfig = {}
    for topic, tests in doc.items():
        where = f"{source}: qc.{topic}"
        if not isinstance(tests, dict):
            raise QcConfigError(f"{where}: a mapping of tests ({', '.join(TESTS)})")
        known = LOCATION_TESTS if topic == POSITION else TESTS
        out[str(topic)] = {str(n): _test(str(n), p, where, known) for n, p in tests.items()}
    return out

"""The QARTOD tests of ``ioos_qc`` 3.0 an export runs, written again, vectorised,
for speed: ``spike_test`` (its default method, ``average``), ``flat_line_test``,
``gross_range_test``, ``rate_of_change_test``, ``location_test`` (without its
``range_max``) and the aggregate, ``qartod_compare``. The library's own loop over
every sample in Python (spike: the missing-value flags), its masked window of
``count`` samples per sample (flat line), its masked arrays (the others) and the
import of pandas it brings cost more than the rest of an export
(docs/benchmarks.md, "With quality flags"). Each function gives the flags
``ioos_qc.qartod``'s function of the same name gives, flag for flag, on any
series (NaN and infinities as missing, the masked arrays' data where the library
reads them): runtime/python/tests/test_dataset_qcfast.py checks them against the
library on random series with gaps, infinities, repeated times, spikes and flat
stretches, and the export's tests against ioos_qc run on the archive. Anything
else (another spike method) goes to the library.

>>> spike_test(np.array([1.0, 1.0, 9.0, 1.0, np.nan]), 1, 3).tolist()
[2, 3, 4, 2, 9]
"""

from __future__ import annotations

from typing import Any

import numpy as np

GOOD, UNKNOWN, SUSPECT, FAIL, MISSING = 1, 2, 3, 4, 9


def spike_test(
    inp: np.ndarray,
    suspect_threshold: float | None = None,
    fail_threshold: float | None = None,
    method: str = "average",
) -> np.ndarray:
    """``ioos_qc.qartod.spike_test(inp, suspect_threshold, fail_threshold)``: a sample
    further than a threshold from the mean of its two neighbours (``method`` must be
    ``average``: ``fast_test`` sends the other to the library)."""
    assert method == "average", method
    v = np.asarray(inp, dtype=np.float64)
    missing = ~np.isfinite(v)
    ref = np.zeros(len(v))
    with np.errstate(over="ignore", invalid="ignore"):
        ref[1:-1] = (v[:-2] + v[2:]) / 2
        no_ref = ~np.isfinite(ref)
        no_ref[1:-1] |= missing[:-2] | missing[2:]
        diff = np.abs(v - ref)
    flags = np.ones(len(v), dtype=np.uint8)
    with np.errstate(invalid="ignore"):
        if suspect_threshold:
            flags[diff > suspect_threshold] = SUSPECT
        if fail_threshold:
            flags[diff > fail_threshold] = FAIL
    if len(v):
        flags[[0, -1]] = UNKNOWN
    flags[no_ref | ~np.isfinite(diff)] = UNKNOWN
    flags[missing] = MISSING
    return flags


def median_step(steps: np.ndarray) -> Any:
    """``np.median(steps)`` (a series' time steps), without its partial sort when every
    step is the same (a regular clock: the usual case)."""
    if len(steps) and steps.min() == steps.max():
        return steps[0]
    return np.median(steps)


def _rolling_min(a: np.ndarray, k: int) -> np.ndarray:
    """The minimum of every ``k`` consecutive values (van Herk / Gil-Werman: block
    prefix and suffix minima), ``len(a) - k + 1`` of them, in O(len(a))."""
    n = len(a)
    blocks = -(-n // k)
    padded = np.full(blocks * k, np.inf)
    padded[:n] = a
    grid = padded.reshape(blocks, k)
    prefix = np.minimum.accumulate(grid, axis=1).ravel()
    suffix = np.minimum.accumulate(grid[:, ::-1], axis=1)[:, ::-1].ravel()
    return np.minimum(suffix[: n - k + 1], prefix[k - 1 : n])


def _flat(lows: np.ndarray, negs: np.ndarray, count: int, tolerance: float) -> np.ndarray:
    """Per sample: the ``count + 1`` values ending at it (missing ones left out) span
    less than ``tolerance``; the first ``count`` samples never (nor any when the
    series has no more than ``count`` samples: the library's strided view of
    ``count + 1`` values per row drops its last row, which would read past the end).
    ``lows``/``negs``: the values and their negation, missing ones as +inf."""
    out = np.zeros(len(lows), dtype=bool)
    k = count + 1
    if count < 0 or k > len(lows):
        return out
    lo = _rolling_min(lows, k)
    hi = -_rolling_min(negs, k)
    with np.errstate(invalid="ignore"):
        out[count:] = np.abs(hi - lo) < tolerance  # no finite value: inf, never flagged
    return out


def flat_line_test(
    inp: np.ndarray,
    tinp: np.ndarray,
    suspect_threshold: float,
    fail_threshold: float,
    tolerance: float = 0,
) -> np.ndarray:
    """``ioos_qc.qartod.flat_line_test``: the value stayed within ``tolerance`` for
    the thresholds' seconds (counted in samples at the median interval, whole seconds).

    The shorter window is tried first: a present sample flat over the longer window
    is flat over the shorter one (its values are among them), and a missing sample
    ends MISSING whatever the windows say; so when the shorter flags no present
    sample (the usual case) the longer is not computed."""
    v = np.asarray(inp, dtype=np.float64)
    flags = np.full(len(v), GOOD, dtype=np.uint8)
    if len(v) < 3:
        return flags
    times = np.asarray(tinp).astype("datetime64[ns]")
    interval = float(median_step(np.diff(times)).astype("timedelta64[s]").astype(float))
    present = np.isfinite(v)
    lows, negs = np.where(present, v, np.inf), np.where(present, -v, np.inf)
    tests = [
        (int(int(t) / interval), flag)
        for t, flag in ((suspect_threshold, SUSPECT), (fail_threshold, FAIL))
    ]
    shorter = min(tests)[0]
    flat = {shorter: _flat(lows, negs, shorter, tolerance)}
    if (flat[shorter] & present).any():
        for count, flag in tests:  # SUSPECT first, then FAIL over it, as the library
            if count not in flat:
                flat[count] = _flat(lows, negs, count, tolerance)
            flags[flat[count]] = flag
    flags[~present] = MISSING
    return flags


def _span(pair: Any) -> tuple[float, float]:
    low, high = sorted(pair)
    return float(low), float(high)


def gross_range_test(
    inp: np.ndarray, fail_span: Any, suspect_span: Any | None = None
) -> np.ndarray:
    """``ioos_qc.qartod.gross_range_test``: outside ``suspect_span`` SUSPECT, outside
    ``fail_span`` FAIL; NaN MISSING (an infinity is compared, as the library does)."""
    v = np.asarray(inp, dtype=np.float64)
    fail = _span(fail_span)
    flags = np.ones(len(v), dtype=np.uint8)
    flags[~np.isfinite(v)] = MISSING
    with np.errstate(invalid="ignore"):
        if suspect_span is not None:
            user = _span(suspect_span)
            if user[0] < fail[0] or user[1] > fail[1]:
                raise ValueError(
                    f"Suspect span(minv={user[0]}, maxv={user[1]}) must fall within the "
                    f"Fail span(minv={fail[0]}, maxv={fail[1]})"
                )
            flags[(v < user[0]) | (v > user[1])] = SUSPECT
        flags[(v < fail[0]) | (v > fail[1])] = FAIL
    return flags


def rate_of_change_test(
    inp: np.ndarray, tinp: np.ndarray, threshold: float, fail_threshold: float | None = None
) -> np.ndarray:
    """``ioos_qc.qartod.rate_of_change_test``: the change from the previous sample per
    second (whole seconds) above ``threshold`` SUSPECT, above ``fail_threshold`` FAIL.
    Where the library's masked division is masked (no time between the two, or a
    missing value) it compares the masked data, the difference itself; so do we."""
    v = np.asarray(inp, dtype=np.float64)
    flags = np.ones(len(v), dtype=np.uint8)
    missing = ~np.isfinite(v)
    if len(v):
        seconds = np.diff(np.asarray(tinp).astype("datetime64[ns]"))
        dt = seconds.astype("timedelta64[s]").astype(float)
        roc = np.zeros(len(v))
        with np.errstate(all="ignore"):
            diff = v[1:] - v[:-1]
            masked = (
                missing[1:] | missing[:-1] | (np.abs(diff) * np.finfo(float).tiny >= np.abs(dt))
            )
            roc[1:] = np.abs(np.where(masked, diff, diff / dt))
            flags[roc > threshold] = SUSPECT
            if fail_threshold is not None:
                flags[roc > fail_threshold] = FAIL
    flags[missing] = MISSING
    return flags


def location_test(lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    """``ioos_qc.qartod.location_test(lon, lat)`` (no ``range_max``): MISSING where the
    position is missing (NaN or infinite), FAIL where only one coordinate is, or where
    ``|lat| > 90`` or ``|lon| > 180`` (an infinity compared, as the library does)."""
    x, y = np.asarray(lon, dtype=np.float64), np.asarray(lat, dtype=np.float64)
    if x.shape != y.shape:
        raise ValueError(f"Longitude ({x.shape}) and latitude ({y.shape}) are different sizes.")
    no_x, no_y = ~np.isfinite(x), ~np.isfinite(y)
    flags = np.ones(len(x), dtype=np.uint8)
    flags[no_x | no_y] = MISSING
    flags[no_x != no_y] = FAIL
    with np.errstate(invalid="ignore"):
        flags[(np.abs(y) > 90) | (np.abs(x) > 180)] = FAIL
    return flags


def location_bounds_test(lon: np.ndarray, lat: np.ndarray, bbox: list[float]) -> np.ndarray:
    """``ioos_qc.qartod.location_bounds_test(lon, lat, shape=bbox)`` with the legacy
    ``bbox`` ``[lon_min, lat_min, lon_max, lat_max]``: FAIL outside the box (its border
    is outside, as for shapely), MISSING where a coordinate is NaN."""
    x, y = np.asarray(lon, dtype=np.float64), np.asarray(lat, dtype=np.float64)
    x0, y0, x1, y1 = bbox
    nan = np.isnan(x) | np.isnan(y)
    flags = np.ones(len(x), dtype=np.uint8)
    flags[nan] = MISSING
    with np.errstate(invalid="ignore"):
        inside = (x > x0) & (x < x1) & (y > y0) & (y < y1)
    flags[~inside & ~nan] = FAIL
    return flags


#: ``qartod_compare``'s precedence, lowest first: a later flag in any test wins.
_PRECEDENCE = (MISSING, UNKNOWN, GOOD, SUSPECT, FAIL)
_RANK = np.zeros(256, dtype=np.uint8)
_RANK[list(_PRECEDENCE)] = np.arange(1, len(_PRECEDENCE) + 1)
_OF_RANK = np.array((MISSING, *_PRECEDENCE), dtype=np.uint8)


def qartod_compare(vectors: list[np.ndarray]) -> np.ndarray:
    """``ioos_qc.qartod.qartod_compare``: per sample the flag of highest precedence
    among the tests' (FAIL over SUSPECT over PASS over NOT_EVALUATED over MISSING;
    MISSING where no test gave one of them)."""
    if not vectors or any(len(v) != len(vectors[0]) for v in vectors):
        raise ValueError("Vectors are not the same size.")
    rank = _RANK[np.asarray(vectors[0], dtype=np.uint8)]
    for v in vectors[1:]:
        np.maximum(rank, _RANK[np.asarray(v, dtype=np.uint8)], out=rank)
    out: np.ndarray = _OF_RANK[rank]
    return out


FAST: dict[str, Any] = {
    "spike_test": spike_test,
    "flat_line_test": flat_line_test,
    "gross_range_test": gross_range_test,
    "rate_of_change_test": rate_of_change_test,
}


def fast_test(name: str, params: dict[str, Any]) -> Any | None:
    """The vectorised test standing for ``ioos_qc``'s ``name`` with ``params``, if any."""
    if name == "spike_test" and params.get("method", "average") != "average":
        return None
    return FAST.get(name)

"""Two QARTOD tests of ``ioos_qc`` 3.0 written again, vectorised, for speed:
``spike_test`` (its default method, ``average``) and ``flat_line_test``. The
library's own loop over every sample in Python (spike: the missing-value flags)
and its masked window of ``count`` samples per sample (flat line) cost more than
the rest of an export (docs/benchmarks.md, "With quality flags"). Each function
gives the flags ``ioos_qc.qartod``'s function of the same name gives, flag for
flag, on any series (NaN and infinities as missing): runtime/python/tests/
test_dataset_qcfast.py checks them against the library on random series with
gaps, spikes and flat stretches, and the export's tests against ioos_qc run on
the archive. Anything else (another spike method) goes to the library.

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
    interval = float(np.median(np.diff(times)).astype("timedelta64[s]").astype(float))
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


def fast_test(name: str, params: dict[str, Any]) -> Any | None:
    """The vectorised test standing for ``ioos_qc``'s ``name`` with ``params``, if any."""
    if name == "spike_test" and params.get("method", "average") == "average":
        return spike_test
    if name == "flat_line_test":
        return flat_line_test
    return None

"""The vectorised QARTOD tests (modd.dataset.qcfast) give ``ioos_qc`` 3.0's flags,
flag for flag: random series with missing values, infinities, spikes and flat
stretches, at every length from 0 to a few hundred, every threshold shape."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from ioos_qc import qartod
from modd.dataset import qcfast


def _series(rng: np.random.Generator, n: int) -> np.ndarray:
    v = np.cumsum(rng.normal(0, 0.3, n))
    if n:
        spikes = rng.random(n) < 0.05
        v[spikes] += rng.normal(0, 20, int(spikes.sum()))
        v[rng.random(n) < 0.1] = np.nan
        v[rng.random(n) < 0.01] = np.inf
        start = int(rng.integers(0, n))
        v[start : start + int(rng.integers(0, 40))] = v[start]  # a stuck sensor
    return v


def _library(fn: str, *args: object, **kwargs: object) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.asarray(getattr(qartod, fn)(*args, **kwargs), dtype=np.uint8)


@pytest.mark.parametrize("seed", range(40))
def test_spike_test_is_ioos_qcs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for n in (1, 2, 3, 4, 7, 50, int(rng.integers(100, 400))):
        v = _series(rng, n)
        for s, f in ((1.0, 3.0), (0.5, None), (None, 2.0), (0, 0), (2.0, 1.0)):
            want = _library("spike_test", inp=v, suspect_threshold=s, fail_threshold=f)
            got = qcfast.spike_test(v, s, f)
            assert got.tolist() == want.tolist(), (n, s, f, v)


@pytest.mark.parametrize("seed", range(40))
def test_flat_line_test_is_ioos_qcs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for n in (0, 1, 2, 3, 4, 5, 9, 10, 11, 60, int(rng.integers(100, 400))):
        v = _series(rng, n)
        step = int(rng.choice([1, 2, 3, 5]))
        t = (np.arange(n) * step * 10**9 + int(rng.integers(0, 10**9))).astype("datetime64[ns]")
        cases = ((3, 6, 0.01), (10, 20, 0.5), (0, 5, 0.1), (5.7, 9.9, 1e-9), (1, 2, 0), (8, 3, 0.5))
        for s, f, tol in cases:
            want = _library(
                "flat_line_test",
                inp=v,
                tinp=t,
                suspect_threshold=s,
                fail_threshold=f,
                tolerance=tol,
            )
            got = qcfast.flat_line_test(v, t, s, f, tol)
            assert got.tolist() == want.tolist(), (n, step, s, f, tol, v)


def _times(rng: np.random.Generator, n: int) -> np.ndarray:
    """Increasing times, some repeated, some within the same whole second."""
    steps = rng.choice([0, 10**8, 6 * 10**8, 10**9, 3 * 10**9], n)
    return (np.cumsum(steps) + int(rng.integers(0, 10**9))).astype("datetime64[ns]")


@pytest.mark.parametrize("seed", range(40))
def test_gross_range_test_is_ioos_qcs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for n in (0, 1, 2, 5, int(rng.integers(50, 400))):
        v = _series(rng, n) * 3
        v[rng.random(n) < 0.05] = -np.inf
        for fail, suspect in (
            ([-5, 5], [-2, 2]),
            ([5, -5], None),
            ([-1, 3], [0, 3]),
            ([0, 0], None),
        ):
            want = _library("gross_range_test", inp=v, fail_span=fail, suspect_span=suspect)
            got = qcfast.gross_range_test(v, fail, suspect)
            assert got.tolist() == want.tolist(), (n, fail, suspect, v)


def test_gross_range_test_refuses_a_suspect_span_outside_the_fail_span() -> None:
    with pytest.raises(ValueError, match="must fall within"):
        _library("gross_range_test", inp=[1.0], fail_span=[0, 1], suspect_span=[-1, 1])
    with pytest.raises(ValueError, match="must fall within"):
        qcfast.gross_range_test(np.array([1.0]), [0, 1], [-1, 1])


@pytest.mark.parametrize("seed", range(40))
def test_rate_of_change_test_is_ioos_qcs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for n in (0, 1, 2, 3, 10, int(rng.integers(50, 400))):
        v = _series(rng, n)
        v[rng.random(n) < 0.03] = -np.inf
        t = _times(rng, n)
        for threshold, fail in ((0.5, None), (1.0, 4.0), (0.0, 0.0), (3.0, 1.0)):
            want = _library(
                "rate_of_change_test", inp=v, tinp=t, threshold=threshold, fail_threshold=fail
            )
            got = qcfast.rate_of_change_test(v, t, threshold, fail)
            assert got.tolist() == want.tolist(), (n, threshold, fail, v, t)


@pytest.mark.parametrize("seed", range(20))
def test_qartod_compare_is_ioos_qcs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for k in (1, 2, 4):
        for n in (0, 1, 7, 300):
            flags = [rng.choice([0, 1, 2, 3, 4, 9], n).astype(np.uint8) for _ in range(k)]
            want = _library("qartod_compare", flags)
            assert qcfast.qartod_compare(flags).tolist() == want.tolist(), flags


def _positions(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    lon = rng.uniform(-200, 200, n)
    lat = rng.uniform(-100, 100, n)
    for a in (lon, lat):
        a[rng.random(n) < 0.1] = np.nan
        a[rng.random(n) < 0.03] = rng.choice([np.inf, -np.inf])
    lon[rng.random(n) < 0.02] = 10.0  # on the box's border
    return lon, lat


@pytest.mark.parametrize("seed", range(30))
def test_location_tests_are_ioos_qcs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for n in (0, 1, 2, 50, int(rng.integers(100, 400))):
        lon, lat = _positions(rng, n)
        want = _library("location_test", lon=lon, lat=lat)
        assert qcfast.location_test(lon, lat).tolist() == want.tolist(), (lon, lat)
        for bbox in ([-20.0, -30.0, 10.0, 40.0], [-180.0, -90.0, 180.0, 90.0]):
            want = _library("location_bounds_test", lon=lon, lat=lat, shape=list(bbox))
            got = qcfast.location_bounds_test(lon, lat, bbox)
            assert got.tolist() == want.tolist(), (bbox, lon, lat)

"""No leaks: the resident set stays steady over 1 000 fits (and predictions,
model files and errors) on a small campaign."""

import os
import sys

import numpy as np
import pytest

import robokrige as rk

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="reads /proc/self/statm"
)


def rss_mb():
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def test_rss_steady_over_1000_fits():
    rng = np.random.default_rng(3)
    q = rng.uniform(-40, 40, size=(30, 3))
    e = rng.normal(0, 0.2, size=(30, 3))
    params = dict(corr="gaussian", starts=1)
    data = rk.as_data(q, None, e)

    def cycle(k):
        # alternately from a Data and from arrays
        m = rk.ErrorModel(**params).fit(data) if k % 2 else rk.ErrorModel(**params).fit(q, errors=e)
        mean, std = m.predict(q, data.dirs, return_std=True)
        rk.ErrorModel.from_json(m.to_json())
        try:
            rk.ErrorModel(space="bogus").fit(q, errors=e)
        except rk.RobokrigeError:
            pass
        return mean

    for k in range(100):  # warm-up: allocator pools, thread pool, caches
        cycle(k)
    start = rss_mb()
    for k in range(1000):
        cycle(k)
    growth = rss_mb() - start
    # a leak of one 30-row model per fit would be ≥ 1 000 × ~20 kB = 20 MB
    assert growth < 8.0, f"RSS grew by {growth:.1f} MB over 1000 fits"

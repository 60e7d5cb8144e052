"""LKH in a child process (runtime/lkh.py): an LKH abort must not take the runtime down.

The abort is real: ``os.abort()`` in the solver's place kills the child with SIGABRT, as LKH's
failed assertion did on SITL.  Without the isolation these tests would kill pytest itself.
"""

from __future__ import annotations

import itertools
import math
import os
import time

import numpy as np
import pytest

from iterplan_compiler.runtime import lkh
from iterplan_compiler.runtime.ideal import IdealMethod, ideal_path
from iterplan_compiler.runtime.sorter import Pose
from iterplan_compiler.runtime.tour import plan_tour

elkai = pytest.importorskip("elkai", reason="elkai (LKH-3) is not installed")

fork_only = pytest.mark.skipif(not hasattr(os, "fork"), reason="no os.fork on this platform")


def _square(n: int) -> np.ndarray:
    pts = np.array([(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n))
                    for k in range(n)]) * 1000
    return np.rint(np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1)))


def test_a_solve_returns_the_in_process_tour():
    m = _square(12).astype(np.int64)
    tour = lkh.solve_matrix(m, asymmetric=False)
    assert tour[0] == tour[-1] and sorted(tour[:-1]) == list(range(12))
    # the points on a circle: the optimum goes round it
    steps = {(b - a) % 12 for a, b in itertools.pairwise(tour)}
    assert steps <= {1, 11}
    assert tour == elkai.DistanceMatrix(m.tolist()).solve_tsp(runs=1)


@fork_only
def test_an_abort_in_lkh_is_an_error_not_the_end_of_the_process(monkeypatch):
    monkeypatch.setattr(elkai._elkai, "solve_problem", lambda params, problem: os.abort())
    with pytest.raises(lkh.LKHError, match="SIGABRT"):
        lkh.solve_matrix(_square(8).astype(np.int64), asymmetric=True, trials=5)


@fork_only
def test_a_solve_that_overruns_is_abandoned(monkeypatch):
    monkeypatch.setattr(lkh, "TIMEOUT_S", 0.5)
    monkeypatch.setattr(elkai._elkai, "solve_problem", lambda params, problem: time.sleep(30))
    t0 = time.monotonic()
    with pytest.raises(lkh.LKHError, match="longer than"):
        lkh.solve_matrix(_square(8).astype(np.int64), asymmetric=True)
    assert time.monotonic() - t0 < 10


def test_the_callers_fall_back_when_lkh_fails(monkeypatch):
    def fail(*args, **kwargs):
        raise lkh.LKHError("LKH died (SIGABRT)")

    monkeypatch.setattr(lkh, "solve_matrix", fail)
    pts = np.array([((c + 0.5) * 50, (r + 0.5) * 50) for r in range(3) for c in range(5)])
    with pytest.warns(RuntimeWarning, match="tour sorter: LKH died"):
        order, heads = plan_tour(pts, Pose(-100.0, -100.0, 0.3),
                                 (0.0, math.pi / 2, math.pi, 3 * math.pi / 2), 23.4, 50.0)
    assert sorted(order) == list(range(len(pts))) and len(heads) == len(pts)
    cells = [((c + 0.5) * 50, (r + 0.5) * 50) for r in range(5) for c in range(12)]
    with pytest.warns(RuntimeWarning, match="ideal: LKH died"):
        r = ideal_path(cells, (25.0, -75.0))
    assert r.method is IdealMethod.BOUND and r.distance == pytest.approx(r.lower)


def test_a_tour_from_far_away_stays_within_lkh_integers():
    """A tour planned from 14,000 km away (ArduPlane's position before its EKF origin, as on
    SITL) gave matrix entries of 2.8e9, which overflowed LKH's 32-bit costs into an abort;
    the entries are now scaled below ``lkh.MAX_ENTRY`` and LKH succeeds."""
    import warnings

    pts = np.array([((c + 0.5) * 50, (r + 0.5) * 50) for r in range(3) for c in range(4)])[:10]
    assert lkh.integer_matrix(np.array([[0.0, 2.8e8]]), 10.0).max() == lkh.MAX_ENTRY
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)      # LKH's fallback would warn
        order, _ = plan_tour(pts, Pose(-1.1e7, -8.0e6, 1.0),
                             (0.0, math.pi / 2, math.pi, 3 * math.pi / 2), 23.4, 50.0)
    assert sorted(order) == list(range(10))

"""Sorter kernel against the independent scalar reference; strategy ordering."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.runtime.sorter import (
    LastSorter,
    Pose,
    RandomSorter,
    dubins_lengths,
    fast_angle,
)
from iterplan_compiler.runtime.sorters import make_sorter
from tests.runtime.dubins_ref import csc_length, integrate, words

coord = st.floats(-2000, 2000, allow_nan=False)
angle = st.floats(-7, 7, allow_nan=False)


def test_reference_paths_end_at_goal():
    # The reference itself: every word it reports really ends at the goal pose.
    rng = np.random.default_rng(0)
    for _ in range(60):
        q0 = (*rng.uniform(-300, 300, 2), rng.uniform(-4, 4))
        q1 = (*rng.uniform(-300, 300, 2), rng.uniform(-4, 4))
        for w, tpq in words(q0, q1, 40.0).items():
            x, y, h = integrate(q0, w, tpq, 40.0, steps=200)
            assert math.hypot(x - q1[0], y - q1[1]) < 1e-6
            assert abs((h - q1[2] + math.pi) % (2 * math.pi) - math.pi) < 1e-6


@settings(max_examples=60, deadline=None, derandomize=True)
@given(x0=coord, y0=coord, h0=angle, beta=angle, r=st.floats(15, 90),
       seed=st.integers(0, 2**16), parallel=st.booleans())
def test_kernel_matches_reference(x0, y0, h0, beta, r, seed, parallel):
    rng = np.random.default_rng(seed)
    xs = rng.uniform(-2500, 2500, 40)
    ys = rng.uniform(-2500, 2500, 40)
    got = dubins_lengths(Pose(x0, y0, h0), xs, ys, beta, r, parallel=parallel)
    assert got.dtype == np.float32
    for i in range(len(xs)):
        ref = csc_length((x0, y0, h0), (xs[i], ys[i], beta), r)
        if parallel:
            ref = min(ref, csc_length((x0, y0, h0), (xs[i], ys[i], beta + math.pi), r))
        assert abs(float(got[i]) - ref) <= 0.05 + 2e-5 * ref, (i, got[i], ref)


def test_kernel_edge_cases():
    r = 40.0
    p = Pose(0.0, 0.0, 0.0)
    # Straight ahead, arriving with the same heading: exactly the distance, no spurious circle.
    xs = np.array([100.0, 1000.0, 5000.0])
    got = dubins_lengths(p, xs, np.zeros(3), 0.0, r, parallel=False)
    np.testing.assert_allclose(got, xs, rtol=1e-5)
    # Target at the start pose itself: the answer is a full loop or finite, never NaN.
    got = dubins_lengths(p, np.array([0.0]), np.array([0.0]), 0.0, r)
    assert np.isfinite(got).all()
    # Chunk boundaries do not change results.
    rng = np.random.default_rng(5)
    xs, ys = rng.uniform(-900, 900, 1000), rng.uniform(-900, 900, 1000)
    a = dubins_lengths(Pose(3, 4, 1), xs, ys, 0.5, r, chunk=97)
    b = dubins_lengths(Pose(3, 4, 1), xs, ys, 0.5, r)
    np.testing.assert_array_equal(a, b)


def test_parallel_is_min_of_both_headings_and_flip_flag():
    rng = np.random.default_rng(2)
    xs, ys = rng.uniform(-800, 800, 500), rng.uniform(-800, 800, 500)
    p = Pose(10, -20, 2.0)
    a = dubins_lengths(p, xs, ys, 1.0, 35.0, parallel=False)
    b = dubins_lengths(p, xs, ys, 1.0 + math.pi, 35.0, parallel=False)
    both, flip = dubins_lengths(p, xs, ys, 1.0, 35.0, parallel=True, return_flip=True)
    np.testing.assert_allclose(both, np.minimum(a, b), rtol=1e-6)
    assert (flip == (b < a)).all()


def test_fast_angle_accuracy():
    rng = np.random.default_rng(1)
    y = rng.normal(size=20000).astype(np.float32)
    x = rng.normal(size=20000).astype(np.float32)
    ref = np.mod(np.arctan2(y.astype(float), x.astype(float)), 2 * math.pi)
    got = fast_angle(y, x).astype(float)
    err = np.abs((got - ref + math.pi) % (2 * math.pi) - math.pi)
    assert err.max() < 3e-6
    assert ((got >= 0) & (got < 2 * math.pi + 1e-6)).all()


def test_distance_lengths_grow_with_distance_on_a_line():
    # Cells straight ahead along the arrival heading: strictly increasing keys.
    s = make_sorter("distance", radius=30.0, arrival_heading=0.0, parallel=False)
    xs = np.arange(1, 50) * 50.0
    k = s.keys(xs, np.zeros_like(xs), np.arange(49), Pose(0, 0, 0))
    assert (np.diff(k) > 0).all()


def test_last_puts_interesting_at_the_end_in_map_order():
    mask = np.zeros(10, dtype=bool)
    mask[[1, 4, 7]] = True
    ids = np.array([9, 7, 4, 3, 1, 0])
    k = LastSorter(mask).keys(None, None, ids, Pose(0, 0, 0))
    order = ids[np.argsort(k)]
    assert order.tolist() == [0, 3, 9, 1, 4, 7]


def test_random_is_seeded_and_changes_between_resorts():
    ids = np.arange(100)
    a1 = RandomSorter(7).keys(None, None, ids, None)
    s = RandomSorter(7)
    b1, b2 = s.keys(None, None, ids, None), s.keys(None, None, ids, None)
    np.testing.assert_array_equal(a1, b1)
    assert not np.array_equal(b1, b2)


def test_unknown_sorter():
    with pytest.raises(ValueError, match="unknown sorter"):
        make_sorter("fastest")

"""The chunked CSC kernel's branches, edge cases and the no-full-sort selection helpers.

Complements ``test_sorter.py`` (random poses against the scalar reference): here every static
branch of the kernel (outer-word half-plane cases, the inner-word wrap thresholds for arrival
angles below/above 3pi/2, exact axis headings) is exercised deterministically, plus targets
straight behind, overlapping turn circles, large map coordinates and the selection helpers.
"""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.runtime.sorter import (
    DistanceSorter,
    LastSorter,
    Pose,
    dubins_lengths,
    select_smallest,
)
from tests.runtime.dubins_ref import csc_length

HEADINGS = [0.0, math.pi / 2, math.pi, 1.5 * math.pi, 1e-4, -1e-4, 0.3, 2.0, 4.0, 4.8, 5.5, 6.2]


def _reference(pose, xs, ys, beta, r, parallel):
    out = []
    for x, y in zip(xs, ys, strict=True):
        q0 = (pose.x, pose.y, pose.heading)
        ref = csc_length(q0, (float(x), float(y), beta), r)
        if parallel:
            ref = min(ref, csc_length(q0, (float(x), float(y), beta + math.pi), r))
        out.append(ref)
    return np.array(out)


def test_every_relative_heading_branch_matches_reference():
    rng = np.random.default_rng(11)
    xs, ys = rng.uniform(-600, 600, 30), rng.uniform(-600, 600, 30)
    for h0 in (0.0, 2.5, -1.0):
        pose = Pose(20.0, -35.0, h0)
        for rel in HEADINGS:
            beta = h0 + rel
            for parallel in (False, True):
                got = dubins_lengths(pose, xs, ys, beta, 40.0, parallel=parallel, chunk=7)
                ref = _reference(pose, xs, ys, beta, 40.0, parallel)
                np.testing.assert_allclose(got, ref, rtol=2e-5, atol=0.02,
                                           err_msg=f"h0={h0} rel={rel} parallel={parallel}")


def test_target_straight_behind_needs_a_full_turn():
    # Arrival heading = start heading, target on the line behind: LSL/RSR must include the full
    # circle (a half-plane test alone also accepts the backwards ray).
    r = 40.0
    xs = np.array([-500.0, -500.0, -500.0, -120.0])
    ys = np.array([0.0, 1e-3, -1e-3, 0.0])
    for h0 in (0.0, 1.0, -2.0):
        c, s = math.cos(h0), math.sin(h0)
        wx, wy = 7 + xs * c - ys * s, -3 + xs * s + ys * c
        pose = Pose(7.0, -3.0, h0)
        got = dubins_lengths(pose, wx, wy, h0, r, parallel=False)
        ref = _reference(pose, wx, wy, h0, r, False)
        np.testing.assert_allclose(got, ref, rtol=1e-5, atol=0.02)
        assert (got > -xs).all()   # never the bare straight-line distance


def test_close_targets_with_overlapping_circles():
    # Inside 2r the inner tangents do not exist (NaN internally): results stay finite and match.
    rng = np.random.default_rng(3)
    pose = Pose(0.0, 0.0, 0.7)
    xs, ys = rng.uniform(-90, 90, 200), rng.uniform(-90, 90, 200)
    for beta in (0.0, 0.7, 3.0, 5.0):
        for parallel in (False, True):
            got = dubins_lengths(pose, xs, ys, beta, 45.0, parallel=parallel)
            assert np.isfinite(got).all()
            np.testing.assert_allclose(got, _reference(pose, xs, ys, beta, 45.0, parallel),
                                       rtol=2e-5, atol=0.02)


def test_large_map_coordinates_float32():
    # A 10 M-cell grid spans ~160 km: float32 inputs far from the origin keep ~cm accuracy.
    rng = np.random.default_rng(4)
    pose = Pose(80_000.0, 80_000.0, 1.2)
    xs = (80_000 + rng.uniform(-3000, 3000, 50)).astype(np.float32)
    ys = (80_000 + rng.uniform(-3000, 3000, 50)).astype(np.float32)
    got = dubins_lengths(pose, xs, ys, math.pi / 2, 33.0, parallel=True)
    ref = _reference(pose, xs.astype(float), ys.astype(float), math.pi / 2, 33.0, True)
    np.testing.assert_allclose(got, ref, rtol=2e-5, atol=0.05)


def test_dtypes_chunks_and_empty_input():
    rng = np.random.default_rng(6)
    xs, ys = rng.uniform(-900, 900, 5000), rng.uniform(-900, 900, 5000)
    pose = Pose(1.0, 2.0, 3.0)
    a = dubins_lengths(pose, xs, ys, 1.0, 30.0, parallel=True)
    b = dubins_lengths(pose, xs.astype(np.float32), ys.astype(np.float32), 1.0, 30.0,
                       parallel=True, chunk=333)
    np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-3)
    for chunk in (4999, 5000, 10**6):
        c, flip = dubins_lengths(pose, xs, ys, 1.0, 30.0, parallel=True, chunk=chunk,
                                 return_flip=True)
        np.testing.assert_array_equal(a, c)
        assert flip.dtype == bool and flip.shape == a.shape
    one = dubins_lengths(pose, xs[:40], ys[:40], 1.0, 30.0, parallel=True, chunk=1)
    np.testing.assert_array_equal(a[:40], one)
    empty = dubins_lengths(pose, np.zeros(0), np.zeros(0), 0.0, 30.0)
    assert empty.shape == (0,) and empty.dtype == np.float32


@settings(max_examples=40, deadline=None, derandomize=True)
@given(n=st.integers(1, 30000), k=st.integers(1, 5000), levels=st.sampled_from([3, 1000, 0]),
       seed=st.integers(0, 1000))
def test_select_smallest_is_the_stable_sort_prefix(n, k, levels, seed):
    rng = np.random.default_rng(seed)
    keys = (rng.integers(0, levels, n).astype(np.float32) if levels
            else rng.random(n, dtype=np.float32))
    if seed % 5 == 0:
        keys = np.sort(keys)[::-1].copy()     # adversarial for a strided sample
    got = select_smallest(keys, k)
    np.testing.assert_array_equal(got, np.argsort(keys, kind="stable")[:k])


def test_best_is_the_first_of_a_stable_sort():
    rng = np.random.default_rng(8)
    xs, ys = rng.uniform(-900, 900, 3000), rng.uniform(-900, 900, 3000)
    ids = np.arange(3000)
    pose = Pose(0.0, 0.0, 0.4)
    s = DistanceSorter(35.0, math.pi / 2, True)
    assert s.best(xs, ys, ids, pose) == np.argsort(s.keys(xs, ys, ids, pose), kind="stable")[0]
    mask = np.zeros(3000, dtype=bool)
    mask[:10] = True
    assert LastSorter(mask).best(xs, ys, ids, pose) == 10


def test_grid_with_axis_aligned_poses_matches_reference():
    # The runtime's common case: cells on a grid, the aircraft on a cell centre flying along the
    # fixed axis (heading = arrival heading or its opposite), so many targets lie exactly on the
    # line ahead/behind.  (The previous kernel got every target straight behind wrong.)
    c = np.arange(-7, 8) * 50.0
    gx, gy = np.meshgrid(c, c)
    xs, ys = gx.ravel() + 25, gy.ravel() + 25
    for sx, sy in ((25.0, 25.0), (125.0, -75.0)):
        for beta in (math.pi / 2, 0.0, math.pi, -math.pi / 2):
            for heading in (beta, beta + math.pi):
                pose = Pose(sx, sy, heading)
                for parallel in (False, True):
                    got = dubins_lengths(pose, xs, ys, beta, 33.0, parallel=parallel)
                    ref = _reference(pose, xs, ys, beta, 33.0, parallel)
                    np.testing.assert_allclose(got, ref, rtol=2e-5, atol=0.02)

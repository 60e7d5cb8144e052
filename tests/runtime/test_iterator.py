"""Iterator ⟨D, n, R⟩ semantics exactly as the paper defines them."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.sorter import Pose, Sorter
from iterplan_compiler.runtime.sorters import make_sorter


class KeySorter(Sorter):
    """Keys = a fixed per-cell priority shifted by the pose's x (so re-sorting changes order)."""

    name = "key"

    def __init__(self, prio):
        self.prio = np.asarray(prio, dtype=np.float64)

    def keys(self, xs, ys, ids, pose):
        return (self.prio[ids] - pose.x) % 1000.0


def make(n, prio, block=3):
    ids = np.arange(n, dtype=np.int64) * 3 + 1       # ids need not be 0..n-1
    p = np.zeros(ids.max() + 1)
    p[ids] = prio
    return Iterator(ids, np.zeros(n), np.zeros(n), KeySorter(p), Pose(0, 0, 0), block=block), ids


def test_initialisation_and_full_pass():
    it, ids = make(5, [50, 10, 40, 20, 30])
    # n is one element of L, R = L \ {n}, D = ∅ — n is the best by the Sorter.
    assert it.has_next() and it.next == ids[1]
    assert it.remaining_count() == 4 and it.num_done == 0
    seen = []
    while it.has_next():
        seen.append(it.next)
        it.remove_next()
    assert seen == [ids[1], ids[3], ids[4], ids[2], ids[0]]
    assert it.next is None and it.remaining_count() == 0
    assert sorted(it.processed().tolist()) == sorted(ids.tolist())


def test_reset_reinitialises():
    it, ids = make(4, [1, 2, 3, 4])
    it.remove_next()
    it.remove_next()
    it.reset(Pose(0, 0, 0))
    assert it.num_done == 0 and it.remaining_count() == 3 and it.next == ids[0]


def test_single_location():
    it, ids = make(1, [0])
    assert it.has_next() and it.remaining_count() == 0
    it.remove_next()
    assert not it.has_next()


ops = st.lists(st.one_of(st.just(("remove",)), st.just(("reset",)),
                         st.tuples(st.just("resort"), st.integers(0, 999))), max_size=60)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(prio=st.lists(st.integers(0, 999), min_size=1, max_size=40, unique=True), ops=ops,
       block=st.integers(1, 8))
def test_model_based(prio, ops, block):
    """Against a plain-set model: D, n, R partition L; remove puts n in D and takes the
    Sorter's best of R; resort keeps n and D; reset restores D = ∅."""
    n = len(prio)
    it, ids = make(n, prio, block)
    key = dict(zip(ids.tolist(), prio, strict=False))
    x = 0

    def best(cands):
        return min(cands, key=lambda c: ((key[c] - x) % 1000.0, c)) if cands else None

    L = set(ids.tolist())
    n_ = best(L)
    D, R = set(), L - {n_}
    for op in ops:
        if op[0] == "remove":
            if n_ is None:
                continue
            it.remove_next()
            D.add(n_)
            n_ = best(R)
            R.discard(n_)
        elif op[0] == "reset":
            x = 0
            it.reset(Pose(0, 0, 0))
            n_ = best(L)
            D, R = set(), L - {n_}
        else:
            x = op[1]
            it.resort(Pose(x, 0, 0))
        assert it.next == n_
        assert it.has_next() == (n_ is not None)
        assert set(it.processed().tolist()) == D
        assert set(it.remaining().tolist()) == R
        assert D.isdisjoint(R) and (n_ is None or (n_ not in D and n_ not in R))
        assert D | R | ({n_} if n_ is not None else set()) == L


def test_distance_sorter_offers_nearest_first():
    # A row of cells east of a vehicle flying east: offered west-to-east.
    xs = np.arange(20) * 50.0 + 25
    it = Iterator(np.arange(20), xs, np.zeros(20) + 25,
                  make_sorter("distance", radius=30, arrival_heading=0.0, parallel=False),
                  Pose(-100, 25, 0.0))
    order = []
    while it.has_next():
        order.append(it.next)
        it.remove_next()
    assert order == list(range(20))


def test_large_iterator_pass_is_fast_enough():
    n = 200_000
    rng = np.random.default_rng(0)
    it = Iterator(np.arange(n), rng.uniform(0, 20000, n), rng.uniform(0, 20000, n),
                  make_sorter("distance", radius=40, arrival_heading=0.0), Pose(0, 0, 0))
    count = 0
    while it.has_next():
        it.remove_next()
        count += 1
    assert count == n and it.num_done == n


@pytest.mark.parametrize("parallel", [False, True])
def test_pruned_ordering_offers_exactly_the_unpruned_order(parallel):
    """Lower-bound pruning (large R) must not change what is offered: same locations, same
    order, through resets, removals and re-sorts from changing poses."""
    from iterplan_compiler.runtime.sorter import DistanceSorter

    rng = np.random.default_rng(7)
    n = 20_000
    xs, ys = rng.uniform(0, 8000, n), rng.uniform(0, 8000, n)
    sorter = DistanceSorter(60.0, math.pi / 2, parallel=parallel)
    pose = Pose(4000.0, 4000.0, 0.3)
    pruned = Iterator(np.arange(n), xs, ys, sorter, pose, block=256, prune_min=1000)
    exact = Iterator(np.arange(n), xs, ys, sorter, pose, block=256, prune_min=10**9)
    assert pruned._lb is not None and exact._lb is None
    for step in range(6000):
        assert pruned.next == exact.next, step
        if step % 97 == 0:
            p = Pose(*rng.uniform(0, 8000, 2), float(rng.uniform(-3, 3)))
            pruned.resort(p)
            exact.resort(p)
        pruned.remove_next()
        exact.remove_next()
    assert pruned.peek_order(500).tolist() == exact.peek_order(500).tolist()
    assert sorted(pruned.remaining().tolist()) == sorted(exact.remaining().tolist())

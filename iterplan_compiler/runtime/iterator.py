"""The Iterator ⟨D, n, R⟩ of the paper (§III-B-1), with a Sorter choosing the order.

Paper definition, implemented literally:

* initialisation: ``n`` is set to one element of L, ``R = L \\ {n}``, ``D = ∅``;
* ``has_next``: true iff ``n`` is not null;
* ``remove_next``: adds ``n`` to ``D``; if ``R = ∅`` sets ``n`` to null, otherwise sets ``n`` to a
  location of ``R`` and removes it from ``R``;
* ``reset``: the iterator is re-initialised (over all of L again).

*Which* element of R becomes ``n`` is the Sorter's business: ``R`` is kept as a queue in offered
order and :meth:`Iterator.resort` re-orders it from a (predicted) pose — the executor calls it on
``go.next`` with the arrival pose, as in the paper.  Ordering is lazy: only the front block of the
queue is fully sorted (``argpartition`` + ``argsort`` of ``block`` elements); the rest is sorted
block by block when the iterator gets there, so a re-sort costs about one kernel pass.

Pruning (large R, a sorter with :meth:`~iterplan_compiler.runtime.sorter.Sorter.lower_bounds`,
i.e. ``distance``): a re-sort computes only the cheap lower bounds (the straight-line distance:
no path is shorter), and a block is sorted by exact keys computed for just the locations that
can be in it — the ``block`` smallest lower bounds give exact keys whose maximum ``T`` bounds
the block, every location with a lower bound below ``T`` is scored too, and nothing else can
belong (its exact key is at least its lower bound, at least ``T``).  The block is then moved to
the front of the queue by O(block) swaps instead of permuting all of R.  Once blocks grow past
an eighth of what is left, the rest is scored exactly.  The offered order is that of the exact
keys, as without pruning (``tests/runtime/test_iterator.py`` checks it).

All per-location data are NumPy arrays; ``remove_next``/``has_next`` are O(1) amortised.
"""

from __future__ import annotations

import numpy as np

from iterplan_compiler.runtime.sorter import Pose, Sorter, select_smallest

NULL = -1
#: Prune (see the module docstring) when R has at least this many locations.
PRUNE_MIN = 65536


class Iterator:
    """Iterator over the locations ``ids`` (cell ids) with ENU centres ``xs``, ``ys``.

    ``n`` is exposed as :attr:`next` (a cell id, or ``None`` when null).  ``D`` is the boolean
    mask :attr:`done` over positions in ``ids``; ``R`` is :meth:`remaining`.
    """

    def __init__(self, ids: np.ndarray, xs: np.ndarray, ys: np.ndarray, sorter: Sorter,
                 pose: Pose, *, block: int = 4096, prune_min: int = PRUNE_MIN):
        self.ids = np.asarray(ids, dtype=np.int64)
        if len(self.ids) == 0:
            raise ValueError("an iterator needs at least one location")
        self.xs = np.asarray(xs, dtype=np.float32)
        self.ys = np.asarray(ys, dtype=np.float32)
        self.sorter = sorter
        self.block = int(block)
        self.prune_min = int(prune_min)
        self._lb: np.ndarray | None = None   # lower bounds aligned with _queue (pruning)
        self._pose = pose
        self.done = np.zeros(len(self.ids), dtype=bool)
        self.num_done = 0
        self.resorts = 0
        self._queue = np.zeros(0, dtype=np.int64)   # positions (into ids) of R, offered order
        self._keys: np.ndarray = np.zeros(0)
        self._head = 0          # R = _queue[_head:]
        self._sorted_to = 0     # _queue[_head:_sorted_to] is in final order
        self._n = NULL          # position of n, or NULL
        self.reset(pose)

    # -- the paper's operations ---------------------------------------------------------------
    def has_next(self) -> bool:
        """True iff ``n`` is not null."""
        return self._n != NULL

    @property
    def next(self) -> int | None:
        """The cell id of ``n`` (None when null)."""
        return None if self._n == NULL else int(self.ids[self._n])

    @property
    def next_position(self) -> int:
        """Index of ``n`` in :attr:`ids` (``NULL`` = -1 when null)."""
        return self._n

    def remove_next(self) -> None:
        """Add ``n`` to D; take the first element of R (in sorted order) as the new ``n``."""
        if self._n == NULL:
            raise RuntimeError("remove_next with a null next location")
        if not self.done[self._n]:
            self.done[self._n] = True
            self.num_done += 1
        self._n = self._pop()

    def skip_run(self, j: int) -> None:
        """``remove_next`` ``j`` times at once: ``n`` and the next ``j - 1`` locations in
        offered order go to D, the one after becomes ``n`` (the executor's fast skip)."""
        if self._n == NULL:
            raise RuntimeError("skip_run with a null next location")
        if j <= 0:
            return
        self._ensure_sorted(self._head + j - 1)
        pos = np.concatenate([[self._n], self._queue[self._head:self._head + j - 1]])
        self.num_done += int(np.count_nonzero(~self.done[pos]))
        self.done[pos] = True
        self._head += len(pos) - 1
        self._n = self._pop()

    def reset(self, pose: Pose) -> None:
        """Re-initialise: D = ∅, n = the best location of L for ``pose``, R = L \\ {n}."""
        self.done[:] = False
        self.num_done = 0
        self.sorter.on_reset(self.xs, self.ys, self.ids, pose)
        self._order(np.arange(len(self.ids), dtype=np.int64), pose)
        self._n = self._pop()

    def resort(self, pose: Pose) -> None:
        """Re-order R for ``pose`` (``n`` itself is unchanged, as in the paper)."""
        self._order(self._queue[self._head:], pose)

    def fork(self) -> Iterator:
        """An independent copy of this iterator's position and state (D, n, R, the offered
        order and the Sorter's state): operations on the copy never change this one (the
        read-only location arrays are shared).  What a shadow run of the plan iterates
        (``runtime/shadow.py``)."""
        twin = object.__new__(Iterator)
        twin.__dict__.update(self.__dict__)
        twin.sorter = self.sorter.fork()
        twin.done = self.done.copy()
        twin._queue = self._queue.copy()
        twin._keys = self._keys.copy()
        twin._lb = None if self._lb is None else self._lb.copy()
        return twin

    # -- introspection --------------------------------------------------------------------------
    def remaining_count(self) -> int:
        return len(self._queue) - self._head

    def remaining(self) -> np.ndarray:
        """Cell ids of R (in the current offered order only where already sorted)."""
        return self.ids[self._queue[self._head:]]

    def processed(self) -> np.ndarray:
        """Cell ids of D."""
        return self.ids[self.done]

    def peek_order(self, k: int) -> np.ndarray:
        """The next ``k`` cell ids R will offer (forces sorting of that prefix)."""
        self._ensure_sorted(self._head + k)
        return self.ids[self._queue[self._head:self._head + k]]

    # -- internals ------------------------------------------------------------------------------
    def _order(self, positions: np.ndarray, pose: Pose) -> None:
        self.resorts += 1
        self._queue = positions.copy()
        self._head = 0
        self._sorted_to = 0
        self._pose = pose
        lb = None
        if len(positions) >= self.prune_min:
            lb = self.sorter.lower_bounds(self.xs[positions], self.ys[positions], pose)
        self._lb = lb
        if lb is None:
            self._keys = self.sorter.keys(self.xs[positions], self.ys[positions],
                                          self.ids[positions], pose)
        else:
            self._keys = np.zeros(len(positions), dtype=np.float32)

    def _exact(self, idx: np.ndarray) -> np.ndarray:
        q = self._queue[idx]
        return self.sorter.keys(self.xs[q], self.ys[q], self.ids[q], self._pose)

    def _ensure_sorted(self, upto: int) -> None:
        n = len(self._queue)
        while self._sorted_to < min(upto, n):
            lo = self._sorted_to
            # Blocks grow geometrically so a full pass costs O(n log n), not O(n^2 / block).
            hi = min(lo + max(self.block, lo), n)
            if self._lb is not None:
                if (hi - lo) * 8 < n - lo:
                    self._sort_block_pruned(lo, hi)
                    continue
                self._keys[lo:] = self._exact(np.arange(lo, n))     # the rest, exactly
                self._lb = None
            keys = self._keys[lo:]
            if hi < n:
                # Bring the block's smallest keys to the front, then sort just those.
                part = np.argpartition(keys, hi - lo - 1)
                self._queue[lo:] = self._queue[lo:][part]
                self._keys[lo:] = keys[part]
            sub = np.argsort(self._keys[lo:hi], kind="stable")
            self._queue[lo:hi] = self._queue[lo:hi][sub]
            self._keys[lo:hi] = self._keys[lo:hi][sub]
            self._sorted_to = hi

    def _sort_block_pruned(self, lo: int, hi: int) -> None:
        """Put the ``hi - lo`` smallest exact keys of ``_queue[lo:]`` at ``lo:hi`` in order,
        scoring only the locations that can be among them (module docstring)."""
        assert self._lb is not None
        lb = self._lb[lo:]
        want = hi - lo
        first = select_smallest(lb, want)
        bound = float(np.max(self._exact(lo + first)))
        # float32 kernels: a little slack so rounding cannot exclude a member
        cand = np.flatnonzero(lb <= bound * (1 + 1e-5) + 1e-3)
        exact = self._exact(lo + cand)
        pick = cand[np.argsort(exact, kind="stable")[:want]]
        chosen = lo + pick                                  # absolute positions, in order
        front = np.arange(lo, hi)
        moved_out = front[~np.isin(front, chosen)]          # front slots not chosen ...
        vacated = chosen[~np.isin(chosen, front)]           # ... go where chosen ones were
        q, lbs = self._queue, self._lb
        new_front_q, new_front_lb = q[chosen], lbs[chosen]
        q[vacated], lbs[vacated] = q[moved_out], lbs[moved_out]
        q[lo:hi], lbs[lo:hi] = new_front_q, new_front_lb
        self._keys[lo:hi] = np.sort(exact, kind="stable")[:want]
        self._sorted_to = hi

    def _pop(self) -> int:
        if self._head >= len(self._queue):
            return NULL
        if self._head >= self._sorted_to:
            self._ensure_sorted(self._head + 1)
        pos = int(self._queue[self._head])
        self._head += 1
        return pos

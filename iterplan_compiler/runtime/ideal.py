"""The paper's "ideal" mission: one definition for ``iterc run`` and the experiments.

Fig. 3's note: "Ideal duration is calculated using the minimum flight distance needed for the
mission using constant speed, ignoring the UAV's movement restrictions".  So

    ideal distance = min over visiting orders pi of  |start - p_pi(1)| + sum |p_pi(k) - p_pi(k+1)|

the shortest open path (Euclidean, straight legs) from the start through every point to visit
(``closed=True`` returns to the first point: a patrol loop).  When the mission prescribes the
order (Ordered Patrol) there is nothing to minimise: ``ordered=True`` takes the points as given.

How it is computed (:class:`IdealMethod`, reported next to the number):

* ``EXACT`` -- up to :data:`EXACT_MAX` points: Held-Karp dynamic programming (vectorised), the
  true optimum;
* ``TOUR`` -- up to :data:`TOUR_MAX` points: the LKH-3 heuristic (``elkai``) on the exact
  Euclidean distance matrix (centimetres), an open path forced through a dummy node.  An upper
  bound of the optimum that is, on grid cells, the optimum in practice; it is never below the
  Euclidean minimum spanning tree (a lower bound), and ``lower`` carries that bound so the gap
  can be seen.  Should LKH fail (it runs in a child process, ``runtime/lkh.py``), the method is
  ``BOUND`` with that lower bound;
* ``BOUND`` -- more points: the nearest-neighbour bound, a lower bound of the shortest path:
  the start's distance to the nearest point plus, for every point but one, the distance to its
  nearest other point (every point but the last is left along an edge at least that long;
  SciPy's k-d tree, ~1 s for 700,000 points).  On a grid whose cells admit a serpentine path
  it is the optimum (reach + one cell side per further cell).

The *kinematic floor* (:func:`kinematic_floor`) is the same order flown with the turn radius:
Dubins CSC legs arriving parallel to the arrival heading (either way, chosen by dynamic
programming over the two headings at each point).  ``ideal <= kinematic floor <= flown``: the
first gap is the physics of a fixed wing, the second what the plan and the iteration add.
"""

from __future__ import annotations

import enum
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from iterplan_compiler.runtime import lkh
from iterplan_compiler.runtime.planner import shortest_csc
from iterplan_compiler.runtime.sorter import Pose

Point = tuple[float, float]
#: Held-Karp up to this many points (2^n n passes of NumPy: 10 points ~ 20 ms).
EXACT_MAX = 10
#: LKH-3 up to this many points (a dense matrix; ~2 s at 300 points on this machine).
TOUR_MAX = 400
#: Kinematic floor only up to this many legs (scalar Dubins legs, ~40 us each).
KINEMATIC_MAX = 20_000


class IdealMethod(enum.Enum):
    ORDERED = "ordered"    # the order is prescribed: its polygon length
    EXACT = "exact"        # Held-Karp optimum
    TOUR = "tour"          # LKH-3 near-optimal tour (upper bound)
    BOUND = "bound"        # Euclidean MST (lower bound)


@dataclass(frozen=True)
class Ideal:
    """Ideal distance (m), how it was computed, the visiting order it implies (indices into
    the points; empty for ``BOUND``) and a lower bound (the MST, or the distance itself)."""

    distance: float
    method: IdealMethod
    order: tuple[int, ...]
    lower: float


def _dist_matrix(pts: np.ndarray) -> np.ndarray:
    d = pts[:, None, :] - pts[None, :, :]
    return np.sqrt((d * d).sum(axis=2))


def path_length(start: Point | None, pts: np.ndarray, order: Sequence[int],
                closed: bool = False) -> float:
    """Length of the polygon start -> pts[order[0]] -> ... (-> pts[order[0]] if closed)."""
    if len(order) == 0:
        return 0.0
    q = pts[np.asarray(order)]
    legs = np.hypot(*np.diff(q, axis=0).T).sum() if len(q) > 1 else 0.0
    total = float(legs)
    if start is not None:
        total += math.dist(start, tuple(q[0]))
    if closed and len(q) > 1:
        total += math.dist(tuple(q[-1]), tuple(q[0]))
    return total


def _held_karp(d0: np.ndarray, d: np.ndarray) -> tuple[int, ...]:
    """Optimal open path from a start (distances ``d0``) through all points (matrix ``d``)."""
    n = len(d0)
    full = 1 << n
    cost = np.full((full, n), np.inf)
    parent = np.full((full, n), -1, dtype=np.int64)
    for j in range(n):
        cost[1 << j, j] = d0[j]
    for mask in range(1, full):
        row = cost[mask]
        if not np.isfinite(row).any():
            continue
        for j in range(n):
            if mask >> j & 1:
                continue
            cand = row + d[:, j]
            k = int(np.argmin(cand))
            m2 = mask | 1 << j
            if cand[k] < cost[m2, j]:
                cost[m2, j] = cand[k]
                parent[m2, j] = k
    j = int(np.argmin(cost[full - 1]))
    mask, order = full - 1, []
    while j >= 0:
        order.append(j)
        j, mask = int(parent[mask, j]), mask & ~(1 << j)
    return tuple(reversed(order))


def lkh_open_path(d0: np.ndarray, d: np.ndarray) -> tuple[int, ...]:
    """Near-optimal open path from a start (``d0``) through the points (``d``) by LKH-3: a
    symmetric TSP on start + points + a dummy joined to the start at 0 and to every point at a
    constant ``M`` (every tour pays ``M`` once when the dummy sits next to the start, twice
    otherwise, so the solver keeps it there and the tour minus the dummy is the open path)."""
    n = len(d0)
    big = float(d0.max() + d.max()) * 4 + 1.0
    m = np.zeros((n + 2, n + 2))
    m[0, 1:n + 1] = m[1:n + 1, 0] = d0
    m[1:n + 1, 1:n + 1] = d
    m[n + 1, 1:n + 1] = m[1:n + 1, n + 1] = big
    mat = lkh.integer_matrix(m, 100.0)       # LKH works in integers: cm
    tour = lkh.solve_matrix(mat, asymmetric=False)[:-1]
    i = tour.index(0)
    tour = tour[i:] + tour[:i]
    if tour[1] == n + 1:
        tour = [0, *reversed(tour[1:])]
    return tuple(t - 1 for t in tour[1:] if t != n + 1)


def mst_length(pts: np.ndarray) -> float:
    """Euclidean minimum spanning tree length of ``pts`` (dense; a lower bound of any path
    through them)."""
    from scipy.sparse.csgraph import minimum_spanning_tree

    if len(pts) < 2:
        return 0.0
    d = np.triu(_dist_matrix(pts) + 1e-9, 1)
    return float(minimum_spanning_tree(d).sum()) - 1e-9 * (len(pts) - 1)


def nearest_neighbour_bound(start: Point | None, pts: np.ndarray) -> float:
    """Lower bound of the shortest open path from ``start`` through ``pts`` (module
    docstring, ``BOUND``)."""
    from scipy.spatial import cKDTree

    if len(pts) < 2:
        return 0.0 if start is None or len(pts) == 0 else math.dist(start, tuple(pts[0]))
    tree = cKDTree(pts)
    nn = tree.query(pts, k=2)[0][:, 1]
    reach = 0.0 if start is None else float(tree.query(np.asarray(start))[0])
    return reach + float(nn.sum() - nn.max())


def ideal_path(points: Sequence[Point] | np.ndarray, start: Point | None = None, *,
               ordered: bool = False, closed: bool = False) -> Ideal:
    """The ideal distance through ``points`` from ``start`` (module docstring).  ``closed``
    (a loop back to the first point) requires ``ordered`` or no ``start``."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    n = len(pts)
    if n == 0:
        return Ideal(0.0, IdealMethod.EXACT, (), 0.0)
    if ordered or n == 1:
        order = tuple(range(n))
        dist = path_length(start, pts, order, closed)
        return Ideal(dist, IdealMethod.ORDERED if ordered else IdealMethod.EXACT, order, dist)
    if closed:
        raise ValueError("an unordered closed ideal is a TSP tour: not needed by any mission")
    if start is None:       # free start: the cheapest first point, i.e. a dummy at distance 0
        d0 = np.zeros(n)
        all_pts = pts
    else:
        d0 = np.hypot(pts[:, 0] - start[0], pts[:, 1] - start[1])
        all_pts = np.vstack([np.asarray(start, dtype=np.float64), pts])
    if n <= EXACT_MAX:
        order = _held_karp(d0, _dist_matrix(pts))
        dist = path_length(start, pts, order)
        return Ideal(dist, IdealMethod.EXACT, order, dist)
    if n <= TOUR_MAX:
        lower = max(mst_length(all_pts), nearest_neighbour_bound(start, pts))
        try:
            order = lkh_open_path(d0, _dist_matrix(pts))
        except lkh.LKHError as exc:     # LKH failed (runtime/lkh.py): the bound below
            warnings.warn(f"ideal: {exc}; reporting the lower bound", RuntimeWarning,
                          stacklevel=2)
            return Ideal(lower, IdealMethod.BOUND, (), lower)
        return Ideal(path_length(start, pts, order), IdealMethod.TOUR, order, lower)
    lower = nearest_neighbour_bound(start, pts)
    return Ideal(lower, IdealMethod.BOUND, (), lower)


def kinematic_floor(points: Sequence[Point] | np.ndarray, order: Sequence[int],
                    start: Pose | None, arrival_heading: float, radius: float, *,
                    parallel: bool = True, closed: bool = False,
                    headings: Sequence[float] | None = None) -> float:
    """Shortest length of the CSC path through ``points`` in ``order`` (from the ``start``
    pose; ``closed``: back to the first point, a periodic loop), arriving at each point with
    ``arrival_heading`` (or its opposite when ``parallel``; any of ``headings`` if given, e.g.
    the planner's admissible ones).  Dynamic programming over the arrival heading at each
    point.  NaN for more than :data:`KINEMATIC_MAX` legs."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)[np.asarray(order, dtype=np.int64)]
    if len(pts) == 0:
        return 0.0
    if len(pts) > KINEMATIC_MAX:
        return math.nan
    if headings is not None:
        heads = [float(h) for h in headings]
    else:
        heads = [arrival_heading, arrival_heading + math.pi] if parallel else [arrival_heading]
    seq = [*pts, pts[0]] if closed else list(pts)

    def legs(best0: list[float]) -> list[float]:
        best = best0
        for k in range(1, len(seq)):
            x, y = float(seq[k][0]), float(seq[k][1])
            best = [min(best[i] + shortest_csc(Pose(float(seq[k - 1][0]), float(seq[k - 1][1]),
                                                    heads[i]), x, y, h, radius).length
                        for i in range(len(heads))) for h in heads]
        return best

    if not closed:
        if start is None:
            best = [0.0 for _ in heads]
        else:
            best = [shortest_csc(start, float(pts[0][0]), float(pts[0][1]), h, radius).length
                    for h in heads]
        return float(min(legs(best)))
    # Periodic: fix the heading at the first point, fly round, come back with the same heading.
    out = math.inf
    for i in range(len(heads)):
        best = [0.0 if j == i else math.inf for j in range(len(heads))]
        out = min(out, legs(best)[i])
    return float(out)


def ideal_distance(points: Sequence[Point], start: Point | None) -> float:
    """:func:`ideal_path`'s distance (m) through ``points`` from ``start`` (free order)."""
    return ideal_path(points, start).distance

"""Tour-based ordering: the ``tour`` sorter (the "order" lever of issue #15).

The ``distance`` sorter is greedy: the next location is the cheapest to reach from the predicted
arrival pose.  When the hybrid layer knows more -- a static sensor marks the cells that will be
flown to (Cover's region, the patrol cells), and their shape -- it can plan the whole visiting
order before the mission, like a mission planner:

    order = argmin over the candidate orders o of  DubinsLength(start pose, cells in order o)

where ``DubinsLength`` is the kinematic floor of :mod:`.ideal` (CSC legs at the planning radius,
arriving at each cell with one of the admissible headings, chosen by dynamic programming).  The
candidates (:func:`candidate_orders`):

* boustrophedon (serpentine) sweeps of contiguous regions, along the arrival heading's axis and
  across it, entered from either end, with the column stride 1 ... 4: stride k flies column i,
  then i + k, i + 1, i + k + 1, ... so that every turn between columns spans at least the turn
  diameter (a fixed wing cannot U-turn into the adjacent 50 m column);
* the LKH-3 solution (``elkai``) of the generalised TSP whose nodes are (cell, arrival heading)
  pairs with Dubins leg costs (Noon-Bean transformation to an asymmetric TSP), for up to
  :data:`LKH_MAX` cells (~3 s at 150 cells; in a child process, ``runtime/lkh.py``: if LKH
  fails, the other candidates remain);
* the greedy nearest-Dubins order (what ``distance`` would fly on a static region).

The tour is planned when the Iterator is (re)initialised over all locations (``reset``: at the
start, before the mission's clock runs -- a mission planner's job, done on the ground from the
take-off pose --, and at each new pass, charged as think time like any sorting) and kept on
``resort``: the remaining tour cells are offered in tour order, all other locations after them
by Dubins length.  With ``HeadingChoice.LOOKAHEAD`` the motion planner arrives at each tour cell
with the heading the plan chose (:meth:`TourSorter.planned_heading`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from iterplan_compiler.runtime import lkh
from iterplan_compiler.runtime.planner import shortest_csc
from iterplan_compiler.runtime.sorter import Pose, Sorter, dubins_lengths

#: LKH on the (cell, heading) generalised TSP up to this many cells (2 x cells + 1 nodes).
#: Measured (300 cells, 601 nodes): 14 s and 1.6 % longer than the greedy order, so larger
#: sets keep the sweeps and the greedy order; at 150 cells LKH is 6 % shorter in 3 s.
LKH_MAX = 165
#: LKH trials (improvement attempts from perturbed tours) at most (60: as good as LKH's
#: default, the dimension, at 150 cells, in 40 % of the time).
TRIALS = 60
#: Keys of locations not on the tour start here (float32: metres stay exact to ~0.1 m).
OFF_TOUR = np.float32(1.0e6)


def dubins_order_plan(pts: np.ndarray, start: Pose | None, headings: tuple[float, ...],
                      radius: float) -> tuple[float, list[float]]:
    """Shortest CSC flight from ``start`` through ``pts`` in order, arriving at each with one
    of ``headings``: (length, the arrival heading at each point).  Dynamic programming over
    the heading at each point, with back-pointers."""
    if len(pts) == 0:
        return 0.0, []
    x0, y0 = float(pts[0][0]), float(pts[0][1])
    best = [0.0 if start is None else shortest_csc(start, x0, y0, h, radius).length
            for h in headings]
    back: list[list[int]] = []
    for k in range(1, len(pts)):
        px, py = float(pts[k - 1][0]), float(pts[k - 1][1])
        x, y = float(pts[k][0]), float(pts[k][1])
        new, arg = [], []
        for h in headings:
            c = [best[i] + shortest_csc(Pose(px, py, hi), x, y, h, radius).length
                 for i, hi in enumerate(headings)]
            i = int(np.argmin(c))
            new.append(c[i])
            arg.append(i)
        best = new
        back.append(arg)
    j = int(np.argmin(best))
    idx = [j]
    for arg in reversed(back):
        j = arg[j]
        idx.append(j)
    return float(min(best)), [headings[i] for i in reversed(idx)]


def dubins_order_length(pts: np.ndarray, start: Pose | None, headings: tuple[float, ...],
                        radius: float) -> float:
    """The length of :func:`dubins_order_plan`."""
    return dubins_order_plan(pts, start, headings, radius)[0]


def _sweeps(pts: np.ndarray, axis: float, spacing: float) -> list[list[int]]:
    """Serpentine orders of ``pts`` in columns along ``axis`` (radians), strides 1..4, both
    ends, both first directions."""
    c, s = math.cos(axis), math.sin(axis)
    along = pts[:, 0] * c + pts[:, 1] * s
    across = -pts[:, 0] * s + pts[:, 1] * c
    col = np.rint((across - across.min()) / spacing).astype(np.int64)
    cols = [np.flatnonzero(col == k) for k in range(int(col.max()) + 1)]
    cols = [ix[np.argsort(along[ix], kind="stable")] for ix in cols if len(ix)]
    out = []
    for stride in range(1, 5):
        seq: list[int] = []
        for base in range(0, len(cols), 2 * stride if stride > 1 else 1):
            if stride == 1:
                seq.append(base)
                continue
            for j in range(stride):
                seq.extend(i for i in (base + j, base + j + stride) if i < len(cols))
        for rev_cols in (False, True):
            order_cols = seq[::-1] if rev_cols else seq
            for up in (True, False):
                o: list[int] = []
                for n, ci in enumerate(order_cols):
                    ix = cols[ci]
                    o.extend((ix if (n % 2 == 0) == up else ix[::-1]).tolist())
                out.append(o)
    return out


def _greedy(pts: np.ndarray, start: Pose, headings: tuple[float, ...],
            radius: float) -> list[int]:
    """Nearest-next by Dubins length (the ``distance`` sorter's order on a static set)."""
    left = list(range(len(pts)))
    pose, order = start, []
    while left:
        xs, ys = pts[left, 0], pts[left, 1]
        best = np.full(len(left), np.inf, dtype=np.float32)
        head = np.zeros(len(left))
        for h in headings:
            d = dubins_lengths(pose, xs, ys, h, radius)
            better = d < best
            best = np.where(better, d, best)
            head = np.where(better, h, head)
        j = int(np.argmin(best))
        order.append(left.pop(j))
        pose = Pose(float(xs[j]), float(ys[j]), float(head[j]))
    return order


def _lkh_gtsp(pts: np.ndarray, start: Pose, headings: tuple[float, ...],
              radius: float) -> list[int]:
    """LKH-3 on the (cell, heading) generalised TSP (Noon-Bean: each cell's heading nodes form
    a zero-cost cycle, the tour enters a cell at the heading it is flown with and leaves from
    the cycle's predecessor at that node's cost, plus ``M`` per inter-cell arc)."""
    m, h = len(pts), len(headings)
    n = 1 + m * h                                   # node 0: the start; 1 + i*h + a: (i, a)
    cost = np.zeros((n, n))
    for a, ha in enumerate(headings):               # leg (i, a) -> (j, b)
        for i in range(m):
            row = np.stack([dubins_lengths(Pose(float(pts[i, 0]), float(pts[i, 1]), ha),
                                           pts[:, 0], pts[:, 1], hb, radius)
                            for hb in headings], axis=1).reshape(-1)
            cost[1 + i * h + a, 1:] = row
    for b, hb in enumerate(headings):
        cost[0, 1 + b::h] = dubins_lengths(start, pts[:, 0], pts[:, 1], hb, radius)
    big = float(cost.max()) * 2 + 1.0
    tsp = np.full((n, n), 10 * big)
    tsp[0, 1:] = cost[0, 1:] + big
    tsp[1:, 0] = big                                # the open end: back to the start for free
    for i in range(m):
        for a in range(h):
            u = 1 + i * h + a
            succ = 1 + i * h + (a + 1) % h          # the cluster cycle
            others = np.ones(n, dtype=bool)
            others[0] = False
            others[1 + i * h:1 + (i + 1) * h] = False
            tsp[u, others] = cost[succ, others] + big
            if h > 1:
                tsp[u, succ] = 0.0
    np.fill_diagonal(tsp, 0.0)
    tour = solve_atsp(lkh.integer_matrix(tsp, 10.0), trials=max(20, min(n, TRIALS)))
    i0 = tour.index(0)
    seq = tour[i0:-1] + tour[:i0]
    order, seen = [], set()
    for node in seq[1:]:
        cell = (node - 1) // h
        if cell not in seen:
            seen.add(cell)
            order.append(cell)
    return order


def solve_atsp(matrix: np.ndarray, trials: int) -> list[int]:
    """An (asymmetric) TSP tour of the integer ``matrix`` by LKH-3 (``runtime.lkh``: in a
    child process), closed (the first node repeated at the end).  LKH's trial budget is
    ``trials`` (its default, the dimension, costs ~30 s for 600 nodes here), one run, LKH's
    fixed seed: deterministic.  Raises ``lkh.LKHError``."""
    return lkh.solve_matrix(matrix, asymmetric=True, trials=trials)


def candidate_orders(pts: np.ndarray, start: Pose, headings: tuple[float, ...],
                     radius: float, spacing: float) -> list[list[int]]:
    """The orders :func:`plan_tour` chooses from (module docstring)."""
    cands = []
    if len(pts) > 1:
        for axis in (headings[0], headings[0] + math.pi / 2):
            cands.extend(_sweeps(pts, axis, spacing))
    # With more than two headings, the orders found with the first two (the map's axis,
    # either way) are candidates too: the heuristics over 4 headings per cell can miss them,
    # and flown with all the headings (the DP) they are never longer, so a plan over the grid
    # headings is never longer than one over the axis.
    sets = [headings] if len(headings) <= 2 else [headings, headings[:2]]
    for hs in sets:
        cands.append(_greedy(pts, start, hs, radius))
        if 2 <= len(pts) <= LKH_MAX:
            try:
                cands.append(_lkh_gtsp(pts, start, hs, radius))
            except lkh.LKHError as exc:     # the sweeps and the greedy order remain
                warnings.warn(f"tour sorter: {exc}; planning with the sweeps and the greedy "
                              "order", RuntimeWarning, stacklevel=2)
    return cands


def plan_tour(pts: np.ndarray, start: Pose, headings: tuple[float, ...], radius: float,
              spacing: float) -> tuple[list[int], list[float]]:
    """The shortest (kinematic floor) of the candidate orders of ``pts`` from ``start``:
    (order, arrival heading at each point of the order)."""
    if len(pts) == 0:
        return [], []
    cands = candidate_orders(pts, start, headings, radius, spacing) if len(pts) > 1 else [[0]]
    plans = [(dubins_order_plan(pts[o], start, headings, radius), o) for o in cands]
    (_, heads), order = min(plans, key=lambda p: p[0][0])
    return order, heads


@dataclass
class TourSorter(Sorter):
    """Tour cells (``interesting``, a bool mask by cell id) in planned tour order, then every
    other location by Dubins length (see the module docstring)."""

    radius: float
    arrival_heading: float
    interesting: np.ndarray
    headings: tuple[float, ...]
    spacing: float = 50.0
    name = "tour"
    _rank: dict[int, int] = field(default_factory=dict)
    _heading: dict[int, float] = field(default_factory=dict)
    _planned_for: tuple = ()

    def _plan(self, xs: np.ndarray, ys: np.ndarray, ids: np.ndarray, pose: Pose) -> None:
        key = (pose, len(ids), int(ids[0]) if len(ids) else -1)
        if key == self._planned_for:
            return                      # the same pass planned again (executor set-up)
        on = self.interesting[ids]
        pts = np.column_stack([xs[on], ys[on]]).astype(np.float64)
        order, heads = plan_tour(pts, pose, self.headings, self.radius, self.spacing)
        tour_ids = ids[on][order].tolist()
        self._rank = {int(c): k for k, c in enumerate(tour_ids)}
        self._heading = {int(c): h for c, h in zip(tour_ids, heads, strict=True)}
        self._planned_for = key

    def planned_heading(self, cell: int) -> float | None:
        """The arrival heading the tour plans at ``cell`` (None: not on the tour)."""
        return self._heading.get(int(cell))

    def _tour_keys(self, ids: np.ndarray) -> np.ndarray:
        rank = np.full(len(ids), -1.0, dtype=np.float32)
        on = np.flatnonzero(self.interesting[ids])
        rank[on] = [self._rank.get(int(c), -1) for c in ids[on].tolist()]
        return rank

    def on_reset(self, xs, ys, ids, pose):
        """A fresh pass over every location: plan the tour from ``pose``."""
        self._plan(np.asarray(xs), np.asarray(ys), np.asarray(ids), pose)

    def keys(self, xs, ys, ids, pose):
        rank = self._tour_keys(ids)
        out = np.full(len(ids), np.inf, dtype=np.float32)
        for h in self.headings:
            np.fmin(out, dubins_lengths(pose, xs, ys, h, self.radius), out=out)
        out += OFF_TOUR
        on = rank >= 0
        out[on] = rank[on]
        return out


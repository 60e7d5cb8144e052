"""The Sorter: in which order the Iterator offers the remaining locations.

The paper's hybrid layer assumes the best next location is the one that is cheapest to reach from
the pose the UAV *will have* when ``arrived`` fires.  Strategies (paper §V "Runtime overhead"):

``distance``
    Length of the shortest Dubins-like path (turn at the minimum radius, straight, turn at the
    minimum radius: the CSC words LSL, RSR, LSR, RSL, i.e. "at most two turns") from the arrival
    pose to each location, arriving with a fixed heading (or, with ``parallel=True``, with either
    that heading or its opposite: "parallel to a given fixed direction").
``last``
    The deliberately bad order: the *interesting* locations (where a next-location sensor says yes)
    go to the end, everything else first, each group in map order.
``random``
    A fresh seeded random permutation on every re-sort.

A sorter maps ``(x, y, pose)`` to priority keys (smaller = offered earlier); ``best`` gives just
the first location and :func:`select_smallest` the first ``k`` in order without a full sort.
The distance kernel (:func:`dubins_lengths`) is vectorised NumPy in float32 over chunks, every
step writing into a reused workspace (no temporaries), with no per-element sin/cos: targets are
rotated into the start frame once; the outer words (LSL, RSR) need no angle at all, the inner
words (LSR, RSL) one polynomial half-angle ``atan`` each; the "parallel" variant shares all of
the geometry between the two arrival directions.  About 120 NumPy passes per chunk for a fixed
arrival heading, 220 for parallel; ``benchmarks/sorter_bench.py`` prints the throughput.
"""

from __future__ import annotations

import copy
import enum
import math
from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * math.pi
# Elements per chunk.  The kernel makes ~100-200 NumPy calls per chunk at ~1 us of call overhead
# each, so small chunks are overhead-bound; 15 work rows of 32k float32 (1.9 MB) spill from L2
# into L3 but still measured best here (8k: 1.4x, 4k: 2x slower).  Re-tune with
# ``python benchmarks/sorter_bench.py --chunks 8192,16384,32768,65536``.
CHUNK = 32768


@dataclass(frozen=True)
class Pose:
    """Planar pose: ENU metres and math heading (radians, CCW from east)."""

    x: float
    y: float
    heading: float


# Minimax polynomial for atan(t), t in [-1, 1] (odd powers up to t^11), max error 1.7e-6 rad:
# ~4x faster than np.arctan2, whose float32 loop is not vectorised on every build.
_ATAN_C = (0.99997726, -0.33262347, 0.19354346, -0.11643287, 0.05265332, -0.01172120)
_F32 = np.float32
_PI = _F32(math.pi)
_HALF_PI = _F32(math.pi / 2)
_TWO_PI32 = _F32(TWO_PI)
# The inner-tangent kernel evaluates b = pi/2 - 2 atan(t) = pi/2 + t * sum(_HALF_C[i] t^2i).
_HALF_C = tuple(_F32(-2.0 * c) for c in _ATAN_C)
_SIGN_BIT = np.uint32(0x80000000)


def fast_angle(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``atan2(y, x)`` mapped to [0, 2*pi), float32, |error| < 3e-6 rad."""
    ax = np.abs(x)
    ay = np.abs(y)
    mx = np.maximum(ax, ay)
    mx += _F32(1e-30)  # (0, 0) -> angle 0 instead of NaN
    t = np.minimum(ax, ay)
    t /= mx
    s = t * t
    p = _F32(_ATAN_C[5]) * s
    for c in _ATAN_C[4::-1]:
        p += _F32(c)
        if c != _ATAN_C[0]:
            p *= s
    p *= t
    # Octant fix-ups as arithmetic blends, not np.where: where() is branchy and mispredicts
    # badly on unstructured data (10 ns/element against ~1.5 for the blend).
    p += (ay > ax) * (_HALF_PI - (p + p))
    p += (x < 0) * (_PI - (p + p))             # now the angle of (x, |y|), in [0, pi]
    p += (y < 0) * (_TWO_PI32 - (p + p))
    return p


# -- the CSC kernel ------------------------------------------------------------------------------
# Every step below is one NumPy call writing into a preallocated chunk-sized buffer: at ~1 us of
# call overhead and ~0.15 ns/element per pass on hot data, the cost is (number of passes) x
# (chunk fits in L2).  Fresh temporaries per operation (the previous kernel) cost ~2x more per
# pass because every result lands in cold memory.  Buffer map (rows of the workspace):
_AX, _BX, _PY, _VY, _N2, _B2, _AX2, _BX2 = range(8)
_S0 = 8           # scratch rows _S0 .. _S0 + 6
_NBUF = _S0 + 7


def _outer(dst: np.ndarray, first: bool, vx: np.ndarray, vy: np.ndarray, n2: np.ndarray,
           theta: float, r: float, f: list, m: list) -> None:
    """Outer-tangent word (turn left, straight, turn left) along the centre-to-centre vector v
    in a frame where the start heading is 0 and the arrival heading is ``theta`` in [0, 2pi).

    Its two arcs telescope to ``theta``, plus one full circle when angle(v) lies beyond theta —
    decided by a half-plane test, no angle needed.  The tolerance (1e-5 |v|) keeps "exactly
    equal" on the no-circle side, so float32 noise on a straight-ahead target never adds 2*pi*r.
    Writes (``first``) or ``fmin``s the length into ``dst``.  RSR is this with y mirrored.
    """
    d, tol, cr, tmp = f[_S0], f[_S0 + 1], f[_S0 + 2], f[_S0 + 3]
    pos = m[0]
    ct, st = math.cos(theta), math.sin(theta)
    # ncr = -cross(theta direction, v): negative when v is CCW of theta.
    np.multiply(vx, _F32(st), out=cr)
    np.multiply(vy, _F32(ct), out=tmp)
    np.subtract(cr, tmp, out=cr)
    # theta in the upper half: angle(v) > theta  <=>  v in the lower half or CCW of theta
    #   <=>  min(ncr, vy) < -tol.   Lower half: both  <=>  max(ncr, vy) < -tol.
    if st < 0 or (st == 0 and ct < 0):
        np.maximum(cr, vy, out=cr)
    else:
        np.minimum(cr, vy, out=cr)
        if theta < 0.1:
            # Nearly degenerate wedge [0, theta]: both half-plane tests also pass (within tol)
            # for v pointing *backwards* (angle ~pi), e.g. a target straight behind with the
            # arrival heading equal to the start heading.  The wedge lies ahead of its
            # bisector, so "v . bisector < 0" also means angle(v) > theta.
            np.multiply(vx, _F32(math.cos(theta / 2)), out=tmp)
            np.multiply(vy, _F32(math.sin(theta / 2)), out=tol)
            np.add(tmp, tol, out=tmp)
            np.minimum(cr, tmp, out=cr)
    np.sqrt(n2, out=d)
    np.multiply(d, _F32(1e-5), out=tol)
    np.add(cr, tol, out=cr)
    np.less(cr, 0, out=pos)
    np.multiply(pos, _F32(TWO_PI * r), out=tmp)
    np.add(tmp, _F32(r * theta), out=tmp)
    if first:
        np.add(d, tmp, out=dst)
    else:
        np.add(d, tmp, out=d)
        np.fmin(dst, d, out=dst)


def _inner(dst: np.ndarray, vx: np.ndarray, vy: np.ndarray, n2: np.ndarray, theta: float,
           r: float, f: list, m: list) -> None:
    """Inner-tangent word (turn left, straight, turn right) along centre vector v; arrival angle
    ``theta`` in [0, 2pi).  ``fmin``s its length into ``dst``.  RSL is this with y mirrored.

    The straight heading is psi = angle(v) + atan2(2r, L) with L = sqrt(|v|^2 - 4r^2): v rotated
    by that angle is (X, Y) = (vx L - 2r vy, vy L + 2r vx), whose norm is exactly |v|^2, so one
    half-angle atan gives angle(|X|, Y) = 2 atan(Y / (|v|^2 + |X|)) with the argument in [-1, 1]
    (no min/max/division range reduction), and psi = pi/2 - copysign(pi/2 - that, X).
    Where the circles overlap L is NaN, every result is NaN and ``fmin`` ignores it (no masks).
    """
    L, X, Y, t, s, p, g = (f[_S0 + i] for i in range(7))
    two_r = _F32(2 * r)
    np.subtract(n2, _F32(4 * r * r), out=L)
    np.sqrt(L, out=L)
    np.multiply(vx, L, out=X)
    np.multiply(vy, two_r, out=t)
    np.subtract(X, t, out=X)
    np.multiply(vy, L, out=Y)
    np.multiply(vx, two_r, out=t)
    np.add(Y, t, out=Y)
    np.abs(X, out=t)
    np.add(t, n2, out=t)
    np.divide(Y, t, out=t)
    np.multiply(t, t, out=s)
    np.multiply(s, _HALF_C[5], out=p)
    for c in _HALF_C[4:0:-1]:
        np.add(p, c, out=p)
        np.multiply(p, s, out=p)
    np.add(p, _HALF_C[0], out=p)
    np.multiply(p, t, out=p)
    np.add(p, _HALF_PI, out=p)            # b = pi/2 - angle(|X|, Y), in [0, pi]
    # g = copysign(b, X) with two integer passes (np.copysign's float32 loop is ~8x slower);
    # b >= 0 up to polynomial error, so OR-ing X's sign bit in is the copysign.
    xb = X.view(np.uint32)
    np.bitwise_and(xb, _SIGN_BIT, out=xb)
    pb = p.view(np.uint32)
    np.bitwise_or(pb, xb, out=pb)
    # psi = pi/2 - g in [-pi/2, 3pi/2].  Turning wrap(psi) + wrap(psi - theta) is
    # pi - theta - 2g plus 2pi per wrap: at psi < 0 (g > pi/2), at psi < theta
    # (g > pi/2 - theta) and at psi < theta - 2pi (g > 5pi/2 - theta).  For g in [-pi, pi]
    # the last never fires when theta <= 3pi/2, and the second always fires when theta > 3pi/2
    # (a constant), so exactly two per-element comparisons remain.
    np.multiply(p, _F32(-2 * r), out=g)
    np.add(g, L, out=g)
    if theta <= 1.5 * math.pi:
        c2, const = math.pi / 2 - theta, math.pi - theta
    else:
        c2, const = 2.5 * math.pi - theta, 3 * math.pi - theta
    np.add(g, _F32(r * const), out=g)
    np.greater(p, _F32(math.pi / 2), out=m[0])
    np.greater(p, _F32(c2), out=m[1])
    wraps = m[0].view(np.uint8)            # 0, 1 or 2 (uint8 adds are ~4x cheaper than float)
    np.add(wraps, m[1].view(np.uint8), out=wraps)
    np.multiply(wraps, _F32(TWO_PI * r), out=t)
    np.add(g, t, out=g)
    np.fmin(dst, g, out=dst)


# Geometry, in the start frame (start at the origin, heading 0; target p, arrival angle b):
# start circles Ls = (0, r), Rs = (0, -r); goal circles A = p + r(-sin b, cos b) (left of the
# arrival heading) and B = p - r(-sin b, cos b).  The four centre-to-centre vectors u = A - Ls,
# v = B - Rs, w = B - Ls, z = A - Rs carry all eight words of both arrival directions, because
# b + pi swaps A and B: LSL/RSR/LSR/RSL(b) use u/v/w/z and (b + pi) uses w/z/u/v.  So
# ``parallel`` shares the rotation, the vectors and their squared norms.
def dubins_lengths(start: Pose, xs: np.ndarray, ys: np.ndarray, arrival_heading: float,
                   radius: float, *, parallel: bool = False, chunk: int = CHUNK,
                   return_flip: bool = False):
    """Shortest CSC path length (float32, metres) from ``start`` to every ``(xs[i], ys[i])``
    arriving with ``arrival_heading`` (or its opposite too when ``parallel``).

    With ``return_flip`` also returns a bool array: True where arriving with
    ``arrival_heading + pi`` is the shorter choice.  Pure function; ``xs``/``ys`` any float dtype
    (float32 avoids a conversion pass).
    The geometry is in the comment above.
    """
    n = len(xs)
    out = np.empty(n, dtype=np.float32)
    flip = np.zeros(n, dtype=bool) if return_flip else None
    if n == 0:
        return (out, flip) if return_flip else out
    chunk = max(1, int(chunk))
    r = float(radius)
    c32, s32 = _F32(math.cos(start.heading)), _F32(math.sin(start.heading))
    x0, y0 = _F32(start.x), _F32(start.y)
    beta = arrival_heading - start.heading
    sb, cb = math.sin(beta), math.cos(beta)
    bw, nbw = beta % TWO_PI, (-beta) % TWO_PI
    bw2, nbw2 = (beta + math.pi) % TWO_PI, (-beta - math.pi) % TWO_PI
    # (x row, mirrored, y offset, (word, theta) for b, (word, theta) for b + pi).  Mirrored
    # vectors (v, z) store -y so that RSR/RSL run as LSL/LSR with theta = wrap(-heading).
    vecs = (
        (_AX2, _AX, False, r * cb - r, ("o", bw), ("i", bw2)),       # u = A - Ls
        (_BX2, _BX, True, r * cb - r, ("o", nbw), ("i", nbw2)),      # v = B - Rs
        (_BX2, _BX, False, -r * cb - r, ("i", bw), ("o", bw2)),      # w = B - Ls
        (_AX2, _AX, True, -r * cb - r, ("i", nbw), ("o", nbw2)),     # z = A - Rs
    )
    size = min(chunk, n)
    fbuf = np.empty((_NBUF, size), dtype=np.float32)
    mbuf = np.empty((2, size), dtype=bool)
    rows_full = (list(fbuf), list(mbuf))
    with np.errstate(invalid="ignore"):
        for i in range(0, n, chunk):
            k = min(chunk, n - i)
            f, m = rows_full if k == size else ([a[:k] for a in fbuf], [a[:k] for a in mbuf])
            best = out[i:i + k]
            best2 = f[_B2] if return_flip else best
            if return_flip:
                best2.fill(np.inf)
            dx, dy, t = f[_S0], f[_S0 + 1], f[_S0 + 2]
            np.subtract(xs[i:i + k], x0, out=dx, casting="unsafe")
            np.subtract(ys[i:i + k], y0, out=dy, casting="unsafe")
            ax, bx, py = f[_AX], f[_BX], f[_PY]
            np.multiply(dx, c32, out=ax)          # rotate into the start frame
            np.multiply(dy, s32, out=t)
            np.add(ax, t, out=ax)
            np.multiply(dy, c32, out=py)
            np.multiply(dx, s32, out=t)
            np.subtract(py, t, out=py)
            np.subtract(ax, _F32(r * sb), out=ax)       # x of A - Ls and A - Rs
            np.add(ax, _F32(2 * r * sb), out=bx)        # x of B - Ls and B - Rs
            np.multiply(ax, ax, out=f[_AX2])
            np.multiply(bx, bx, out=f[_BX2])
            vy, n2 = f[_VY], f[_N2]
            first = True
            for x2row, xrow, mirrored, off, w1, w2 in vecs:
                if mirrored:
                    np.subtract(_F32(off), py, out=vy)
                else:
                    np.add(py, _F32(off), out=vy)
                np.multiply(vy, vy, out=n2)
                np.add(n2, f[x2row], out=n2)
                vx = f[xrow]
                for (kind, theta), dst in ((w1, best), (w2, best2)) if parallel else ((w1, best),):
                    if kind == "o":
                        _outer(dst, first and dst is best, vx, vy, n2, theta, r, f, m)
                        if dst is best:
                            first = False
                    else:
                        _inner(dst, vx, vy, n2, theta, r, f, m)
            if flip is not None:
                np.less(best2, best, out=flip[i:i + k])
                np.fmin(best, best2, out=best)
    return (out, flip) if return_flip else out


def select_smallest(keys: np.ndarray, k: int) -> np.ndarray:
    """Indices of the ``k`` smallest ``keys`` in ascending key order, ties by index: exactly
    ``np.argsort(keys, kind="stable")[:k]``, without sorting or partitioning all of ``keys``.

    A threshold is read off a strided sample (a partition of <= 64k elements), one compare +
    ``flatnonzero`` pass collects the candidates at or below it (every key below the k-th
    smallest and all its ties), and only those are sorted: ~6 ms for k = 4096 of 10 M keys,
    against ~45-60 ms for ``argpartition`` (+ ~90 ms to apply it to an index queue).  When
    ``k`` is over 1/64 of ``keys``, or the sample under-estimates (fewer than ``k``
    candidates), the threshold comes from ``argpartition`` instead.  For callers that want only the best next location (``k = 1``) see
    :meth:`Sorter.best`.
    """
    keys = np.asarray(keys)
    n = len(keys)
    k = min(int(k), n)
    if k <= 0:
        return np.zeros(0, dtype=np.int64)
    if n <= 1024:
        return np.argsort(keys, kind="stable")[:k]
    cand = np.zeros(0, dtype=np.int64)
    if n > 64 * k:          # else the candidates would be a large share of keys anyway
        sample = keys[::max(1, n // 65536)]
        j = min(len(sample) - 1, int(2 * k * len(sample) / n) + 8)
        cand = np.flatnonzero(keys <= np.partition(sample, j)[j])
    if len(cand) < k:
        kth = keys[np.argpartition(keys, k - 1)[k - 1]]
        cand = np.flatnonzero(keys <= kth)
    # cand is in index order, so a stable sort of its keys breaks ties by index.
    return cand[np.argsort(keys[cand], kind="stable")[:k]]


class Sorter:
    """Strategy interface: ``keys(xs, ys, ids, pose)`` -> priority keys (smaller first)."""

    name = "abstract"

    def keys(self, xs: np.ndarray, ys: np.ndarray, ids: np.ndarray, pose: Pose) -> np.ndarray:
        raise NotImplementedError

    def lower_bounds(self, xs: np.ndarray, ys: np.ndarray, pose: Pose) -> np.ndarray | None:
        """Cheap lower bounds of :meth:`keys` (float32), or None when the strategy has none;
        the Iterator uses them to score only the locations that can come next."""
        return None

    def on_reset(self, xs: np.ndarray, ys: np.ndarray, ids: np.ndarray, pose: Pose) -> None:
        """The Iterator starts a pass over all of L from ``pose`` (a planning sorter plans
        here, before the mission clock runs or between passes); default: nothing."""

    def planned_heading(self, cell: int) -> float | None:
        """The arrival heading this sorter planned for ``cell`` (a planning sorter; the
        motion planner then arrives so), or None: the planner chooses."""
        return None

    def fork(self) -> Sorter:
        """An independent copy (``Iterator.fork``): using it never changes this sorter.  The
        default shares the fields, which sorters replace rather than change in place."""
        return copy.copy(self)

    def best(self, xs: np.ndarray, ys: np.ndarray, ids: np.ndarray, pose: Pose) -> int:
        """Index (into the given arrays) of the location a full stable sort by :meth:`keys`
        would put first: the smallest key, ties to the lowest index.  One kernel pass and an
        ``argmin``; no sort.  Requires at least one location."""
        return int(np.argmin(self.keys(xs, ys, ids, pose)))


@dataclass
class DistanceSorter(Sorter):
    """Dubins-like path length from the (predicted) arrival pose; see module docstring."""

    radius: float
    arrival_heading: float
    parallel: bool = True
    #: also admit the other grid axis (``ArrivalHeadings.GRID``: 4 headings)
    grid: bool = False
    name = "distance"

    def keys(self, xs, ys, ids, pose):
        out = dubins_lengths(pose, xs, ys, self.arrival_heading, self.radius,
                             parallel=self.parallel or self.grid)
        if self.grid:
            np.fmin(out, dubins_lengths(pose, xs, ys, self.arrival_heading + math.pi / 2,
                                        self.radius, parallel=True), out=out)
        return out

    def lower_bounds(self, xs, ys, pose):
        """Straight-line distance from the pose: no path to a location is shorter."""
        dx = np.subtract(xs, _F32(pose.x), dtype=np.float32)
        dy = np.subtract(ys, _F32(pose.y), dtype=np.float32)
        dx *= dx
        dy *= dy
        dx += dy
        return np.sqrt(dx, out=dx)


@dataclass
class LastSorter(Sorter):
    """Interesting locations last (``interesting`` is a bool mask indexed by cell id)."""

    interesting: np.ndarray
    name = "last"

    def keys(self, xs, ys, ids, pose):
        flag = self.interesting[ids].astype(np.int64)
        # Map order within each group: the cell id itself is a unique tiebreak.
        return flag * (int(self.interesting.shape[0]) + 1) + ids


class RandomSorter(Sorter):
    """A new seeded random order on every re-sort (deterministic given the seed)."""

    name = "random"

    def __init__(self, seed: int = 0):
        self.rng = np.random.default_rng(seed)

    def keys(self, xs, ys, ids, pose):
        return self.rng.random(len(ids), dtype=np.float32)

    def fork(self) -> RandomSorter:
        """A copy with its own generator in the same state (the copy's draws do not advance
        this sorter's)."""
        twin = copy.copy(self)
        twin.rng = copy.deepcopy(self.rng)
        return twin


class SorterKind(enum.Enum):
    """The strategies (``iterc run --sorter``): the paper's three and the planned tour."""

    DISTANCE = "distance"
    LAST = "last"
    RANDOM = "random"
    TOUR = "tour"          # runtime/tour.py


SORTERS = tuple(k.value for k in SorterKind)


def sorter_kind(name: str | SorterKind) -> SorterKind:
    """The :class:`SorterKind` named ``name`` (ValueError with the choices otherwise)."""
    if isinstance(name, SorterKind):
        return name
    try:
        return SorterKind(name)
    except ValueError:
        raise ValueError(f"unknown sorter {name!r}; choose one of {', '.join(SORTERS)}") \
            from None

"""Snapshots of a flying mission for the live view (executor side; no web framework here).

:class:`Observer` is the executor's ``RunConfig.observe`` hook.  It is called after every
physical tick; all but a few calls per wall second return after one clock read.  When a snapshot
is due it copies only what changed since the last one — the new track points, the new log
entries, the cells newly added to the iterator's done set ``D`` (on maps of up to
:data:`MAX_CELLS` locations), the planned path when a new one was planned — plus a handful of
scalars, and hands the result to the :class:`Hub`.  The hub (shared with the server thread under
a lock) keeps the cumulative state a newly connected page starts from and a bounded queue of
deltas for the pages already connected.

Messages (JSON-ready dicts; the page's ``view.js`` applies them):

* ``map`` (once): cell rectangles (lat/lon bounds) and sensor layers, home, bounds;
* ``state``: a delta — ``t`` (mission s), ``pose``, ``track`` (new [lat, lon] points), ``it``
  (iterator: ``next``, ``done``, ``remaining``, ``first``), ``done_new``/``done_reset``,
  ``path`` (new planned path or ``[]`` when none), ``ctrl`` (state, enabled actions), ``log``
  (new entries), ``photos`` (new), counters, ``overhead_pct``, ``mode``, ``link_ok`` and at the
  end ``final`` (``ok``, ``reason``, ``summary``).
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from typing import Any

import numpy as np

#: Maps with more locations draw only their outline and the sensor cells (a browser cannot draw
#: 10^6 rectangles); the done set is then shown as a count only.
MAX_CELLS = 6000
#: Sensor cells drawn at most (per sensor) on big maps.
MAX_SENSOR_CELLS = 6000
#: Track points kept for a newly connected page (older ones are thinned out).
MAX_TRACK = 20000
TRACK_PER_DELTA = 50   # at most this many new track points per snapshot (the last always)
LOG_KEEP = 60          # log entries a newly connected page gets
LOG_PER_DELTA = 40     # at most this many new log entries per snapshot
FIRST_K = 5            # the sorter's first few (R in offered order, already sorted prefix only)
PATH_POINTS = 160      # planned path samples sent

COLOURS = {"inP": "#ff8c00", "P": "#ff8c00", "fire": "#d0021b"}
PALETTE = ("#4a90e2", "#7ed321", "#9013fe", "#50e3c2", "#b8860b")


def _r(v: float, nd: int = 7) -> float:
    return round(float(v), nd)


def map_message(grid: Any, title: str = "") -> dict:
    """The static part of the page: cells, sensor layers, home, bounds (lat/lon)."""
    cs = grid.cell_size
    cells = np.asarray(grid.cells, dtype=np.int64)
    big = len(cells) > MAX_CELLS

    def rects(ids: np.ndarray) -> list[list[float]]:
        xs, ys = grid.centres(ids)
        s, w = grid.to_latlon(xs - cs / 2, ys - cs / 2)
        n, e = grid.to_latlon(xs + cs / 2, ys + cs / 2)
        return [[_r(a), _r(b), _r(c), _r(d)] for a, b, c, d in
                zip(np.atleast_1d(s), np.atleast_1d(w), np.atleast_1d(n), np.atleast_1d(e),
                    strict=True)]

    sensors = []
    for i, (name, ids) in enumerate(sorted(grid.sensors.items())):
        ids = np.asarray(ids, dtype=np.int64)
        sensors.append({"name": name, "colour": COLOURS.get(name, PALETTE[i % len(PALETTE)]),
                        "cells": [int(c) for c in ids[:MAX_SENSOR_CELLS]],
                        "count": int(len(ids))})
    shown = cells if not big else np.unique(np.concatenate(
        [np.asarray(s["cells"], dtype=np.int64) for s in sensors] or [np.zeros(0, np.int64)]))
    s0, w0 = grid.to_latlon(0.0, 0.0)
    n0, e0 = grid.to_latlon(grid.cols * cs, grid.rows * cs)
    hlat, hlon = grid.to_latlon(*grid.home)
    return {
        "type": "map", "title": title or grid.name, "name": grid.name,
        "cols": int(grid.cols), "rows": int(grid.rows), "cell_size": float(cs),
        "locations": int(len(cells)), "per_cell": not big,
        "cells": [int(c) for c in shown], "rects": rects(shown) if len(shown) else [],
        "names": [grid.cell_name(int(c)) for c in shown],
        "sensors": sensors, "home": [_r(hlat), _r(hlon)],
        "bounds": [[_r(s0), _r(w0)], [_r(n0), _r(e0)]],
    }


class Hub:
    """Thread-safe store between the executor's thread and the server's.

    ``publish`` (executor side) merges a delta into the cumulative state and queues it;
    ``full`` and ``since`` (server side) read them.  Deltas carry a sequence number; a page that
    fell behind the queue (``keep`` deltas) starts again from ``full``."""

    def __init__(self, map_msg: dict | None = None, *, keep: int = 400):
        self._lock = threading.Lock()
        self._map = map_msg
        self._seq = 0
        self._deltas: deque[dict] = deque(maxlen=keep)
        self._state: dict[str, Any] = {"type": "state", "phase": "waiting for the vehicle"}
        self._track: list[list[float]] = []
        self._done: set[int] = set()
        self._log: deque[list] = deque(maxlen=LOG_KEEP)
        self._photos: list[list] = []
        self.final = False
        self.replay: dict | None = None      # replay mode: the whole run (see replay.py)

    def set_map(self, map_msg: dict) -> None:
        with self._lock:
            self._map = map_msg

    def publish(self, delta: dict) -> None:
        with self._lock:
            self._seq += 1
            delta["seq"] = self._seq
            self._deltas.append(delta)
            st = self._state
            for k, v in delta.items():
                if k not in ("track", "log", "photos", "done_new", "done_reset"):
                    st[k] = v
            if delta.get("track"):
                self._track.extend(delta["track"])
                if len(self._track) > MAX_TRACK:
                    self._track = self._track[::2]
            if delta.get("done_reset"):
                self._done.clear()
            if delta.get("done_new"):
                self._done.update(delta["done_new"])
            if delta.get("log"):
                self._log.extend(delta["log"])
            if delta.get("photos"):
                self._photos.extend(delta["photos"])
            if delta.get("final"):
                self.final = True

    @property
    def seq(self) -> int:
        with self._lock:
            return self._seq

    def full(self) -> tuple[int, list[dict]]:
        """(sequence number, messages a new page starts from: map, then the whole state)."""
        with self._lock:
            st = dict(self._state)
            st.update(track=list(self._track), done_reset=True, done_new=sorted(self._done),
                      log=list(self._log), photos=list(self._photos), seq=self._seq,
                      full=True)
            msgs = [self._map] if self._map is not None else []
            return self._seq, [*msgs, st]

    def since(self, seq: int) -> list[dict] | None:
        """Deltas after ``seq``, or None when some were already dropped (send ``full``)."""
        with self._lock:
            if seq >= self._seq:
                return []
            if not self._deltas or self._deltas[0]["seq"] > seq + 1:
                return None
            return [d for d in self._deltas if d["seq"] > seq]

    def state(self) -> dict:
        """The cumulative state (for ``/api/state`` and tests)."""
        return self.full()[1][-1]


class Observer:
    """``RunConfig.observe`` hook: snapshots into ``hub`` at most ``rate`` per wall second."""

    def __init__(self, hub: Hub, rate: float = 5.0, clock=time.monotonic):
        self.hub = hub
        self.period = 1.0 / rate
        self.clock = clock
        self._next = 0.0
        self._track_i = 0
        self._log_i = 0
        self._photo_i = 0
        self._arr_i = 0
        self._iterator: Any = None
        self._sent: np.ndarray | None = None
        self._path_key: Any = None
        self._first_key: Any = None
        self._first_val: list[int] = []
        self._start: tuple[float, float] | None = None
        self._ideal = 0.0
        self._last_pt: tuple[float, float] | None = None
        self._t_last_arrival = 0.0
        self.snapshots = 0
        self.seconds = 0.0          # CPU time of this thread spent in snapshots (benchmark)

    def __call__(self, ex: Any, final: bool = False) -> None:
        now = self.clock()
        if now < self._next and not final:
            return
        self._next = now + self.period
        t = time.thread_time()
        try:
            self.hub.publish(self.snapshot(ex, final))
        finally:
            self.snapshots += 1
            self.seconds += time.thread_time() - t

    # -- the snapshot -----------------------------------------------------------------------------
    def snapshot(self, ex: Any, final: bool) -> dict:
        grid = ex.grid
        v = ex.vehicle
        p = v.pose()
        lat, lon = grid.to_latlon(p.x, p.y)
        started = bool(getattr(ex, "_started", True))
        d: dict[str, Any] = {
            "type": "state", "t": round(p.t - ex.t0, 2) if started else 0.0,
            "phase": "flying" if started else "starting",
            "pose": {"lat": _r(lat), "lon": _r(lon), "alt": round(float(p.alt), 1),
                     "heading": round((90.0 - math.degrees(p.course)) % 360.0, 1),
                     "gs": round(float(p.groundspeed), 1)},
        }
        # Track tail (the executor records a point every track_every mission seconds).
        tr = ex.track
        if len(tr) < self._track_i:
            self._track_i = 0
        new = tr[self._track_i:]
        self._track_i = len(tr)
        if len(new) > TRACK_PER_DELTA:      # a run much faster than real time: thin it out
            step = -(-len(new) // TRACK_PER_DELTA)
            new = new[step - 1::step] if (len(new) - 1) % step == step - 1 else \
                [*new[step - 1::step], new[-1]]
        if new:
            xs = np.fromiter((q[1] for q in new), float, len(new))
            ys = np.fromiter((q[2] for q in new), float, len(new))
            la, lo = grid.to_latlon(xs, ys)
            d["track"] = [[_r(a), _r(b)] for a, b in zip(np.atleast_1d(la), np.atleast_1d(lo),
                                                           strict=True)]
        d["it"] = self._iterator_state(ex, d)
        self._path(ex, d)
        # Controller.
        ctrl = ex.controller
        controllable = ex.table.controllable
        d["ctrl"] = {"state": int(ctrl.state),
                     "enabled": [[a, a in controllable] for a in sorted(ctrl.enabled())]}
        log = ex.log
        if len(log) < self._log_i:
            self._log_i = 0
        if len(log) > self._log_i:
            tail = log[max(self._log_i, len(log) - LOG_PER_DELTA):]
            d["log"] = [[e.t, e.kind, e.label, e.state,
                         grid.cell_name(e.cell) if e.cell >= 0 else ""] for e in tail]
            self._log_i = len(log)
        photos = ex.photos
        if len(photos) > self._photo_i:
            d["photos"] = []
            for _t, cell, x, y in photos[self._photo_i:]:
                la, lo = grid.to_latlon(x, y)
                d["photos"].append([_r(la), _r(lo), grid.cell_name(cell) if cell >= 0 else ""])
            self._photo_i = len(photos)
        d["counts"] = dict(ex.counts)
        d["photo_count"] = len(photos)
        d["compute_s"] = round(float(ex.compute_s), 3)
        d["overhead_pct"] = self._overhead(ex, p, started)
        d["mode"] = str(getattr(v, "mode", None) or ("SIM" if v.is_simulated else "?"))
        d["link_ok"] = bool(getattr(v, "link_ok", True))
        d["simulated"] = bool(v.is_simulated)
        if final:
            s = getattr(ex, "summary", {}) or {}
            ok = bool(getattr(ex, "ok", False))
            d["final"] = {"ok": ok, "reason": str(getattr(ex, "reason", "")), "summary": s,
                          "safe_state": str(getattr(ex, "safe_state", ""))}
            d["phase"] = "mission completed" if ok else \
                f"mission ended early: {getattr(ex, 'reason', '')}"
            if s.get("overhead_pct") is not None:
                d["overhead_pct"] = s["overhead_pct"]
            d["path"] = []
        return d

    def _iterator_state(self, ex: Any, d: dict) -> dict:
        it = ex.iterator
        grid = ex.grid
        n = it.next
        out: dict[str, Any] = {"next": None if n is None else grid.cell_name(n),
                               "next_cell": n, "done": int(it.num_done),
                               "remaining": int(it.remaining_count()),
                               "total": int(len(it.ids))}
        first = self._first(it)
        out["first"] = [grid.cell_name(int(c)) for c in first]
        out["first_cells"] = [int(c) for c in first]
        # D as deltas, on maps the page draws cell by cell.
        if len(it.ids) <= MAX_CELLS:
            done = it.done
            if it is not self._iterator or self._sent is None or len(self._sent) != len(done):
                self._iterator = it
                self._sent = np.zeros(len(done), dtype=bool)
                d["done_reset"] = True
            elif (self._sent & ~done).any():          # reset: D shrank
                self._sent[:] = False
                d["done_reset"] = True
            new = np.flatnonzero(done & ~self._sent)
            if len(new):
                self._sent[new] = True
                d["done_new"] = [int(c) for c in it.ids[new]]
        return out

    def _first(self, it: Any) -> list[int]:
        """The sorter's first few of R, read without changing the iterator (the observer must
        not change what the executor computes, nor when): the sorted prefix when there is one,
        else the smallest sort keys (a copy; computed once per re-sort, O(|R|))."""
        try:
            return self._first_of(it)
        except (AttributeError, IndexError, ValueError):   # another Iterator implementation
            return []

    def _first_of(self, it: Any) -> list[int]:
        head, sorted_to = it._head, it._sorted_to
        key = (id(it), it.resorts, head, sorted_to)
        if key == self._first_key:
            return self._first_val
        queue, keys = it._queue, it._keys
        if sorted_to >= min(head + FIRST_K, len(queue)):
            pos = queue[head:head + FIRST_K]
        else:
            k = keys[head:]
            m = min(FIRST_K, len(k))
            if m == 0:
                pos = queue[:0]
            else:
                part = np.argpartition(k, m - 1)[:m] if m < len(k) else np.arange(len(k))
                part = part[np.lexsort((part, k[part]))]
                pos = queue[head:][part]
        self._first_key, self._first_val = key, [int(c) for c in it.ids[pos]]
        return self._first_val

    def _path(self, ex: Any, d: dict) -> None:
        pl = ex.planner
        key = (id(pl), id(pl.path), pl.arrived)
        if key == self._path_key:
            return
        self._path_key = key
        if pl.path is None or pl.arrived or not len(getattr(pl, "_px", ())):
            d["path"] = []
            d["target"] = None
            return
        end = min(int(getattr(pl, "_end", len(pl._px) - 1)) + 1, len(pl._px))
        idx = np.unique(np.linspace(0, end - 1, min(PATH_POINTS, end)).astype(int))
        la, lo = ex.grid.to_latlon(pl._px[idx], pl._py[idx])
        d["path"] = [[_r(a), _r(b)] for a, b in zip(np.atleast_1d(la), np.atleast_1d(lo),
                                                      strict=True)]
        tgt = ex.ctx.target_cell if getattr(ex, "ctx", None) is not None else None
        d["target"] = None if tgt is None else ex.grid.cell_name(tgt)

    def _overhead(self, ex: Any, p: Any, started: bool) -> float | None:
        """Overhead so far: time flown up to the last arrival against straight legs between
        the cells visited so far (in the order flown) at cruise speed, in %.  The summary at the
        end uses the paper's ideal (the better of this and a nearest-neighbour tour)."""
        if not started:
            return None
        if self._start is None:
            self._start = self._last_pt = (float(p.x), float(p.y))
        arr = ex.arrivals
        for t, _cell, x, y in arr[self._arr_i:]:
            lx, ly = self._last_pt  # type: ignore[misc]
            self._ideal += math.hypot(x - lx, y - ly)
            self._last_pt = (x, y)
            self._t_last_arrival = t
        self._arr_i = len(arr)
        speed = float(getattr(ex.vehicle, "airspeed", 0.0) or 0.0)
        if self._ideal <= 0 or speed <= 0:
            return None
        ideal_t = self._ideal / speed
        return round((self._t_last_arrival - ideal_t) / ideal_t * 100.0, 1)

"""The mission summary of ``iterc run`` (``summary.json``): what was flown against the ideal.

Per iterator pass (a cell is visited once per pass; passes chained, each starting where the
previous one ended) the ideal is :func:`~iterplan_compiler.runtime.ideal.ideal_path` over the
cells arrived at (the paper's minimum flight distance at constant speed, no turn limits;
``ideal_method`` says how it was computed), and the kinematic floor the shorter of that order
and the order flown, flown as Dubins legs at the planning radius with the admissible arrival
headings (:func:`~iterplan_compiler.runtime.tour.dubins_order_length`).  So

    overhead_pct   = 100 (duration - ideal / speed) / (ideal / speed)
    physics_pct    = 100 (floor - ideal) / ideal         (what the turn radius costs at least)
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from iterplan_compiler.runtime.ideal import KINEMATIC_MAX, IdealMethod, ideal_path
from iterplan_compiler.runtime.sorter import Pose, sorter_kind
from iterplan_compiler.runtime.tour import dubins_order_length

if TYPE_CHECKING:
    from iterplan_compiler.runtime.executor import Executor


def _passes(ex: Executor) -> list[tuple[int, int]]:
    lo, out = 0, []
    n = len(ex.arrivals)
    for hi in [*ex._pass_marks, n]:
        if hi > lo:
            out.append((lo, hi))
        lo = hi
    return out


def ideal_and_floor(ex: Executor, start: tuple[float, float],
                    start_pose: Pose | None) -> tuple[float, float, set[IdealMethod]]:
    """(ideal distance, kinematic floor (NaN past ``KINEMATIC_MAX`` arrivals), methods)."""
    pts = np.asarray([(x, y) for _, _, x, y in ex.arrivals], dtype=np.float64).reshape(-1, 2)
    ideal, floor, methods = 0.0, 0.0, set()
    heads = ex.planner.admissible
    for lo, hi in _passes(ex):
        seg = pts[lo:hi]
        best = ideal_path(seg, start)
        ideal += best.distance
        methods.add(best.method)
        if len(pts) <= KINEMATIC_MAX:
            orders = [list(range(len(seg)))] + ([list(best.order)] if best.order else [])
            floor += min(dubins_order_length(seg[o], start_pose, heads, ex.radius)
                         for o in orders)
        else:
            floor = math.nan
        start = (float(seg[-1, 0]), float(seg[-1, 1]))
        start_pose = Pose(start[0], start[1], ex.planner.heading) if start_pose else None
    return ideal, floor, methods


def mission_summary(ex: Executor, ok: bool, reason: str) -> dict[str, Any]:
    """The summary dict (module docstring)."""
    duration = ex.vehicle.time - ex.t0 if ex._started else 0.0
    tr = np.asarray(ex.track, dtype=np.float64).reshape(-1, 4)
    m = tr[:, 0] >= 0        # the mission proper (after the controller started)
    seg = np.hypot(np.diff(tr[m, 1]), np.diff(tr[m, 2])) if m.sum() > 1 else np.zeros(0)
    start = tuple(tr[m][0, 1:3]) if m.any() else ex.grid.home
    ideal, floor, methods = ideal_and_floor(ex, (float(start[0]), float(start[1])),
                                            ex.start_pose)
    speed = ex.vehicle.airspeed
    ideal_t = ideal / speed if speed > 0 else math.nan
    overhead = (duration - ideal_t) / ideal_t * 100 if ideal_t > 0 else math.nan
    physics = (floor - ideal) / ideal * 100 if ideal > 0 and math.isfinite(floor) else math.nan

    def rnd(x: float, k: int = 1) -> float | None:
        return round(x, k) if math.isfinite(x) else None

    return {
        "ok": ok, "reason": reason, "controller": ex.table.name,
        "sorter": sorter_kind(ex.cfg.sorter).value, "ideal_compute": ex.cfg.ideal_compute,
        "headings": ex.cfg.headings.value, "heading_choice": ex.cfg.heading_choice.value,
        "locations": int(len(ex.grid.cells)),
        "duration_s": round(duration, 2), "distance_m": round(float(seg.sum()), 1),
        "ideal_distance_m": round(ideal, 1), "ideal_duration_s": round(ideal_t, 2),
        "ideal_method": "+".join(sorted(mt.value for mt in methods)) or "exact",
        "overhead_pct": rnd(overhead),
        "kinematic_floor_m": rnd(floor), "physics_overhead_pct": rnd(physics),
        "arrivals": ex.counts["arrived"], "photos": len(ex.photos),
        "go": ex.counts["go"], "steps": ex.counts["steps"],
        "passes": ex.counts["passes"], "misses": ex.planner.misses,
        "resorts": ex.iterator.resorts,
        "compute_s": round(ex.compute_s, 4) if not ex.cfg.ideal_compute else 0.0,
        "speed_mps": round(speed, 2), "turn_radius_m": round(ex.radius, 1),
        "vehicle": type(ex.vehicle).__name__, "safe_state": ex.safe_state,
    }

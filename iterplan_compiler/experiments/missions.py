"""One simulated mission per experiment case, and the measurements taken from its event log.

Measurements (what Fig. 3 plots):

* Ordered Patrol (fig3b): the *loop time* — time between two consecutive visits of the first
  patrol location (``visited.p.0``), i.e. one pass p.0 -> p.1 -> p.2 -> p.0.  Ideal: the closed
  tour through the three locations at constant speed.
* Cover (fig3c, fig3d): the *cover time* — from the moment the plan starts (the first
  ``has.next``) until every location of the region has been arrived at.  Ideal: reach the
  nearest region cell, then one cell side per further cell, at constant speed.

The runtime's compute-time accounting is on: time the plan spends iterating is flight time.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Iterable, Sequence
from pathlib import Path

from iterplan_compiler.experiments import flight
from iterplan_compiler.experiments.flight import LogEvent
from iterplan_compiler.experiments.stats import ideal_cover, ideal_patrol_loop
from iterplan_compiler.experiments.sweeps import Case, Experiment, case_map_data, layout
from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice
from iterplan_compiler.runtime.sorter import SorterKind

EXAMPLE_OF = {Experiment.FIG3B: "ordered_patrol", Experiment.FIG3C: "cover",
              Experiment.FIG3D: "cover"}


class MeasurementError(RuntimeError):
    """The log does not contain what the measurement needs (mission cut short?)."""


def loop_times(log: Sequence[LogEvent], marker: str = "visited.p.0") -> list[float]:
    """Durations between consecutive occurrences of ``marker``."""
    ts = [e.t for e in log if e.label == marker]
    return [b - a for a, b in zip(ts[:-1], ts[1:], strict=True)]


def cover_time(log: Sequence[LogEvent], region: Iterable[int]) -> tuple[float, LogEvent]:
    """(seconds from the first ``has.next`` until all ``region`` cells were arrived at, the
    start event).  Raises :class:`MeasurementError` if the region was not covered."""
    todo = set(int(c) for c in region)
    start = next((e for e in log if e.label == "has.next"), None)
    if start is None:
        raise MeasurementError("the plan never started (no has.next in the log)")
    for e in log:
        if e.label == "arrived" and e.cell in todo:
            todo.discard(e.cell)
            if not todo:
                return e.t - start.t, start
    raise MeasurementError(f"{len(todo)} region cell(s) never visited")


def measure(case: Case, log: Sequence[LogEvent], grid, speed: float, warmup: int = 0) -> dict:
    """The case's duration and ideal from its event log.  Patrol: the mean of ``case.loops``
    loops after ``warmup`` loops (the first loop carries the approach from the launch: the
    arrival pose at p.0 is the launch leg's); ``first_loop`` is the first loop's time,
    ``launch`` the time from the mission's start (after take-off) to the first visit of p.0."""
    if case.experiment is Experiment.FIG3B:
        loops = loop_times(log)
        if len(loops) < warmup + case.loops:
            raise MeasurementError(f"only {len(loops)} complete patrol loop(s) in the log")
        points = [grid.centre(int(grid.sensors[f"p.{i}"][0])) for i in range(case.count)]
        dur = sum(loops[warmup: warmup + case.loops]) / case.loops
        launch = next(e.t for e in log if e.label == "visited.p.0")
        return {"duration": dur, "ideal": ideal_patrol_loop(points, speed),
                "events": len(log), "first_loop": loops[0], "warmup": warmup,
                "launch": launch}
    region = [int(c) for c in grid.sensors["cover"]]
    dur, start = cover_time(log, region)
    centres = [grid.centre(c) for c in region]
    return {"duration": dur, "ideal": ideal_cover((start.x, start.y), centres,
                                                  grid.cell_size, speed),
            "events": len(log)}


def build_grid(case: Case):
    """The case's GridMap (runtime), with exactly ``case.universe`` locations."""
    import numpy as np

    from iterplan_compiler.runtime.mapfile import load_map

    grid = load_map(data=case_map_data(case))
    grid.cells = np.arange(case.universe, dtype=np.int64)
    return grid


class StopWhen:
    """Stop predicate over logged events: Ordered Patrol stops after ``loops + 1`` visits of
    p.0; Cover stops once every region cell has been arrived at (or after a full pass of the
    iterator, ``n.next``, which means some region cell was skipped)."""

    def __init__(self, case: Case, grid, warmup: int = 0):
        self.patrol = case.experiment is Experiment.FIG3B
        self.needed = warmup + case.loops + 1
        self.seen = 0
        self.todo = set() if self.patrol else {int(c) for c in grid.sensors["cover"]}

    def __call__(self, event: LogEvent) -> bool:
        if self.patrol:
            self.seen += event.label == "visited.p.0"
            return self.seen >= self.needed
        if event.label == "arrived":
            self.todo.discard(event.cell)
            return not self.todo
        return event.label == "n.next"


def preflight(experiment: Experiment, ctrl_dir: Path) -> str | None:
    """Compile the experiment's controller once (into ``ctrl_dir``) and check the runtime;
    return a message saying what is missing, or None when everything is there."""
    from iterplan_compiler.experiments.pipeline import StageError, compile_example

    try:
        compile_example(EXAMPLE_OF[experiment], ctrl_dir)
    except StageError as exc:
        return str(exc)
    try:
        from iterplan_compiler.runtime import executor  # noqa: F401
    except ImportError as exc:
        return f"runtime executor not available in this build ({exc})"
    return None


def kinematic_floor_s(case: Case, res, grid, radius: float, headings=None) -> float:
    """The measurement's kinematic floor (s): what the same mission costs at least with the
    turn radius (runtime/ideal.py).  Patrol: the periodic loop through the patrol cells in
    order; Cover: from the pose at the first ``has.next``, the shorter of the order flown and
    the ideal's order, each with the best arrival headings (``headings``: the run's admissible
    ones; default either way along the map's direction).  At the planned airspeed, like the
    ideal."""
    import numpy as np

    from iterplan_compiler.runtime.ideal import ideal_path, kinematic_floor
    from iterplan_compiler.runtime.sorter import Pose
    from iterplan_compiler.runtime.tour import dubins_order_length

    h = grid.arrival_heading
    if case.experiment is Experiment.FIG3B:
        pts = [grid.centre(int(grid.sensors[f"p.{i}"][0])) for i in range(case.count)]
        return kinematic_floor(pts, list(range(len(pts))), None, h, radius,
                               closed=True, headings=headings) / res.speed
    region = {int(c) for c in grid.sensors["cover"]}
    start = next(e for e in res.log if e.label == "has.next")
    tr = np.asarray(res.track, dtype=np.float64).reshape(-1, 3)
    k = int(np.clip(np.searchsorted(tr[:, 0], start.t), 1, len(tr) - 1))
    course = math.atan2(tr[k, 2] - tr[k - 1, 2], tr[k, 1] - tr[k - 1, 1])
    pose = Pose(start.x, start.y, course)
    flown: list[tuple[float, float]] = []
    seen: set[int] = set()
    for e in res.log:
        if e.label == "arrived" and e.cell in region and e.cell not in seen:
            seen.add(e.cell)
            flown.append(grid.centre(e.cell))
    arr = np.asarray(flown, dtype=np.float64).reshape(-1, 2)
    best = ideal_path(arr, (start.x, start.y))
    orders = [list(range(len(arr)))] + ([list(best.order)] if best.order else [])
    heads = (h, h + math.pi) if headings is None else tuple(headings)
    return min(dubins_order_length(arr[o], pose, heads, radius) for o in orders) / res.speed


class VehicleKind(enum.Enum):
    """The simulated aircraft of the sweeps."""

    #: the SITL-calibrated simulator (``SimParams.from_arduplane``, docs/sitl-calibration.md)
    #: with the paper's 17 m/s cruise: SITL's plane.parm + AIRSPEED_CRUISE 17, WP_LOITER_RAD 60
    SITL = "sitl"
    #: the same aircraft with a tighter-tracking L1 navigation (NAVL1_PERIOD 8 instead of 15):
    #: the runtime plans 23.4 m turns instead of 43.9 m (``vehicle.planning_bank_deg``); flown
    #: on SITL with the same parameters (``benchmarks/sitl_vs_sim.py --aircraft tight``)
    SITL_TIGHT = "sitl-tight"
    PAPER = "paper"     # the plain kinematic model at 18.2 m/s TAS, 45 deg bank


#: the tour sorter's admissible arrival headings on Cover (sweeps): along either grid axis for
#: regions up to TOUR_GRID_MAX cells, else along the map's axis.  Measured (fig3c, universe 713,
#: 4-12 seeds): grid 38 % against 52 % at 10 cells, equal at 25 and 61 (28 %, 27.5 %), about a
#: point worse at 100 and 150 (the serpentine along the axis dominates large regions and
#: sideways arrivals only add path-following error there).
TOUR_HEADINGS = ArrivalHeadings.PARALLEL
TOUR_GRID_MAX = 25
SITL_SLOW_PARAMS = {"AIRSPEED_CRUISE": 17.0, "WP_LOITER_RAD": 60.0}
SITL_TIGHT_PARAMS = {**SITL_SLOW_PARAMS, "NAVL1_PERIOD": 8.0}


def sim_params(kind: VehicleKind):
    from iterplan_compiler.runtime.sim import SimParams

    if kind is VehicleKind.PAPER:
        return SimParams()
    return SimParams.from_arduplane(
        SITL_TIGHT_PARAMS if kind is VehicleKind.SITL_TIGHT else SITL_SLOW_PARAMS)


def arrival_for(sorter: SorterKind, experiment: Experiment = Experiment.FIG3C, count: int = 0):
    """The planner's heading options: the paper's for its three sorters; ``tour`` on Cover
    flies its planned order with the planned arrival headings (``LOOKAHEAD``: the tour is the
    whole mission there; grid headings for up to :data:`TOUR_GRID_MAX` cells).  On Ordered Patrol the plan cannot know the mission's order (it is
    in the controller), so a heading planned for the tour's next cell is a guess: measured at
    1,000 locations, 23 % loop overhead with it against 10 % with the shortest heading."""
    if sorter is SorterKind.TOUR and experiment is not Experiment.FIG3B:
        grid = 0 < count <= TOUR_GRID_MAX
        return ArrivalHeadings.GRID if grid else TOUR_HEADINGS, HeadingChoice.LOOKAHEAD
    return ArrivalHeadings.PARALLEL, HeadingChoice.SHORTEST


class Runner:
    """Picklable case runner for :func:`harness.run_cases` (imports lazily in the worker)."""

    def __init__(self, ctrl_dir: str, fast_skip: bool = False,
                 vehicle: VehicleKind = VehicleKind.SITL, arrival=None, warmup: int = 0):
        self.ctrl_dir = ctrl_dir
        self.fast_skip = fast_skip
        self.vehicle = vehicle
        #: (ArrivalHeadings, HeadingChoice) for every sorter, or None: :func:`arrival_for`
        self.arrival = arrival
        #: fig3b: patrol loops flown before the measured ones
        self.warmup = warmup

    def __call__(self, case: Case) -> dict:

        name = EXAMPLE_OF[case.experiment]
        module = Path(self.ctrl_dir) / f"{name}_controller.py"
        grid = build_grid(case)
        # Fast skip where the measurement allows it: the patrol loop time needs only the
        # visited.p.0 events; the cover time starts at the first has.next, a skipped event.
        from iterplan_compiler.runtime.planner import admissible_headings

        arrival = self.arrival or arrival_for(case.sorter, case.experiment, case.count)
        warmup = self.warmup if case.experiment is Experiment.FIG3B else 0
        res = flight.fly(module, grid, sorter=case.sorter, seed=case.seed,
                         stop=StopWhen(case, grid, warmup),
                         fast_skip=self.fast_skip and case.experiment is Experiment.FIG3B,
                         heading=layout(case).heading, params=sim_params(self.vehicle),
                         arrival=arrival)
        if not res.ok:
            raise MeasurementError(f"mission ended early: {res.reason}")
        out = measure(case, res.log, grid, res.speed, warmup)
        out["compute_s"] = float(res.summary.get("compute_s", 0.0) or 0.0)
        out["steps"] = int(res.summary.get("steps", 0) or 0)
        out["turn_radius"] = float(res.summary.get("turn_radius_m", 0.0) or 0.0)
        heads = admissible_headings(grid.arrival_heading, True, arrival[0])
        out["floor"] = kinematic_floor_s(case, res, grid, out["turn_radius"], heads)
        out["physics_pct"] = 100.0 * (out["floor"] - out["ideal"]) / out["ideal"]
        return out

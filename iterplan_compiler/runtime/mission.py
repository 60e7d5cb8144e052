"""Mission configuration and what bindings see: :class:`RunConfig` (the ``iterc run`` flags),
:class:`MissionContext` (iterator, planner, vehicle and map for the action bindings) and
:class:`MissionEnd` (how a mission stops).  Split from :mod:`.executor`, which re-exports them."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.planner import (
    ArrivalHeadings,
    HeadingChoice,
    MotionPlanner,
    PlannerMode,
)
from iterplan_compiler.runtime.shadow import Prediction, Shadow
from iterplan_compiler.runtime.sorter import Pose, SorterKind
from iterplan_compiler.runtime.vehicle import SafeAction, Start

if TYPE_CHECKING:
    from iterplan_compiler.runtime.executor import Executor


@dataclass
class RunConfig:
    """Mission options (CLI flags of ``iterc run`` map 1:1 onto these)."""

    sorter: SorterKind | str = SorterKind.DISTANCE
    #: admissible arrival headings and how the planner picks one (the "order" lever)
    headings: ArrivalHeadings = ArrivalHeadings.PARALLEL
    heading_choice: HeadingChoice = HeadingChoice.SHORTEST
    seed: int = 0
    ideal_compute: bool = False
    passes: int = 1                 # stop after this many complete iterator passes; 0 = never
    max_time: float = 4 * 3600.0    # mission seconds
    max_wall: float | None = None   # wall seconds (a frozen vehicle clock cannot hang a run)
    start: Start = Start.AUTO
    tick: float = 0.25              # physical time step while waiting (s)
    altitude: float | None = None   # default: the map's altitude
    turn_radius: float | None = None   # planning radius; default 1.4 x the vehicle's minimum
    #: expected wind speed (m/s): the default planning radius grows to what the aircraft can fly
    #: over ground downwind, 1.4 x r_min x ((V + wind) / V)^2
    wind: float = 0.0
    parallel: bool = True           # arrive parallel to the fixed direction (either way)
    planner_mode: PlannerMode = PlannerMode.COURSE
    lead: float | None = None
    accept: float | None = None
    end_action: SafeAction = SafeAction.LOITER   # commanded when the mission completes or
    fault_action: SafeAction = SafeAction.RTL    # is interrupted / when it ends on a fault
    log_limit: int = 200_000
    livelock_limit: int = 100_000   # steps without waiting or iterator progress
    progress: Callable[[str], None] | None = None
    progress_every: float = 300.0   # mission seconds between progress lines
    track_every: float = 1.0        # mission seconds between track points
    choose: Callable[[Sequence[str]], str] | None = None
    auto_takeoff: bool = True       # take off before starting when the controller has no takeoff
    #: clock for think time (wall by default; ``time.process_time`` makes charges independent
    #: of machine load when several missions share the CPUs)
    compute_clock: Callable[[], float] = time.perf_counter
    #: called for every controller event as ``on_event(kind, label)`` with kind "c"
    #: (controllable) or "u" (uncontrollable); returning True ends the mission successfully
    on_event: Callable[[str, str], bool | None] | None = None
    #: called after every physical tick as ``observe(executor, final=False)`` and once at the
    #: end with ``final=True`` (a live view takes snapshots here; keep it cheap)
    observe: Callable[[Executor, bool], None] | None = None
    #: pace a simulated vehicle at this many simulated seconds per wall second (None: as fast
    #: as possible)
    realtime: float | None = None
    #: run the controller's skip cycles for many locations at once (``runtime/skip.py``)
    fast_skip: bool = False
    #: the labels ``on_event`` needs to see (None: all, which rules out fast skips)
    on_event_labels: frozenset[str] | None = None


class TargetMemory:
    """Which ``go.next`` target followed which, the last time (``HeadingChoice.REPEAT``).  The
    plan's order is in the controller; the hybrid layer only learns it by watching, so nothing
    is expected before the mission has repeated a target."""

    def __init__(self) -> None:
        self._followed: dict[int, int] = {}
        self._previous: int | None = None

    def record(self, cell: int) -> None:
        """``cell`` is the new target."""
        if self._previous is not None:
            self._followed[self._previous] = cell
        self._previous = cell

    def expect(self, prediction: Prediction) -> None:
        """What a shadow run predicts (``HeadingChoice.PREDICT``): its targets follow its start
        in order (and the start follows them if the prediction closes a cycle).  Real targets
        recorded later overwrite it."""
        chain = [prediction.start, *prediction.targets]
        if prediction.closes:
            chain.append(prediction.start)
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            self._followed[a] = b

    def expected_after(self, cell: int, limit: int = 8) -> tuple[list[int], bool]:
        """The targets that followed ``cell`` the last time, then their successors, up to
        ``limit``; and whether that chain leads back to ``cell`` (a patrol cycle)."""
        chain: list[int] = []
        c = self._followed.get(cell)
        while c is not None and len(chain) < limit:
            if c == cell:
                return chain, True
            if c in chain:
                break
            chain.append(c)
            c = self._followed.get(c)
        return chain, False


class MissionContext:
    """What bindings can see and do (iterator, planner, vehicle, map, logging)."""

    def __init__(self, executor: Executor):
        self._ex = executor
        self.grid = executor.grid
        self.vehicle = executor.vehicle
        self.iterator: Iterator = executor.iterator
        self.planner: MotionPlanner = executor.planner
        self.altitude = executor.altitude
        self.target_cell: int | None = None
        self.last_arrival: int | None = None
        self.done: set[str] = set()
        self.targets = TargetMemory()
        self.shadow: Shadow | None = None    # built on the first prediction (PREDICT)
        self.predictions: list[Prediction] = []

    def predicted_pose(self) -> Pose:
        """Where the vehicle will be when the current leg ends: the arrival pose of the active
        target, or the current pose when idle (the Sorter's reference pose)."""
        if self.target_cell is not None and not self.planner.arrived:
            x, y = self.grid.centre(self.target_cell)
            return Pose(x, y, self.planner.heading)
        p = self.vehicle.pose()
        return Pose(p.x, p.y, p.course)

    def go(self, cell: int) -> None:
        self._ex.settle_compute()      # plan from where the aircraft is after thinking
        self.target_cell = int(cell)
        then, planned = None, None
        if self.planner.choice is HeadingChoice.LOOKAHEAD:
            planned = self.iterator.sorter.planned_heading(cell)
            if planned is None and self.iterator.remaining_count():
                then = self.grid.centre(int(self.iterator.peek_order(1)[0]))
        self.targets.record(int(cell))
        if self.planner.choice is HeadingChoice.PREDICT:
            self._predict(int(cell))
        chain, closes = (self.targets.expected_after(int(cell))
                         if self.planner.choice in (HeadingChoice.REPEAT, HeadingChoice.PREDICT)
                         else ([], False))
        arrival = self.planner.go(*self.grid.centre(cell), then=then, heading=planned,
                                  chain=[self.grid.centre(c) for c in chain], closes=closes)
        self._ex.counts["go"] += 1
        # Sorting happens while the aircraft flies the leg, from the predicted arrival pose.
        self.iterator.resort(arrival)

    def _predict(self, cell: int) -> None:
        """Unless the targets after ``cell`` are known to come round again, run the plan's
        shadow ahead (``runtime/shadow.py``) and remember what it predicts; its think time is
        flight time, charged before the leg is planned."""
        if self.targets.expected_after(cell)[1] or self._ex.cfg.choose is not None:
            return
        ex = self._ex
        if self.shadow is None:
            self.shadow = Shadow(ex.table, ex.bindings, ex.skip_sensors, self.arrival_pose)
        p = self.vehicle.pose()
        prediction = self.shadow.predict(ex.controller.state, self.iterator, cell,
                                         Pose(p.x, p.y, p.course))
        self.predictions.append(prediction)
        self.targets.expect(prediction)
        ex.log_entry("x", f"predicted {len(prediction.targets)} target(s) after "
                          f"{self.grid.cell_name(cell)} ({prediction.stop.value})")
        ex.settle_compute()

    def arrival_pose(self, pose: Pose, cell: int) -> Pose:
        """The arrival pose at ``cell`` flying from ``pose`` by the shortest admissible path
        (the shadow's model of a leg)."""
        x, y = self.grid.centre(cell)
        path = self.planner.path_to(pose, x, y, self.planner.admissible)
        return Pose(x, y, path.end_heading)

    def current_cell(self) -> int | None:
        """The cell the vehicle is at: the last arrival's cell (the plan only senses the current
        location after ``arrived``), else the cell under the vehicle."""
        if self.last_arrival is not None:
            return self.last_arrival
        p = self.vehicle.pose()
        c = self.grid.cell_at(p.x, p.y)
        return None if c < 0 else int(c)

    def record_photo(self) -> None:
        p = self.vehicle.pose()
        cell = self.current_cell()
        self._ex.photos.append((p.t - self._ex.t0, -1 if cell is None else cell, p.x, p.y))

    def note(self, text: str) -> None:
        self._ex.log_entry("x", text)

    def done_now(self, kind: str) -> None:
        """The durative action just started is already complete (e.g. ``takeoff`` while
        airborne): its answer follows at once instead of waiting for the vehicle event."""
        self.done.add(kind)


class MissionEnd(Exception):
    def __init__(self, ok: bool, reason: str):
        super().__init__(reason)
        self.ok = ok
        self.reason = reason

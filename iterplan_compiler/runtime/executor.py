"""Executor: runs a controller with action bindings against a vehicle.

Loop (one discrete step at a time):

1. a pending uncontrollable answer (``y.next``, ``yes.next.inP``, ``arrived``...) is fed to the
   controller; a refusal ends the mission safely;
2. otherwise the controller picks a controllable label (the first of
   ``Controller.enabled_controllable()`` unless a ``choose`` function is given); the controller
   takes it and its binding runs, possibly queueing answers or starting a durative action;
3. otherwise time passes: the vehicle advances by ``tick`` seconds, the motion planner follows its
   path, and vehicle/planner events become answers (``arrived``, ``takeoff.ended``...).

Time accounting: the aircraft keeps flying while the plan thinks.  The wall time spent in steps 1
and 2 (controller, iterator, sensors, Sorter) is measured, and — for simulated vehicles — the
simulation is advanced by it before the next physical tick and before planning a ``go.next``
(the aircraft holds its last command meanwhile), so a faster-than-real-time run still shows the
iteration overhead the paper measures.  ``ideal_compute=True`` turns this off (deterministic).

Start: :meth:`Vehicle.prepare` waits for the vehicle to be ready and says whether the mission
starts on the ground (arm, take off, unless the controller has its own ``takeoff``) or in the
air (``Vehicle.take_control``).

A mission ends when ``passes`` complete iterator passes have been answered (``n.next``), when
``on_event`` says so, at the time limit (mission time ``max_time`` or wall time ``max_wall``),
on an interrupt (``KeyboardInterrupt``: Ctrl-C, or SIGTERM as ``iterc run`` maps it), or early on
a fault: a vehicle fault (``vehicle.FAULTS``: link, telemetry or GPS lost, the pilot or a
failsafe changed the mode, disarmed, a refused command), a refused controller event, a
controller deadlock, a livelock (many steps that neither wait for the vehicle nor move the
iterator), a planner that cannot reach a cell, or a binding error.

Safe end: a completed or interrupted mission commands ``end_action``, a fault ``fault_action``
(:class:`~iterplan_compiler.runtime.vehicle.SafeAction`: loiter over the map centre, RTL, land,
or none) — unless the vehicle is *hands off* (the pilot or the autopilot's failsafe is in
charge: nothing is sent) or not flying.  Every event is logged with mission time and pose (up to
``log_limit`` entries; counters are always complete).
"""

from __future__ import annotations

__all__ = ["Executor", "LogEntry", "MissionContext", "MissionEnd", "MissionResult", "RunConfig",
           "ideal_distance", "load_controller"]  # RunConfig, MissionContext, MissionEnd: mission.py

import math
import time
from collections import deque

import numpy as np

from iterplan_compiler.runtime.bindings import (
    Binding,
    BindingError,
    BindingKind,
    Bindings,
    answers_of,
    canon,
    map_rule_bindings,
)
from iterplan_compiler.runtime.controller import (  # load_controller: re-exported
    Controller,
    ControllerTable,
    RefusedEvent,
    load_controller,
)
from iterplan_compiler.runtime.grid import GridMap
from iterplan_compiler.runtime.ideal import ideal_distance  # re-exported
from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.mission import MissionContext, MissionEnd, RunConfig
from iterplan_compiler.runtime.planner import MotionPlanner, PlannerEventKind, admissible_headings
from iterplan_compiler.runtime.results import LogEntry, MissionResult  # re-exported
from iterplan_compiler.runtime.skip import Cycle, fast_skip, static_sensors
from iterplan_compiler.runtime.sorter import Pose
from iterplan_compiler.runtime.sorters import make_sorter
from iterplan_compiler.runtime.summary import mission_summary
from iterplan_compiler.runtime.vehicle import (
    FAULTS,
    SafeAction,
    Start,
    Vehicle,
    VehicleError,
    planning_radius,
)

#: Bindings through which the controller observes or moves the Iterator.
ITERATOR_KINDS = frozenset({BindingKind.HAS_NEXT, BindingKind.REMOVE_NEXT, BindingKind.RESET,
                            BindingKind.GO_NEXT, BindingKind.SENSOR_NEXT, BindingKind.CUSTOM})


class Executor:
    """Runs ``table`` on ``vehicle`` over ``grid``; see the module docstring."""

    def __init__(self, table: ControllerTable, grid: GridMap, vehicle: Vehicle,
                 bindings: Bindings | None = None, config: RunConfig | None = None):
        self.table = table
        self.grid = grid
        self.vehicle = vehicle
        self.cfg = config or RunConfig()
        self.altitude = self.cfg.altitude if self.cfg.altitude is not None else grid.altitude
        self._setup_planning()
        # The map's dynamic/derived sensor rules get fresh state for every mission.
        self.bindings = map_rule_bindings(grid, bindings).resolve(
            table.controllable, table.uncontrollable, grid.sensors, grid.num_cells)
        self.alphabet = {canon(a): a for a in table.controllable | table.uncontrollable}
        self.no_next = {a for a in table.uncontrollable if canon(a) in ("n.next", "no.next")}
        self.controller = Controller(table)
        self.log: list[LogEntry] = []
        self.photos: list[tuple[float, int, float, float]] = []
        self.arrivals: list[tuple[float, int, float, float]] = []
        self.track: list[tuple[float, float, float, float]] = []
        self.counts = {"steps": 0, "controllable": 0, "uncontrollable": 0, "go": 0,
                       "arrived": 0, "passes": 0, "skipped": 0}
        self.skip_sensors = static_sensors(self.bindings)
        self._skip_cache: dict[int, dict[int, Cycle | None]] = {}
        self.compute_s = 0.0
        self._mark = self.cfg.compute_clock()   # start of the current think period
        self.t0 = vehicle.time
        self.start_pose: Pose | None = None   # where the mission proper began
        self._iterator_seen = False   # has the controller used the Iterator yet?
        self._waiting: dict[str, str] = {}    # vehicle/planner event kind -> answer label
        self._pending: deque[str] = deque()
        self._next_progress = 0.0
        self._steps_since_tick = 0
        self._pass_marks: list[int] = []     # len(arrivals) at the end of each pass
        self._last_track = -1e9
        self._wall_deadline: float | None = None
        self._started = False
        self._pace_mark = time.monotonic()
        self.safe_state = ""

    def _setup_planning(self) -> None:
        """Planner, Sorter and Iterator for the vehicle as it is now (built again once the
        vehicle is ready: a MAVLink vehicle knows its speed and turn limits only then)."""
        grid, vehicle = self.grid, self.vehicle
        radius = self.cfg.turn_radius or planning_radius(vehicle, self.cfg.wind)
        self.radius = radius
        self.planner = MotionPlanner(vehicle, radius=radius,
                                     arrival_heading=grid.arrival_heading,
                                     parallel=self.cfg.parallel, cell_size=grid.cell_size,
                                     lead=self.cfg.lead, accept=self.cfg.accept,
                                     mode=self.cfg.planner_mode, headings=self.cfg.headings,
                                     choice=self.cfg.heading_choice)
        interesting = np.zeros(grid.num_cells, dtype=bool)
        for ids in grid.sensors.values():
            interesting[ids] = True
        sorter = make_sorter(self.cfg.sorter, radius=radius,
                             arrival_heading=grid.arrival_heading, parallel=self.cfg.parallel,
                             interesting=interesting, seed=self.cfg.seed,
                             headings=admissible_headings(grid.arrival_heading,
                                                          self.cfg.parallel, self.cfg.headings),
                             spacing=grid.cell_size)
        xs, ys = grid.centres()
        p = vehicle.pose()
        self.iterator = Iterator(grid.cells, xs, ys, sorter, Pose(p.x, p.y, p.course))
        self.ctx = MissionContext(self)

    # -- bookkeeping ------------------------------------------------------------------------
    def log_entry(self, kind: str, label: str, cell: int = -1) -> None:
        if len(self.log) >= self.cfg.log_limit:
            return
        p = self.vehicle.pose()
        self.log.append(LogEntry(round(p.t - self.t0, 3), kind, label, self.controller.state,
                                 p.x, p.y, p.alt, cell))

    def settle_compute(self) -> None:
        """Charge the measured think time to the simulated clock (see module docstring).

        The aircraft and the motion planner run concurrently with the plan in reality, so the
        debt is flown in ``tick``-sized slices with the planner following its path; events
        raised meanwhile (``arrived``...) are queued like any other."""
        clock = self.cfg.compute_clock
        now = clock()
        debt = now - self._mark
        self._mark = now
        if debt <= 0:
            return
        self.compute_s += debt
        if self.cfg.ideal_compute or not self.vehicle.is_simulated:
            return
        while debt > 1e-12:
            dt = min(self.cfg.tick, debt)
            self._physical_tick(dt)
            debt -= dt
        self._mark = clock()  # the simulator's own run time is not plan time

    def _record_track(self, force: bool = False) -> None:
        p = self.vehicle.pose()
        if force or p.t - self._last_track >= self.cfg.track_every:
            self.track.append((p.t - self.t0, p.x, p.y, p.alt))
            self._last_track = p.t

    def _progress(self, force: bool = False) -> None:
        if self.cfg.progress is None:
            return
        t = self.vehicle.time - self.t0
        if force or t >= self._next_progress:
            it = self.iterator
            self.cfg.progress(
                f"[{t:7.0f} s] visited {self.counts['arrived']}, photos {len(self.photos)}, "
                f"iterator {it.num_done} done / {it.remaining_count()} remaining, "
                f"{self.counts['steps']} steps, compute {self.compute_s:.2f} s")
            self._next_progress = t + self.cfg.progress_every

    # -- main loop ----------------------------------------------------------------------------
    def _answer(self, labels) -> None:
        for a in answers_of(labels):
            label = a if a in self.table.uncontrollable else self.alphabet.get(canon(a))
            if label is None or label not in self.table.uncontrollable:
                raise MissionEnd(False, f"binding answered {a!r}, which is not an uncontrollable "
                                        f"label of the controller")
            self._pending.append(label)

    def _take_off(self) -> None:
        v = self.vehicle
        v.arm()
        v.takeoff(self.altitude)
        deadline = v.time + 600.0
        while v.time < deadline:
            v.advance(self.cfg.tick)
            self._record_track()
            self._check_wall()
            for e in v.poll_events():
                self.log_entry("v", f"{e.kind} {e.detail}".strip())
                if e.kind == "takeoff_complete":
                    return
                if e.kind in FAULTS:
                    raise MissionEnd(False, f"take-off failed: {e.kind}: {e.detail}")
        raise MissionEnd(False, "take-off did not complete within 600 s")

    def _pace(self, dt: float) -> None:
        """Sleep so that simulated time runs ``realtime`` times faster than wall time."""
        assert self.cfg.realtime
        now = time.monotonic()
        due = self._pace_mark + dt / self.cfg.realtime
        if due > now:
            clock = self.cfg.compute_clock
            before = clock()
            time.sleep(due - now)
            self._mark += clock() - before   # sleeping is not think time (on any clock)
        self._pace_mark = max(due, now - 1.0)  # never "catch up" more than a second

    def _check_wall(self) -> None:
        if self._wall_deadline is not None and time.monotonic() > self._wall_deadline:
            raise MissionEnd(False, f"wall-clock limit of {self.cfg.max_wall:.0f} s reached")

    def _fast_skip(self) -> bool:
        """Skip the run of upcoming locations whose cycle from the current state is a pure skip
        (``runtime/skip.py``); True if any was skipped."""
        total = fast_skip(self.iterator, self.controller.state,
                          self._skip_cache.setdefault(self.controller.state, {}),
                          self.skip_sensors, self.table, self.bindings,
                          self.cfg.on_event_labels or frozenset(), self.counts)
        if total:
            self.log_entry("x", f"fast skip: {total} locations")
        return total > 0

    def _physical_tick(self, dt: float) -> None:
        self.vehicle.advance(dt)
        if self.cfg.realtime and self.vehicle.is_simulated:
            self._pace(dt)
        self._record_track()
        if self.cfg.observe is not None:
            self.cfg.observe(self, False)
        for pe in self.planner.update():
            self.log_entry("p", f"{pe.kind.value} {pe.detail}",
                           -1 if self.ctx.target_cell is None else self.ctx.target_cell)
            if pe.kind is PlannerEventKind.ARRIVED:
                cell = self.ctx.target_cell
                self.ctx.last_arrival = cell
                self.counts["arrived"] += 1
                p = self.vehicle.pose()
                self.arrivals.append((p.t - self.t0, -1 if cell is None else cell, p.x, p.y))
                if "arrived" in self._waiting:
                    self._pending.append(self._waiting.pop("arrived"))
            elif pe.kind is PlannerEventKind.STUCK:
                raise MissionEnd(False, f"motion planner cannot reach cell "
                                        f"{self.grid.cell_name(self.ctx.target_cell or 0)} "
                                        f"({pe.detail})")
        for e in self.vehicle.poll_events():
            self.log_entry("v", f"{e.kind} {e.detail}".strip())
            if e.kind in FAULTS:
                raise MissionEnd(False, f"{e.kind}: {e.detail}")
            if e.kind == "takeoff_complete" and not self._iterator_seen:
                # The controller's own take-off: nothing of the Iterator has been observed
                # yet, so order it from where the mission really starts (not the launch pad)
                p = self.vehicle.pose()
                self.iterator.reset(Pose(p.x, p.y, p.course))
            if e.kind in self._waiting:
                self._pending.append(self._waiting.pop(e.kind))

    def run(self) -> MissionResult:
        ok, reason, interrupted = True, "completed", False
        v = self.vehicle
        if self.cfg.max_wall is not None:
            self._wall_deadline = time.monotonic() + self.cfg.max_wall
        try:
            try:
                start = v.prepare(self.cfg.start)
                self._setup_planning()
                self.log_entry("x", f"start {start.value}, planning radius {self.radius:.0f} m")
                has_takeoff = any(b.kind is BindingKind.TAKEOFF for b in self.bindings.values())
                if start is Start.AIRBORNE:
                    v.take_control()
                elif self.cfg.auto_takeoff and not has_takeoff:
                    self._take_off()
                if start is Start.AIRBORNE or (self.cfg.auto_takeoff and not has_takeoff):
                    p = v.pose()
                    self.iterator.reset(Pose(p.x, p.y, p.course))
                    # Fly on straight until the first go.
                    self.planner.go(p.x + 2000 * math.cos(p.course),
                                    p.y + 2000 * math.sin(p.course))
                    self.planner.arrived = True
                self.t0 = v.time
                p = v.pose()
                self.start_pose = Pose(p.x, p.y, p.course)
                self._started = True
                self._loop()
            except KeyboardInterrupt:
                ok, reason, interrupted = False, "interrupted", True
        except MissionEnd as end:
            ok, reason = end.ok, end.reason
        except (BindingError, VehicleError) as exc:
            ok, reason = False, f"{'binding error: ' if isinstance(exc, BindingError) else ''}{exc}"
        if not ok:
            self.log_entry("x", f"safe end: {reason}")
        self.safe_state = self._safe_end(self.cfg.end_action if ok or interrupted
                                         else self.cfg.fault_action)
        self._record_track(force=True)
        self._progress(force=True)
        self.summary = self._summary(ok, reason)
        self.ok, self.reason = ok, reason
        if self.cfg.observe is not None:
            self.cfg.observe(self, True)
        return MissionResult(ok, reason, self.summary, self.log,
                             np.asarray(self.track, dtype=np.float64).reshape(-1, 4),
                             self.photos, self.arrivals, self.grid, dict(self.counts))

    def _safe_end(self, action: SafeAction) -> str:
        """Command ``action`` (see the module docstring); returns what the log and the summary
        say about the state the vehicle was left in."""
        v = self.vehicle
        if v.hands_off:
            status = "no command: " + v.settle(0.0)
        elif not v.flying:
            status = "no command: the vehicle is not flying"
            if getattr(v, "armed", False):
                try:
                    v.disarm()
                    status = "disarmed on the ground" if not getattr(v, "armed", False) else \
                        "on the ground, still armed: disarm refused"
                except (VehicleError, KeyboardInterrupt) as exc:
                    status = f"on the ground, still armed: {exc}"
        elif action is SafeAction.NONE:
            status = "no command (--on-end/--on-fault none): the last command stays in force"
        else:
            self.planner.stop()      # stop steering, so the safe command sticks
            try:
                if action is SafeAction.LOITER:
                    cx, cy = self.grid.centre_point()
                    v.loiter(cx, cy, v.loiter_radius)
                elif action is SafeAction.RTL:
                    v.rtl()
                else:
                    v.land()
                status = f"{action.value} commanded; " + v.settle(3.0)
            except (VehicleError, KeyboardInterrupt) as exc:
                status = f"{action.value} failed: {exc}"
        self.log_entry("x", f"safe state: {status}")
        if self.cfg.progress:
            self.cfg.progress(f"safe state: {status}")
        return status

    def _loop(self) -> None:
        # Hot loop (millions of steps per pass on big maps): locals, no per-step clock reads.
        ctrl = self.controller
        v = self.vehicle
        cfg = self.cfg
        counts = self.counts
        pending = self._pending
        perf = cfg.compute_clock
        on_event = cfg.on_event
        limit = cfg.livelock_limit
        uncontrollable = self.table.uncontrollable
        no_next = self.no_next
        bindings = self.bindings
        ctx = self.ctx
        log = self.log
        log_limit = cfg.log_limit
        choices = self._choices()
        progress_kinds = (BindingKind.REMOVE_NEXT, BindingKind.RESET, BindingKind.GO_NEXT)
        skipping = self._skipping()
        since = 0           # steps since the last wait or iterator progress (livelock guard)
        n = 0
        self._mark = perf()
        while True:
            n += 1
            if not n & 511:
                if perf() - self._mark > cfg.tick:
                    self.settle_compute()
                    self._progress()
                if v.time - self.t0 > cfg.max_time:
                    raise MissionEnd(False, f"time limit of {cfg.max_time:.0f} s reached")
                self._check_wall()
            if pending:
                label = pending.popleft()
                try:
                    ctrl.step(label)
                except RefusedEvent as exc:
                    raise MissionEnd(False, f"unexpected event: {exc}") from None
                counts["steps"] += 1
                counts["uncontrollable"] += 1
                if len(log) < log_limit:
                    self.log_entry("u", label)
                if on_event is not None and on_event("u", label):
                    raise MissionEnd(True, f"stopped by on_event at {label}")
                if label in no_next and self._pass_done():
                    return
                continue
            if skipping and self._fast_skip():
                since = 0
                continue
            enabled = choices[ctrl.state]
            if enabled:
                label = cfg.choose(enabled) if cfg.choose else enabled[0]
                ctrl.step(label)
                b: Binding = bindings[label]
                if not self._iterator_seen and b.kind in ITERATOR_KINDS:
                    self._iterator_seen = True
                if len(log) < log_limit:
                    self.log_entry("c", label)
                if on_event is not None and on_event("c", label):
                    raise MissionEnd(True, f"stopped by on_event at {label}")
                out = b.handler(ctx, label)
                if out is not None:
                    if out.__class__ is str and out in uncontrollable:
                        pending.append(out)
                    else:
                        self._answer(out)
                if b.completes_on and b.answer:
                    self._await(b)
                counts["steps"] += 1
                counts["controllable"] += 1
                if b.kind in progress_kinds:
                    since = 0
                else:
                    since += 1
                    if since > limit:
                        raise MissionEnd(False, f"livelock: {limit} controller steps without "
                                                "waiting for the vehicle or moving the iterator")
                continue
            self._wait_tick()
            since = 0

    def _choices(self) -> dict[int, list[str]]:  # controllable labels per state, as tried
        ctl = self.table.controllable
        return {s: sorted(a for a in m if a in ctl) for s, m in self.table.delta.items()}

    def _skipping(self) -> bool:
        """Whether the fast skip may run (configured, no chooser, static next-sensors, and an
        ``on_event`` hook, if any, that says which labels it needs)."""
        cfg = self.cfg
        return cfg.fast_skip and cfg.choose is None and bool(self.skip_sensors.labels) \
            and (cfg.on_event is None or cfg.on_event_labels is not None)

    def _pass_done(self) -> bool:
        """An iterator pass was answered (``n.next``); True when the mission is complete."""
        self.counts["passes"] += 1
        self._pass_marks.append(len(self.arrivals))
        if self.cfg.passes and self.counts["passes"] >= self.cfg.passes:
            self.settle_compute()
            return True
        return False

    def _await(self, b: Binding) -> None:
        """A durative action started: its answer comes with the vehicle/planner event
        ``b.completes_on``, or at once if that already happened (airborne start)."""
        assert b.completes_on and b.answer
        if b.completes_on in self.ctx.done:
            self.ctx.done.discard(b.completes_on)
            self._pending.append(b.answer)
        else:
            self._waiting[b.completes_on] = b.answer

    def _wait_tick(self) -> None:
        """Nothing to decide: let time pass one ``tick`` (after the deadlock, time and wall
        checks), with the think time charged first."""
        ctrl, cfg = self.controller, self.cfg
        if not ctrl.enabled():
            raise MissionEnd(False, f"controller deadlocked in state {ctrl.state}")
        if not self._waiting:
            exp = ", ".join(sorted(ctrl.enabled() & self.table.uncontrollable))
            raise MissionEnd(False, f"controller waits for {exp}, which nothing will produce")
        if self.vehicle.time - self.t0 > cfg.max_time:
            raise MissionEnd(False, f"time limit of {cfg.max_time:.0f} s reached")
        self._check_wall()
        self.settle_compute()
        self._physical_tick(cfg.tick)
        self._mark = cfg.compute_clock()
        self._progress()

    def _summary(self, ok: bool, reason: str) -> dict:
        return mission_summary(self, ok, reason)

"""Fly a generated controller module on the built-in simulator and return its event log.

The thin adapter between the experiments/demo and the runtime's executor
(:mod:`iterplan_compiler.runtime.executor`): it adds

* a *stop predicate* over executed events (the executor itself stops after ``passes`` iterator
  passes or a time limit; experiments need "after the 3rd visit of p.0" or "once the region is
  covered"), and a compact log of the events the measurements need, so a 700,000-location
  mission does not keep millions of log entries.

The bundled maps' sensor rules (a Nemo that leaves after being seen ``yes_answers`` times,
``"dynamic"`` in find_nemo.json; the shared data structure of Search and Map, ``"derived"`` in
search_and_map.json) are implemented by the runtime itself (``grid.load_map`` reads them,
``bindings.map_rule_bindings`` serves them), exactly as ``iterc run`` flies them.

The stop predicate goes through the executor's ``RunConfig.on_event`` hook.  Compute-time
accounting stays on (``ideal_compute=False``): time the plan spends iterating is flight time, as
in the paper; it is measured as CPU time of the mission's process (``compute_clock=time.process_time``), so a
busy machine or parallel missions do not inflate it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from iterplan_compiler.experiments.pipeline import StageError

if TYPE_CHECKING:
    from iterplan_compiler.runtime.sorter import SorterKind


@dataclass(frozen=True)
class LogEvent:
    """One executed event: simulation time (s), label, current cell (-1 if none), pose."""

    t: float
    label: str
    cell: int = -1
    x: float = math.nan
    y: float = math.nan


#: Labels kept in the compact log (everything else only goes through the stop predicate).
KEEP = frozenset({"has.next", "n.next", "go.next", "arrived", "take.photo", "store.target",
                  "yes.fire", "yes.nemo", "yes.target", "takeoff.ended", "land", "landed",
                  "restart", "visited.p.0", "visited.p.1", "visited.p.2", "visited.p.3",
                  "visited.p.4", "visited.p.5", "y.next"})


@dataclass
class FlightResult:
    """Events executed (in order; all of them if ``full_log``, else :data:`KEEP` ones), the
    cruise speed used for "ideal" durations, the flown track as (t, x, y) samples, the
    executor's summary, and why the flight ended."""

    log: list[LogEvent]
    speed: float
    track: list[tuple[float, float, float]] = field(default_factory=list)
    summary: dict = field(default_factory=dict)
    ok: bool = True
    reason: str = ""
    mission: object = None   # the runtime's MissionResult (PNG/GeoJSON writers)


def example_bindings(grid, data: dict | None):
    """Runtime bindings for the ``dynamic`` / ``derived`` sensor rules in map data ``data``
    (default: the rules :func:`~iterplan_compiler.runtime.grid.load_map` put on ``grid``).

    A thin wrapper: the rules are implemented once, in the runtime
    (:func:`iterplan_compiler.runtime.bindings.map_rule_bindings`), so ``iterc run`` and the
    experiments fly the same thing.  Raises :class:`StageError` for malformed rules."""
    from iterplan_compiler.runtime.bindings import map_rule_bindings
    from iterplan_compiler.runtime.grid import MapError
    from iterplan_compiler.runtime.mapfile import parse_sensor_rules

    if data is None:
        return map_rule_bindings(grid)
    try:
        dynamic, derived = parse_sensor_rules(data, grid.sensors)
    except MapError as exc:
        raise StageError("map", str(exc)) from None
    return map_rule_bindings(grid, dynamic=dynamic, derived=derived)


def fly(module_path: Path, grid, *, sorter: SorterKind | str = "distance", seed: int = 0,
        stop: Callable[[LogEvent], bool] | None = None, max_time: float = 6 * 3600.0,
        compute_time: bool = True, on_event: Callable[[LogEvent], None] | None = None,
        map_data: dict | None = None, full_log: bool = False,
        fast_skip: bool = False, observe: Callable | None = None,
        realtime: float | None = None, heading: float | None = None,
        params: object | None = None, arrival: tuple[object, object] | None = None
        ) -> FlightResult:
    """Run the controller in ``module_path`` over ``grid`` until ``stop(event)`` is true (or
    ``max_time`` simulated seconds) with the ``sorter`` strategy (a :class:`SorterKind`, or
    its value).  ``fast_skip``: the executor's fast skip
    (``runtime/skip.py``), with ``has.next``/``y.next`` left out of the compact log so that
    skip cycles can be skipped.  ``observe``/``realtime`` go to the executor's RunConfig
    (the live view, ``iterc demo --view``).  ``heading``: the launch heading (default the
    map's arrival heading); ``params``: the simulator's :class:`SimParams` (default the
    paper's UAV); ``arrival``: (``ArrivalHeadings``, ``HeadingChoice``) for the planner.  Raises :class:`StageError` if the runtime is
    missing or the module cannot be loaded."""
    try:
        from iterplan_compiler.runtime.executor import Executor, RunConfig, load_controller
        from iterplan_compiler.runtime.sim import SimVehicle
        from iterplan_compiler.runtime.vehicle import SafeAction
    except ImportError as exc:
        raise StageError("runtime", f"the executor is not available in this build ({exc})") \
            from None
    try:
        table = load_controller(module_path)
    except ValueError as exc:
        raise StageError("runtime", str(exc)) from None

    events: list[LogEvent] = []
    keep = None if full_log else (KEEP - {"has.next", "y.next"} if fast_skip else KEEP)
    holder: dict = {}

    def on_controller_event(kind: str, label: str) -> bool:
        """Compact log + stop predicate; ``True`` ends the mission (successfully)."""
        if keep is not None and label not in keep:
            return False
        ex = holder["ex"]
        cell = -1
        if label == "arrived":
            cell = ex.ctx.last_arrival if ex.ctx.last_arrival is not None else -1
        elif label in ("take.photo", "store.target") or label.startswith("visited."):
            c = ex.ctx.current_cell()
            cell = -1 if c is None else c
        elif label == "go.next":
            n = ex.iterator.next
            cell = -1 if n is None else n
        p = ex.vehicle.pose()
        ev = LogEvent(round(p.t - ex.t0, 3), label, int(cell), p.x, p.y)
        events.append(ev)
        if on_event is not None:
            on_event(ev)
        return bool(stop is not None and stop(ev))

    vehicle = SimVehicle(params, home=grid.home,  # type: ignore[arg-type]
                         heading=grid.arrival_heading if heading is None else heading)
    # compute_clock: charge CPU time of this process, not wall time, so the think-time charge
    # does not depend on how busy the machine is (sweeps run missions in parallel processes).
    cfg = RunConfig(sorter=sorter, seed=seed, ideal_compute=not compute_time, passes=0,
                    max_time=max_time, log_limit=0, end_action=SafeAction.LOITER,
                    fault_action=SafeAction.LOITER,
                    compute_clock=time.process_time, on_event=on_controller_event,
                    fast_skip=fast_skip,
                    on_event_labels=(KEEP - {"has.next", "y.next"}) if fast_skip and not full_log
                    else None,
                    observe=observe, realtime=realtime)
    if arrival is not None:
        cfg.headings, cfg.heading_choice = arrival  # type: ignore[assignment]
    try:
        # map_data=None: the rules load_map put on the grid (the executor applies them itself).
        bindings = None if map_data is None else example_bindings(grid, map_data)
        ex = Executor(table, grid, vehicle, bindings, cfg)
    except ValueError as exc:   # BindingError is a ValueError: the map lacks a sensor
        raise StageError("runtime", str(exc)) from None
    holder["ex"] = ex
    result = ex.run()
    track = [(float(t), float(x), float(y)) for t, x, y, _ in result.track]
    return FlightResult(events, float(vehicle.airspeed), track, dict(result.summary),
                        bool(result.ok), str(result.reason), result)

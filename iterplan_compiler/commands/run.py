"""``iterc run CONTROLLER.py --map MAP``: fly a generated controller.

The controller module is what ``iterc compile`` writes (a module-level ``TABLE``); the map is a
JSON file (see ``docs/runtime.md``).  The default vehicle is the built-in simulator; ``--vehicle
mavlink --connect tcp:127.0.0.1:5760`` flies an ArduPlane (ArduPilot SITL or a real one).

Outputs go to ``--out`` (default ``./run-out``, checked before take-off): ``track.csv``,
``track.geojson``, ``events.csv``, ``summary.json``, ``track.png`` and, on MAVLink,
``commands.csv`` (every command sent).  They are written however the run ends — completed, a
fault, Ctrl-C or SIGTERM — after the safe state (``--on-end`` / ``--on-fault``) was commanded.
Exit code 0 when the mission completed, 1 when it ended early (safely) or the input was bad,
2 for usage errors.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from iterplan_compiler.runtime.runfiles import positive_float, sigterm_as_interrupt
from iterplan_compiler.runtime.vehicle import SafeAction, Start, VehicleBackend

if TYPE_CHECKING:
    from iterplan_compiler.runtime.controller import ControllerTable
    from iterplan_compiler.runtime.executor import Executor, RunConfig
    from iterplan_compiler.runtime.grid import GridMap
    from iterplan_compiler.runtime.planner import PlannerMode

HELP = "run a generated controller on the simulator or a MAVLink vehicle"

SAFE_ACTIONS = tuple(a.value for a in SafeAction)


def add_arrival_arguments(parser: argparse.ArgumentParser, *, paper_default: bool) -> None:
    """``--headings`` and ``--heading-choice`` (the planner's arrival rule, values of the
    ``ArrivalHeadings`` / ``HeadingChoice`` enums).  ``paper_default``: default to the paper's
    rule; else None, for callers with their own defaults (``iterc experiment``)."""
    from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice

    parser.add_argument("--headings", choices=[h.value for h in ArrivalHeadings],
                        default=ArrivalHeadings.PARALLEL.value if paper_default else None,
                        help="admissible arrival headings: parallel to the map's direction "
                             "(the paper's), or along either grid axis")
    parser.add_argument("--heading-choice", choices=[c.value for c in HeadingChoice],
                        default=HeadingChoice.SHORTEST.value if paper_default else None,
                        help="arrival heading per leg: the shortest path (the paper's), the "
                             "one that also shortens the next leg (the tour's planned heading "
                             "with --sorter tour), repeat: the one that also shortens the "
                             "legs that followed this location the last time (patrols), or "
                             "predict: repeat, with the targets a shadow run of the plan "
                             "predicts before anything repeats")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    _add_mission_arguments(parser)
    _add_flight_arguments(parser)
    _add_output_arguments(parser)
    # -- live view (issue 16): --view, --realtime, --view-linger ---------------------------
    from iterplan_compiler.view.cli import add_view_arguments
    add_view_arguments(parser)


def _add_mission_arguments(parser: argparse.ArgumentParser) -> None:
    """The controller, map, vehicle and how the mission is ordered and ended."""
    from iterplan_compiler.runtime.sorter import SorterKind

    parser.add_argument("controller", metavar="CONTROLLER.py",
                        help="controller module (from `iterc compile`)")
    parser.add_argument("--map", required=True, help="map file (JSON)")
    parser.add_argument("--vehicle", choices=[v.value for v in VehicleBackend],
                        default=VehicleBackend.SIM.value)
    parser.add_argument("--connect", default="tcp:127.0.0.1:5760",
                        help="MAVLink connection string (with --vehicle mavlink)")
    parser.add_argument("--start", choices=[s.value for s in Start], default=Start.AUTO.value,
                        help="take off from the ground, take over a flying vehicle, or pick by "
                             "what the vehicle reports (default)")
    parser.add_argument("--sorter", choices=[k.value for k in SorterKind],
                        default=SorterKind.DISTANCE.value,
                        help="order of the locations: the paper's distance (greedy Dubins), "
                             "last, random; or tour (a planned tour over the cells the map's "
                             "sensors mark, docs/runtime.md)")
    add_arrival_arguments(parser, paper_default=True)
    parser.add_argument("--seed", type=int, default=0, help="seed for the random sorter and sim")
    parser.add_argument("--ideal-compute", action="store_true",
                        help="do not charge planning compute time to the simulated clock")
    parser.add_argument("--passes", type=int, default=None,
                        help="stop after this many complete iterator passes (0: no limit; "
                             "default 1, or 0 with --until)")
    parser.add_argument("--until", default=None, metavar="LABEL[:K]",
                        help="end the mission (successfully) when the controller's event LABEL "
                             "occurs for the K-th time (default K=1), e.g. `--until restart` "
                             "or `--until n.next:2`; a controllable LABEL ends it before the "
                             "action runs")
    parser.add_argument("--fast-skip", action="store_true",
                        help="run the controller's skip cycles (has.next ... remove.next over "
                             "static next-location sensors) for many locations at once; the "
                             "events and everything the controller observes stay the same")
    parser.add_argument("--max-time", type=positive_float, default=4 * 3600.0, metavar="S",
                        help="end the run after S seconds of mission time or of wall time, "
                             "whichever comes first (default 4 h)")


def _add_flight_arguments(parser: argparse.ArgumentParser) -> None:
    """Path following, the airframe's figures and the simulator's calibration."""
    from iterplan_compiler.runtime.planner import PlannerMode

    parser.add_argument("--planner", choices=[m.value for m in PlannerMode], default=None,
                        help="path following: course hold or fly-to carrots "
                             "(default: course on sim, carrot on mavlink)")
    parser.add_argument("--airspeed", type=positive_float, default=None, metavar="M/S",
                        help="cruise airspeed: the simulator's; on MAVLink commanded with "
                             "DO_CHANGE_SPEED (default: the vehicle's AIRSPEED_CRUISE)")
    parser.add_argument("--turn-radius", type=positive_float, default=None, metavar="M",
                        help="planning turn radius of the motion planner and the Sorter "
                             "(default: 1.4 x the turn at 45 deg bank at cruise speed)")
    parser.add_argument("--loiter-radius", type=positive_float, default=None, metavar="M",
                        help="radius of loiter circles, e.g. the end-of-mission loiter "
                             "(default: the vehicle's WP_LOITER_RAD; 80 on the simulator)")
    parser.add_argument("--altitude", type=positive_float, default=None, metavar="M",
                        help="flight altitude above home (default: the map's)")
    parser.add_argument("--param", action="append", default=[], metavar="FILE",
                        help="ArduPilot parameter file(s) for the simulator: calibrate it to "
                             "ArduPlane SITL with these parameters (AIRSPEED_CRUISE, "
                             "ROLL_LIMIT_DEG, WP_LOITER_RAD, ...)")


def _add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """Safe states, readiness, wind and the output files."""
    parser.add_argument("--on-end", choices=SAFE_ACTIONS, default=SafeAction.LOITER.value,
                        help="what to command when the mission completes or is interrupted "
                             "(Ctrl-C, SIGTERM): loiter over the map centre (default), rtl, "
                             "land, none")
    parser.add_argument("--on-fault", choices=SAFE_ACTIONS, default=SafeAction.RTL.value,
                        help="what to command when the mission ends on a fault (GPS or "
                             "telemetry lost, a refused command, controller or planner error, "
                             "time limit); default rtl.  After a pilot/failsafe mode change, a "
                             "disarm or link loss nothing is commanded")
    parser.add_argument("--ready-timeout", type=positive_float, default=180.0, metavar="S",
                        help="MAVLink: wall seconds to wait for GPS fix, home and pre-arm checks")
    parser.add_argument("--wind", default=None, metavar="E,N",
                        help="sim wind vector east,north in m/s")
    parser.add_argument("--wind-margin", type=float, default=None, metavar="M/S",
                        help="expected wind speed for path planning (default: the --wind "
                             "speed on the simulator, 0 otherwise)")
    parser.add_argument("--out", default="run-out", help="output directory")
    parser.add_argument("--no-plot", action="store_true", help="skip the PNG plot")
    parser.add_argument("--quiet", action="store_true", help="no progress output")


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler.runtime.bindings import BindingError
    from iterplan_compiler.runtime.executor import Executor
    from iterplan_compiler.runtime.runfiles import check_out, write_outputs
    from iterplan_compiler.runtime.vehicle import VehicleError

    options = _options(args)
    if isinstance(options, str):
        return _usage(options)
    until, passes, wind = options
    inputs = _load_inputs(args, until)
    if isinstance(inputs, int):
        return inputs
    table, grid, params = inputs
    out = Path(args.out)
    problem = check_out(out, [Path(args.controller), Path(args.map), *map(Path, args.param)])
    if problem:
        return _err(problem)
    progress = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    # -- live view (issue 16) ---------------------------------------------------------------
    from iterplan_compiler.view import cli as view_cli
    from iterplan_compiler.view.live import ViewError
    try:
        view = view_cli.start(args, grid, title=Path(args.controller).stem)
    except ViewError as exc:
        return _err(str(exc))
    result = None
    # ----------------------------------------------------------------------------------------

    altitude = args.altitude if args.altitude is not None else grid.altitude
    wind_margin = args.wind_margin if args.wind_margin is not None else math.hypot(*wind)
    vehicle: Any = None
    with sigterm_as_interrupt():
        try:
            vehicle, mode = _vehicle(args, grid, params, wind, altitude, progress)
            cfg = _run_config(args, table, until, passes, mode=mode, wind_margin=wind_margin,
                              altitude=altitude, progress=progress,
                              observe=view.observe if view else None)  # live view (issue 16)
            result = Executor(table, grid, vehicle, config=cfg).run()
        except KeyboardInterrupt:
            return _err("interrupted before the mission started; nothing was commanded")
        except (VehicleError, BindingError) as exc:
            return _err(str(exc))
        finally:
            if vehicle is not None:
                vehicle.close()
            if view is not None and result is None:    # live view (issue 16): no mission
                view.close()
        write_outputs(result, out, vehicle, plot=not args.no_plot)
    _print_summary(result, out)
    view_cli.finish(view, args, interrupted=result.reason == "interrupted")  # issue 16
    return 0 if result.ok else 1


def _load_inputs(args: argparse.Namespace, until: tuple[str, int] | None
                 ) -> tuple[ControllerTable, GridMap, dict[str, float]] | int:
    """``(table, grid, params)`` from the controller, map and parameter files, or the exit
    code of the error (already reported)."""
    from iterplan_compiler.runtime.bindings import canon
    from iterplan_compiler.runtime.executor import load_controller
    from iterplan_compiler.runtime.grid import MapError
    from iterplan_compiler.runtime.mapfile import load_map
    from iterplan_compiler.runtime.parm import ParmError, read_parm

    try:
        table = load_controller(args.controller)
    except ValueError as exc:
        return _err(str(exc))
    try:
        grid = load_map(args.map)
    except MapError as exc:
        msg = str(exc)
        return _err(msg if msg.startswith(str(args.map)) else f"{args.map}: {msg}")
    if until is not None:
        labels = {canon(a) for a in table.controllable | table.uncontrollable}
        if until[0] not in labels:
            return _usage(f"--until {until[0]}: the controller has no event of that name")
    try:
        params = read_parm(args.param)
    except ParmError as exc:
        return _err(str(exc))
    return table, grid, params


def _run_config(args: argparse.Namespace, table: ControllerTable,
                until: tuple[str, int] | None, passes: int, *, mode: PlannerMode,
                wind_margin: float,
                altitude: float, progress: Callable[[str], None] | None,
                observe: Callable[[Executor, bool], None] | None) -> RunConfig:
    """The executor's :class:`RunConfig` from the flags and what :func:`run` resolved."""
    from iterplan_compiler.runtime.bindings import canon
    from iterplan_compiler.runtime.executor import RunConfig
    from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice
    from iterplan_compiler.runtime.runfiles import until_hook
    from iterplan_compiler.runtime.sorter import SorterKind
    from iterplan_compiler.view import cli as view_cli

    return RunConfig(sorter=SorterKind(args.sorter),
                     headings=ArrivalHeadings(args.headings),
                     heading_choice=HeadingChoice(args.heading_choice),
                     seed=args.seed, ideal_compute=args.ideal_compute,
                     passes=passes, max_time=args.max_time, max_wall=args.max_time,
                     planner_mode=mode, wind=wind_margin, altitude=altitude,
                     turn_radius=args.turn_radius, start=Start(args.start),
                     end_action=SafeAction(args.on_end),
                     fault_action=SafeAction(args.on_fault),
                     progress=progress, progress_every=60.0,
                     on_event=until_hook(*until) if until else None,
                     fast_skip=args.fast_skip,
                     on_event_labels=frozenset(
                         a for a in table.controllable | table.uncontrollable
                         if until and canon(a) == until[0]),
                     observe=observe,
                     realtime=view_cli.realtime(args))


def _err(msg: str) -> int:
    print(f"iterc run: error: {msg}", file=sys.stderr)
    return 1


def _usage(msg: str) -> int:
    print(f"iterc run: {msg}", file=sys.stderr)
    return 2


def _options(args: argparse.Namespace
             ) -> tuple[tuple[str, int] | None, int, tuple[float, float]] | str:
    """``(until, passes, wind)`` from the flags, or the usage error."""
    from iterplan_compiler.runtime.runfiles import parse_until

    until = None
    if args.until is not None:
        until = parse_until(args.until)
        if until is None:
            return f"--until expects LABEL or LABEL:K (K >= 1), not {args.until!r}"
    passes = args.passes if args.passes is not None else (0 if until else 1)
    if passes < 0:
        return "--passes must be >= 0"
    wind = (0.0, 0.0)
    if args.wind:
        try:
            values = tuple(float(v) for v in args.wind.split(","))
            if len(values) != 2 or not all(math.isfinite(w) for w in values):
                raise ValueError
            wind = (values[0], values[1])
        except ValueError:
            return "--wind expects E,N (m/s)"
    if VehicleBackend(args.vehicle) is VehicleBackend.MAVLINK and (args.param or args.wind):
        return ("--param and --wind configure the simulator; set a real vehicle's "
                "parameters with your ground station")
    return until, passes, wind


def _vehicle(args: argparse.Namespace, grid: Any, params: dict[str, float],
             wind: tuple[float, float], altitude: float, progress: Any
             ) -> tuple[Any, PlannerMode]:
    """The vehicle to fly and the planner mode to fly it with."""
    from iterplan_compiler.runtime.planner import PlannerMode

    chosen = PlannerMode(args.planner) if args.planner is not None else None
    if VehicleBackend(args.vehicle) is VehicleBackend.SIM:
        vehicle = _sim_vehicle(args, grid, params, wind, altitude)
        if chosen is None:   # calibrated simulator: the path follower flown on SITL
            chosen = PlannerMode.CARROT if params else PlannerMode.COURSE
        return vehicle, chosen
    from iterplan_compiler.runtime.mavlink import LinkConfig, MavlinkVehicle
    link = LinkConfig(ready_timeout=args.ready_timeout, airspeed=args.airspeed,
                      loiter_radius=args.loiter_radius)
    vehicle = MavlinkVehicle.connect(args.connect, grid.frame, link, progress=progress)
    return vehicle, chosen if chosen is not None else PlannerMode.CARROT


def _print_summary(result: Any, out: Path) -> None:
    s = result.summary
    print(f"{'mission completed' if result.ok else 'mission ended early: ' + result.reason}")
    print(f"  duration {s['duration_s']:.1f} s at {s['speed_mps']:.1f} m/s, distance "
          f"{s['distance_m']:.0f} m, ideal {s['ideal_duration_s']:.1f} s, overhead "
          f"{s['overhead_pct'] if s['overhead_pct'] is not None else 'n/a'} %")
    print(f"  visited {s['arrivals']} cells, {s['photos']} photos, {s['steps']} controller steps, "
          f"compute {s['compute_s']:.3f} s; outputs in {out}")
    print(f"  safe state: {s['safe_state']}", flush=True)


def _sim_vehicle(args: argparse.Namespace, grid: Any, params: dict[str, float],
                 wind: tuple[float, float], altitude: float) -> Any:
    from iterplan_compiler.runtime.sim import SimParams, SimVehicle

    kw: dict[str, float] = {"seed": args.seed, "wind_east": wind[0], "wind_north": wind[1]}
    if args.airspeed:
        kw["airspeed"] = args.airspeed
    if args.loiter_radius:
        kw["loiter_radius"] = args.loiter_radius
    sp = SimParams.from_arduplane(params, altitude=altitude, **kw) if params \
        else SimParams(**kw)  # type: ignore[arg-type]
    return SimVehicle(sp, home=grid.home, heading=grid.arrival_heading)



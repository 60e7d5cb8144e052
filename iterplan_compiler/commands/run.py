"""``iterc run CONTROLLER.py --map MAP``: fly a generated controller.

The controller module is what ``iterc compile`` writes (a module-level ``TABLE``); the map is a
JSON file (see ``docs/runtime.md``).  The default vehicle is the built-in simulator; ``--vehicle
mavlink --connect tcp:127.0.0.1:5760`` flies an ArduPlane.  Outputs go to ``--out`` (default
``./run-out``): ``track.csv``, ``track.geojson``, ``events.csv``, ``summary.json`` and
``track.png``.  Exit code 0 when the mission completed, 1 when it ended early (safely) or the
input was bad, 2 for usage errors.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

HELP = "run a generated controller on the simulator or a MAVLink vehicle"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("controller", metavar="CONTROLLER.py",
                        help="controller module (from `iterc compile`)")
    parser.add_argument("--map", required=True, help="map file (JSON)")
    parser.add_argument("--vehicle", choices=("sim", "mavlink"), default="sim")
    parser.add_argument("--connect", default="tcp:127.0.0.1:5760",
                        help="MAVLink connection string (with --vehicle mavlink)")
    parser.add_argument("--sorter", choices=("distance", "last", "random"), default="distance")
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
    parser.add_argument("--max-time", type=float, default=4 * 3600.0,
                        help="mission time limit in seconds")
    parser.add_argument("--planner", choices=("course", "carrot"), default=None,
                        help="path following: course hold or fly-to carrots "
                             "(default: course on sim, carrot on mavlink)")
    parser.add_argument("--airspeed", type=float, default=None, help="sim airspeed (m/s)")
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
    from iterplan_compiler.runtime.executor import Executor, RunConfig, load_controller
    from iterplan_compiler.runtime.grid import MapError, load_map
    from iterplan_compiler.runtime.sim import SimParams, SimVehicle

    def err(msg: str) -> int:
        print(f"iterc run: error: {msg}", file=sys.stderr)
        return 1

    try:
        table = load_controller(args.controller)
    except ValueError as exc:
        return err(str(exc))
    try:
        grid = load_map(args.map)
    except MapError as exc:
        return err(f"{args.map}: {exc}")
    until = None
    if args.until is not None:
        until = _parse_until(args.until)
        if until is None:
            print(f"iterc run: --until expects LABEL or LABEL:K (K >= 1), not {args.until!r}",
                  file=sys.stderr)
            return 2
    passes = args.passes if args.passes is not None else (0 if until else 1)
    if passes < 0:
        print("iterc run: --passes must be >= 0", file=sys.stderr)
        return 2
    progress = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))

    vehicle = None
    wind_margin = args.wind_margin or 0.0
    try:
        if args.vehicle == "sim":
            kw = {"seed": args.seed}
            if args.airspeed:
                kw["airspeed"] = args.airspeed
            if args.wind:
                try:
                    e, n = (float(v) for v in args.wind.split(","))
                except ValueError:
                    print("iterc run: --wind expects E,N (m/s)", file=sys.stderr)
                    return 2
                kw.update(wind_east=e, wind_north=n)
                if args.wind_margin is None:
                    wind_margin = math.hypot(e, n)
            vehicle = SimVehicle(SimParams(**kw), home=grid.home, heading=grid.arrival_heading)
            mode = args.planner or "course"
        else:
            from iterplan_compiler.runtime.mavlink import MavlinkError, MavlinkVehicle
            try:
                vehicle = MavlinkVehicle.connect(args.connect, grid.frame, progress=progress)
            except MavlinkError as exc:
                return err(str(exc))
            mode = args.planner or "carrot"
        cfg = RunConfig(sorter=args.sorter, seed=args.seed, ideal_compute=args.ideal_compute,
                        passes=passes, max_time=args.max_time, planner_mode=mode,
                        wind=wind_margin,
                        progress=progress, progress_every=60.0,
                        on_event=_until_hook(*until) if until else None)
        try:
            result = Executor(table, grid, vehicle, config=cfg).run()
        except BindingError as exc:
            return err(str(exc))
    finally:
        if vehicle is not None:
            vehicle.close()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    result.write_track_csv(out / "track.csv")
    result.write_geojson(out / "track.geojson")
    result.write_events_csv(out / "events.csv")
    result.write_summary(out / "summary.json")
    if not args.no_plot:
        result.plot(out / "track.png")
    s = result.summary
    print(f"{'mission completed' if result.ok else 'mission ended early: ' + result.reason}")
    print(f"  duration {s['duration_s']:.1f} s, distance {s['distance_m']:.0f} m, ideal "
          f"{s['ideal_duration_s']:.1f} s, overhead "
          f"{s['overhead_pct'] if s['overhead_pct'] is not None else 'n/a'} %")
    print(f"  visited {s['arrivals']} cells, {s['photos']} photos, {s['steps']} controller steps, "
          f"compute {s['compute_s']:.3f} s; outputs in {out}")
    return 0 if result.ok else 1


def _parse_until(text: str) -> tuple[str, int] | None:
    """``LABEL`` or ``LABEL:K`` -> (canonical label, K), or None if malformed."""
    from iterplan_compiler.runtime.bindings import canon

    label, _, count = text.partition(":")
    label = canon(label)
    if not label:
        return None
    if not count:
        return label, 1
    try:
        k = int(count)
    except ValueError:
        return None
    return (label, k) if k >= 1 else None


def _until_hook(label: str, k: int):
    """Executor ``on_event`` hook: True (end the mission) at the k-th event ``label``."""
    from iterplan_compiler.runtime.bindings import canon

    seen = [0]

    def hook(kind: str, event: str) -> bool:
        if canon(event) != label:
            return False
        seen[0] += 1
        return seen[0] >= k
    return hook

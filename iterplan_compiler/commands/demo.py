"""``iterc demo``: the main job on the bundled default.

Compiles the bundled Fire Patrol spec (front-end -> GR(1) synthesis -> Python controller
module), then flies it on the built-in simulator over the bundled 8x8 map until one full pass of
the iterator is done, printing progress and a mission summary.  Writes the controller module,
the event log, the track (CSV and GeoJSON) and a PNG of the flight into ``./iterplan-demo/``
(or ``--out``).  If a stage of the toolkit is missing in this build, says which and stops with
exit code 1: never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HELP = "compile the bundled Fire Patrol example and fly it in the simulator"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from iterplan_compiler.runtime.sorter import SorterKind

    parser.add_argument("--out", "-o", default="iterplan-demo",
                        help="output directory (default ./iterplan-demo)")
    # the paper's three (the tour plans over sensors the bundled demo map does not mark)
    parser.add_argument("--sorter", default=SorterKind.DISTANCE.value,
                        choices=[k.value for k in SorterKind if k is not SorterKind.TOUR],
                        help="iterator order (default distance, as in the paper)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--passes", type=int, default=1,
                        help="full passes over the map before landing the demo (default 1)")
    parser.add_argument("--quiet", "-q", action="store_true", help="no per-event progress")
    # -- live view (issue 16): --view, --realtime, --view-linger ---------------------------
    from iterplan_compiler.view.cli import add_view_arguments
    add_view_arguments(parser)


def _say(msg: str) -> None:
    print(msg, flush=True)


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler.experiments.catalog import EXAMPLES, example_path
    from iterplan_compiler.experiments.pipeline import StageError, compile_example

    if args.passes < 1:
        print("iterc demo: --passes must be at least 1", file=sys.stderr)
        return 2
    out = Path(args.out)
    ex = EXAMPLES["fire_patrol"]
    spec = example_path(ex.name)
    _say(f"iterplan demo: {ex.title}  (spec {spec.name}, map {ex.map})")
    _say("[1/3] compiling: front-end -> GR(1) synthesis -> Python controller module")
    try:
        module, stats = compile_example(ex.name, out)
    except StageError as exc:
        print(f"iterc demo: stopped: {exc}", file=sys.stderr)
        return 1
    shown = ("game_states", "controller_states", "controller_transitions")
    extra = ", ".join(f"{k.replace('_', ' ')} {stats[k]}" for k in shown if k in stats)
    _say(f"      controller written to {module}" + (f"  ({extra})" if extra else ""))

    _say(f"[2/3] flying it on the built-in simulator (sorter: {args.sorter})")
    try:
        result, grid, view = _fly(module, ex.map or "", args)
    except StageError as exc:
        print(f"iterc demo: stopped: {exc}", file=sys.stderr)
        return 1

    _say("[3/3] mission summary")
    summary = mission_summary(result, grid)
    for k, v in summary.items():
        _say(f"      {k:<24} {v}")
    files = write_outputs(out, result, grid, summary)
    _say("      wrote " + ", ".join(str(f) for f in files))
    from iterplan_compiler.view import cli as view_cli  # live view (issue 16)
    view_cli.finish(view, args, interrupted=result.reason == "interrupted")
    return 0 if summary["all patrol cells visited"] == "yes" else 1


def _fly(module: Path, map_name: str, args):
    from iterplan_compiler.experiments.catalog import examples_dir
    from iterplan_compiler.experiments.flight import fly
    from iterplan_compiler.experiments.missions import LogEvent
    from iterplan_compiler.experiments.pipeline import StageError
    from iterplan_compiler.runtime.grid import MapError
    from iterplan_compiler.runtime.mapfile import load_map
    from iterplan_compiler.runtime.sorter import SorterKind

    map_path = examples_dir() / map_name
    try:
        grid = load_map(map_path)
        map_data = json.loads(map_path.read_text())
    except MapError as exc:
        raise StageError("map", str(exc)) from None
    passes = {"n": 0}

    def stop(e: LogEvent) -> bool:
        passes["n"] += e.label == "n.next"
        return passes["n"] >= args.passes

    def show(e: LogEvent) -> None:
        if args.quiet or e.label not in ("go.next", "arrived", "yes.fire", "take.photo",
                                         "n.next", "takeoff.ended"):
            return
        where = grid.cell_name(e.cell) if e.cell >= 0 else ""
        _say(f"      t={e.t:7.1f}s  {e.label:<11} {where}")

    # -- live view (issue 16) ---------------------------------------------------------------
    from iterplan_compiler.view import cli as view_cli
    from iterplan_compiler.view.live import ViewError
    try:
        view = view_cli.start(args, grid, title="iterc demo: Fire Patrol", open_browser=True)
    except ViewError as exc:
        raise StageError("view", str(exc)) from None
    try:
        result = fly(module, grid, sorter=SorterKind(args.sorter), seed=args.seed, stop=stop,
                     on_event=show, map_data=map_data, max_time=3600.0,
                     observe=view.observe if view else None,
                     realtime=view_cli.realtime(args))
    except BaseException:
        if view is not None:
            view.close()
        raise
    if not result.ok:
        if view is not None:
            view.close()
        raise StageError("flight", f"the mission ended early: {result.reason}")
    return result, grid, view


def mission_summary(result, grid) -> dict:
    """Behaviour of the flight, from its event log, as printable values."""
    log = result.log
    patrol = {int(c) for c in grid.sensors.get("inP", [])}
    fire = {int(c) for c in grid.sensors.get("fire", [])}
    visited = {e.cell for e in log if e.label == "arrived"}
    photos = [e.cell for e in log if e.label == "take.photo"]
    t0 = next((e.t for e in log if e.label == "has.next"), log[0].t if log else 0.0)
    t1 = log[-1].t if log else 0.0
    return {
        "duration (s)": f"{t1 - t0:.1f}",
        "controller steps": result.summary.get("steps", len(log)),
        "locations offered": sum(e.label == "y.next" for e in log),
        "patrol cells visited": f"{len(visited & patrol)}/{len(patrol)}",
        "all patrol cells visited": "yes" if patrol <= visited else "no",
        "cells outside P visited": len(visited - patrol),
        "photos (cells)": ", ".join(grid.cell_name(c) for c in photos) or "none",
        "fires in P": ", ".join(grid.cell_name(c) for c in sorted(fire & patrol)) or "none",
        "photos exactly at fires": "yes" if set(photos) == (fire & patrol) else "no",
    }


def write_outputs(out: Path, result, grid, summary: dict) -> list[Path]:
    """Event log (CSV), track (CSV + GeoJSON), summary (JSON) and a PNG of the flight."""
    out.mkdir(parents=True, exist_ok=True)
    files = []
    log_csv = out / "events.csv"
    log_csv.write_text("t,event,cell\n" + "".join(
        f"{e.t:.2f},{e.label},{grid.cell_name(e.cell) if e.cell >= 0 else ''}\n"
        for e in result.log))
    files.append(log_csv)
    track_csv = out / "track.csv"
    track_csv.write_text("t,x,y\n" + "".join(f"{t:.2f},{x:.2f},{y:.2f}\n"
                                             for t, x, y in result.track))
    files.append(track_csv)
    coords = []
    for _, x, y in result.track:
        lat, lon = grid.to_latlon(x, y)
        coords.append([round(lon, 7), round(lat, 7)])
    gj = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"name": "track"},
         "geometry": {"type": "LineString", "coordinates": coords}}]}
    track_gj = out / "track.geojson"
    track_gj.write_text(json.dumps(gj) + "\n")
    files.append(track_gj)
    summ = out / "summary.json"
    summ.write_text(json.dumps(summary, indent=1, sort_keys=True) + "\n")
    files.append(summ)
    try:
        files.append(plot_flight(out / "flight.png", result, grid))
    except ImportError:
        pass  # matplotlib is a dependency, but a PNG is not worth failing the demo for
    return files


def plot_flight(path: Path, result, grid) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    fig, ax = plt.subplots(figsize=(5.5, 5.5), dpi=110)
    cs = grid.cell_size
    patrol = {int(c) for c in grid.sensors.get("inP", [])}
    fire = {int(c) for c in grid.sensors.get("fire", [])}
    for c in grid.cells:
        c = int(c)
        x, y = grid.centre(c)
        colour = "#ff6a00" if c in fire else ("#ffc27a" if c in patrol else "#f4f4f4")
        ax.add_patch(Rectangle((x - cs / 2, y - cs / 2), cs, cs, facecolor=colour,
                               edgecolor="#bbbbbb", linewidth=0.5))
        ax.text(x, y, grid.cell_name(c), ha="center", va="center", fontsize=5, color="#777777")
    if result.track:
        ax.plot([p[1] for p in result.track], [p[2] for p in result.track], "-", color="#1f4e9c",
                linewidth=1.0, label="flight")
    for e in result.log:
        if e.label == "take.photo" and e.cell >= 0:
            x, y = grid.centre(e.cell)
            ax.plot(x, y, "r*", markersize=10)
    ax.set_aspect("equal")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_title("Fire Patrol: orange = P, dark = fire, * = photo", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)
    return path

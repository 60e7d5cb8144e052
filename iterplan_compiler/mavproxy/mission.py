"""One mission flown from inside MAVProxy: argument parsing, the mission thread, status.

MAVProxy-independent (the MAVProxy module, :mod:`.mavproxy_iterplan`, is a thin shell around
:class:`Mission`): the mission runs the same :class:`~iterplan_compiler.runtime.executor.Executor`
and :class:`~iterplan_compiler.runtime.mavlink.MavlinkVehicle` as ``iterc run --vehicle mavlink``,
over a :class:`~.link.ModuleLink` instead of its own socket, in a background thread so MAVProxy's
loop stays responsive, and writes the same outputs (``track.csv``, ``events.csv``,
``summary.json``, ``commands.csv``, ...).
"""

from __future__ import annotations

import argparse
import threading
import time
import traceback
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from iterplan_compiler.mavproxy.link import ModuleLink
from iterplan_compiler.runtime.planner import PlannerMode
from iterplan_compiler.runtime.runfiles import positive_float
from iterplan_compiler.runtime.sorter import SorterKind
from iterplan_compiler.runtime.vehicle import SafeAction, Start

SAFE_ACTIONS = tuple(a.value for a in SafeAction)
#: ``iterplan run --sorter``: the paper's three (the tour needs the map's sensors up front)
SORTERS = tuple(k.value for k in SorterKind if k is not SorterKind.TOUR)


class UsageError(Exception):
    """A bad ``iterplan`` command line (the message is for the user)."""


class _Parser(argparse.ArgumentParser):
    """argparse that raises instead of calling ``sys.exit`` (fatal inside MAVProxy's loop)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(f"{message}\n{self.format_usage().rstrip()}")

    def exit(self, status: int = 0, message: str | None = None) -> None:  # type: ignore[override]
        raise UsageError(message or self.format_help().rstrip())

    def print_help(self, file: Any = None) -> None:
        raise UsageError(self.format_help().rstrip())


def run_parser() -> argparse.ArgumentParser:
    """``iterplan run``'s options: those of ``iterc run --vehicle mavlink`` that make sense
    inside MAVProxy (the link is MAVProxy's; the map is positional)."""
    p = _Parser(prog="iterplan run", add_help=True,
                description="fly a controller from `iterc compile` over MAVProxy's link")
    p.add_argument("controller", metavar="CONTROLLER.py")
    p.add_argument("map", metavar="MAP.json")
    p.add_argument("--until", default=None, metavar="LABEL[:K]",
                   help="end the mission (successfully) at the K-th event LABEL (default K=1)")
    p.add_argument("--on-end", choices=SAFE_ACTIONS, default=SafeAction.LOITER.value,
                   help="commanded when the mission completes or on `iterplan stop` "
                        "(default loiter over the map centre)")
    p.add_argument("--on-fault", choices=SAFE_ACTIONS, default=SafeAction.RTL.value,
                   help="commanded when the mission ends on a fault (default rtl)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output folder (default: iterplan-YYYYmmdd-HHMMSS in MAVProxy's log "
                        "folder, else the working folder)")
    p.add_argument("--start", choices=[s.value for s in Start], default=Start.AUTO.value)
    p.add_argument("--passes", type=int, default=None,
                   help="stop after this many iterator passes (0: no limit; default 1, "
                        "or 0 with --until)")
    p.add_argument("--sorter", choices=SORTERS, default=SorterKind.DISTANCE.value)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--max-time", type=positive_float, default=4 * 3600.0, metavar="S")
    p.add_argument("--planner", choices=[m.value for m in PlannerMode],
                   default=PlannerMode.CARROT.value)
    p.add_argument("--airspeed", type=positive_float, default=None, metavar="M/S")
    p.add_argument("--turn-radius", type=positive_float, default=None, metavar="M")
    p.add_argument("--loiter-radius", type=positive_float, default=None, metavar="M")
    p.add_argument("--altitude", type=positive_float, default=None, metavar="M")
    p.add_argument("--wind-margin", type=float, default=0.0, metavar="M/S")
    p.add_argument("--ready-timeout", type=positive_float, default=180.0, metavar="S")
    p.add_argument("--plot", action="store_true", help="also write track.png (matplotlib)")
    return p


def parse_run(argv: list[str]) -> argparse.Namespace:
    """Parse ``iterplan run`` arguments; raises :class:`UsageError`."""
    from iterplan_compiler.runtime.runfiles import parse_until

    args = run_parser().parse_args(argv)
    args.until_spec = None
    if args.until is not None:
        args.until_spec = parse_until(args.until)
        if args.until_spec is None:
            raise UsageError(f"--until expects LABEL or LABEL:K (K >= 1), not {args.until!r}")
    if args.passes is not None and args.passes < 0:
        raise UsageError("--passes must be >= 0")
    return args


class Mission:
    """A mission in a background thread (see the module docstring).

    ``get_master``: MAVProxy's current master link; ``say``: prints a line on MAVProxy's
    console; ``stop_event``: MAVProxy's shutdown flag (when it is set the mission ends like on
    ``iterplan stop``); ``on_fly``/``on_done``: called in the mission thread when the vehicle
    is attached and when the mission is over (the module adjusts MAVProxy settings there).
    """

    def __init__(self, args: argparse.Namespace, get_master: Callable[[], Any],
                 say: Callable[[str], None], log_dir: str | Path | None = None,
                 stop_event: threading.Event | None = None,
                 on_fly: Callable[[], None] | None = None,
                 on_done: Callable[[], None] | None = None):
        self.args = args
        self.say = say
        stamp = datetime.now(timezone.utc).strftime("%Y%m%d-%H%M%S")
        self.out = Path(args.out) if args.out else Path(log_dir or ".") / f"iterplan-{stamp}"
        self.link = ModuleLink(get_master, stop_event=stop_event)
        self.on_fly, self.on_done = on_fly, on_done
        self.phase = "starting"
        self.vehicle: Any = None
        self.executor: Any = None
        self.result: Any = None
        self.error: str | None = None
        self.last_line = ""
        self.started = time.monotonic()
        self.ended: float | None = None
        self.thread = threading.Thread(target=self._main, name="iterplan-mission")
        # Not a daemon: when MAVProxy exits, the interpreter waits for the safe end and the
        # outputs (every wait in the runtime is bounded).

    # -- control ------------------------------------------------------------------------------
    def start(self) -> None:
        self.thread.start()

    @property
    def running(self) -> bool:
        return self.thread.is_alive()

    def stop(self) -> bool:
        """End the mission safely (``--on-end``), like Ctrl-C in ``iterc run``; False when a
        stop was already requested (or MAVProxy is shutting down)."""
        return self.link.interrupt()

    def feed(self, msg: Any) -> None:
        self.link.feed(msg)

    # -- reporting ----------------------------------------------------------------------------
    def _progress(self, line: str) -> None:
        self.last_line = line
        self.say(line)

    def status(self) -> list[str]:
        lines = [f"mission {self.phase}: {self.args.controller} on {self.args.map}, "
                 f"outputs {self.out}"]
        v, ex = self.vehicle, self.executor
        if v is not None:
            lines.append(f"  vehicle: mode {v.mode}, {'armed' if v.armed else 'disarmed'}, "
                         f"alt {v.pose().alt:.0f} m, link {'ok' if v.link_ok else 'LOST'}"
                         f"{', hands off' if v.hands_off else ''}; "
                         f"{len(v.command_log)} commands sent")
        if ex is not None:
            c = ex.counts
            t = max(0.0, v.time - ex.t0) if v is not None else 0.0
            lines.append(f"  mission time {t:.0f} s, {c['arrived']} arrivals, "
                         f"{len(ex.photos)} photos, {c['go']} legs, {c['passes']} passes, "
                         f"{c['steps']} controller steps")
        if self.result is not None:
            lines.extend(self._result_lines())
        elif self.error:
            lines.append(f"  error: {self.error}")
        elif self.last_line:
            lines.append(f"  last: {self.last_line}")
        return lines

    def _result_lines(self) -> list[str]:
        r = self.result
        s = r.summary
        oh = s["overhead_pct"]
        return [("mission completed" if r.ok else f"mission ended early: {r.reason}"),
                f"  duration {s['duration_s']:.1f} s at {s['speed_mps']:.1f} m/s, distance "
                f"{s['distance_m']:.0f} m, ideal {s['ideal_duration_s']:.1f} s, overhead "
                f"{oh if oh is not None else 'n/a'} %",
                f"  visited {s['arrivals']} cells, {s['photos']} photos, {s['steps']} controller "
                f"steps, compute {s['compute_s']:.3f} s; outputs in {self.out}",
                f"  safe state: {s['safe_state']}"]

    # -- the mission thread -------------------------------------------------------------------
    def _main(self) -> None:
        try:
            self._fly()
        except Exception as exc:  # noqa: BLE001 - report, never kill MAVProxy
            self.error = f"{type(exc).__name__}: {exc}"
            self.say(f"error: {self.error}")
            for line in traceback.format_exc().rstrip().splitlines():
                self.say(f"  {line}")
        finally:
            self.link.close()
            self.ended = time.monotonic()
            if self.phase not in ("done", "failed"):
                self.phase = "failed"
            if self.on_done is not None:
                try:
                    self.on_done()
                except Exception:  # noqa: BLE001
                    pass

    def _fail(self, msg: str) -> None:
        self.error = msg
        self.phase = "failed"
        self.say(f"error: {msg}")

    def _fly(self) -> None:
        from iterplan_compiler.runtime.bindings import BindingError, canon
        from iterplan_compiler.runtime.executor import Executor, RunConfig, load_controller
        from iterplan_compiler.runtime.grid import MapError
        from iterplan_compiler.runtime.mapfile import load_map
        from iterplan_compiler.runtime.mavlink import LinkConfig, MavlinkVehicle
        from iterplan_compiler.runtime.runfiles import check_out, until_hook, write_outputs
        from iterplan_compiler.runtime.vehicle import VehicleError

        a = self.args
        self.phase = "loading"
        try:
            table = load_controller(a.controller)
        except ValueError as exc:
            return self._fail(str(exc))
        try:
            grid = load_map(a.map)
        except MapError as exc:
            return self._fail(f"{a.map}: {exc}")
        until = a.until_spec
        if until is not None:
            labels = {canon(x) for x in table.controllable | table.uncontrollable}
            if until[0] not in labels:
                return self._fail(f"--until {until[0]}: the controller has no event of that name")
        problem = check_out(self.out, [Path(a.controller), Path(a.map)])
        if problem:
            return self._fail(problem)
        passes = a.passes if a.passes is not None else (0 if until else 1)

        self.phase = "connecting"
        link_cfg = LinkConfig(ready_timeout=a.ready_timeout, airspeed=a.airspeed,
                              loiter_radius=a.loiter_radius)
        vehicle = MavlinkVehicle(self.link, grid.frame, link_cfg, progress=self._progress)
        self.vehicle = vehicle
        result = None
        try:
            try:
                vehicle.start_link("MAVProxy's master link")
                if self.on_fly is not None:
                    self.on_fly()
                cfg = RunConfig(sorter=SorterKind(a.sorter), seed=a.seed, passes=passes,
                                max_time=a.max_time, max_wall=a.max_time,
                                planner_mode=PlannerMode(a.planner), wind=a.wind_margin,
                                altitude=a.altitude if a.altitude is not None else grid.altitude,
                                turn_radius=a.turn_radius, start=Start(a.start),
                                end_action=SafeAction(a.on_end),
                                fault_action=SafeAction(a.on_fault),
                                progress=self._progress, progress_every=60.0,
                                on_event=until_hook(*until) if until else None)
                self.executor = Executor(table, grid, vehicle, config=cfg)
                self.phase = "flying"
                result = self.executor.run()
            except KeyboardInterrupt:
                return self._fail("stopped before the mission started; nothing was commanded")
            except (VehicleError, BindingError) as exc:
                return self._fail(str(exc))
        finally:
            vehicle.close()
        self.phase = "writing outputs"
        write_outputs(result, self.out, vehicle, plot=a.plot)
        self.result = result
        self.phase = "done"
        for line in self._result_lines():
            self.say(line)

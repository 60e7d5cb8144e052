"""``iterc view RUN_DIR``: replay a finished run (``iterc run --out`` folder) in the mission view.

Serves the same page as ``iterc run --view`` with a time slider over the run's track and event
log; ``--map`` (the run's map) adds the grid and sensor layers.  Runs until Ctrl-C (or
``--linger S``).  Needs ``pip install 'iterplan[view]'``.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading

HELP = "show a finished run (iterc run --out folder) in the mission view, with a time slider"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from iterplan_compiler.view.cli import VIEW_HELP

    parser.add_argument("run_dir", metavar="RUN_DIR", help="output folder of `iterc run`")
    parser.add_argument("--map", default=None, help="the run's map (draws the grid and sensors)")
    parser.add_argument("--view", default="127.0.0.1:0", metavar="HOST:PORT",
                        help=VIEW_HELP.replace("a live view of the mission", "the replay"))
    parser.add_argument("--linger", type=float, default=None, metavar="S",
                        help="stop serving after S seconds (default: until Ctrl-C)")


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler.view import missing_dependency

    def err(msg: str) -> int:
        print(f"iterc view: error: {msg}", file=sys.stderr)
        return 1

    problem = missing_dependency()
    if problem:
        return err(problem)
    from iterplan_compiler.view.live import ViewError, parse_address
    from iterplan_compiler.view.replay import ReplayError, load_run
    from iterplan_compiler.view.server import ViewServer
    from iterplan_compiler.view.snapshot import Hub

    grid = None
    if args.map:
        from iterplan_compiler.runtime.grid import MapError
        from iterplan_compiler.runtime.mapfile import load_map
        try:
            grid = load_map(args.map)
        except MapError as exc:
            return err(f"{args.map}: {exc}")
    try:
        data = load_run(args.run_dir, grid)
        host, port = parse_address(args.view)
    except (ReplayError, ViewError) as exc:
        return err(str(exc))
    hub = Hub(data["map"])
    hub.replay = data
    server = ViewServer(hub, host, port)
    try:
        server.start()
    except OSError as exc:
        return err(f"cannot serve on {host}:{port}: {exc.strerror or exc}")
    # SIGTERM / Ctrl-C only *set* an event, handled before the URL is announced: a client
    # that reads the line, uses the page and terminates the viewer gets a clean exit 0
    # wherever the signal lands (raising KeyboardInterrupt from the handler lost two races
    # in CI: before the handler was installed, and between the print and the wait's try)
    stop = threading.Event()
    try:
        old = {s: signal.signal(s, lambda _n, _f: stop.set())
               for s in (signal.SIGTERM, signal.SIGINT)}
    except ValueError:  # not the main thread (an embedding application)
        old = {}
    try:
        print(f"replay view: {server.url}  (Ctrl-C to stop)", flush=True)
        stop.wait(args.linger)
    finally:
        server.stop()
        for sig, h in old.items():
            signal.signal(sig, h)
    return 0

"""The ``--view``, ``--realtime`` and ``--view-linger`` flags of ``iterc run`` and ``iterc demo``
(no web framework imported here)."""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

from iterplan_compiler.runtime.runfiles import non_negative_float, sigterm_as_interrupt

VIEW_HELP = ("serve a live view of the mission at HOST:PORT (default 127.0.0.1 and a free "
             "port, printed at start).  Binding to another address (e.g. 0.0.0.0) shows the "
             "mission to anyone who can reach this machine: the page is read-only, but has no "
             "authentication and no encryption.  Needs pip install 'iterplan[view]'")


def add_view_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("live view")
    g.add_argument("--view", nargs="?", const="127.0.0.1:0", default=None, metavar="HOST:PORT",
                   help=VIEW_HELP)
    g.add_argument("--realtime", nargs="?", const=1.0, type=non_negative_float, default=None,
                   metavar="FACTOR",
                   help="pace the built-in simulator at FACTOR simulated seconds per wall "
                        "second (default 1 with --view, else as fast as possible; 0: as fast "
                        "as possible)")
    g.add_argument("--view-linger", type=non_negative_float, default=None, metavar="S",
                   help="with --view: after the mission, keep serving the final state for S "
                        "seconds (default: until Ctrl-C)")


def realtime(args: argparse.Namespace) -> float | None:
    """The RunConfig.realtime the flags ask for."""
    rt = args.realtime if args.realtime is not None else (1.0 if args.view is not None else None)
    return rt or None


def start(args: argparse.Namespace, grid: Any, title: str = "",
          open_browser: bool = False) -> Any:
    """The LiveView asked for by ``--view`` (None without it); raises ViewError.  With
    ``open_browser`` (``iterc demo``) the page is also opened in the desktop's browser, when
    there is a desktop (not in CI, not with ``ITERPLAN_NO_BROWSER`` set)."""
    if args.view is None:
        return None
    from iterplan_compiler.view.live import LiveView

    view = LiveView(grid, args.view, title=title)
    print(f"live view: {view.url}", flush=True)
    if open_browser and _desktop():
        import webbrowser
        try:
            webbrowser.open(view.url)
        except Exception:  # noqa: BLE001 - the URL is printed anyway
            pass
    return view


def _desktop() -> bool:
    if os.environ.get("CI") or os.environ.get("ITERPLAN_NO_BROWSER"):
        return False
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
                or sys.platform in ("darwin", "win32"))


def finish(view: Any, args: argparse.Namespace, interrupted: bool = False) -> None:
    """After the mission: serve the final state (unless the run was interrupted), then stop."""
    if view is None:
        return
    try:
        if not interrupted and args.view_linger != 0:
            how = ("until Ctrl-C" if args.view_linger is None
                   else f"for {args.view_linger:g} s")
            print(f"live view: final state served at {view.url} {how}", file=sys.stderr,
                  flush=True)
            with sigterm_as_interrupt():
                view.linger(args.view_linger)
    finally:
        view.close()



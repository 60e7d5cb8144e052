"""MAVProxy module ``iterplan``: fly a controller from ``iterc compile`` inside MAVProxy.

Load it with ``module load iterplan`` (the top-level shim ``iterplan.py`` of this project) or
``module load iterplan_compiler.mavproxy.mavproxy_iterplan``; then::

    iterplan run CONTROLLER.py MAP.json [--until LABEL[:K]] [--on-end loiter|rtl|land|none] ...
    iterplan status
    iterplan stop

``run`` starts the mission in a background thread (MAVProxy's loop stays responsive) on
MAVProxy's master link: the same runtime as ``iterc run --vehicle mavlink`` (waits for the
pre-arm checks, arms, takes off — or takes over a flying aircraft — flies the controller and
commands the ``--on-end`` safe state), and writes the same outputs to ``--out``.  ``stop`` ends
the mission safely: the ``--on-end`` action is commanded, as on Ctrl-C in ``iterc run``.
Unloading the module or quitting MAVProxy during a mission does the same.

While a mission flies, MAVProxy's ``streamrate`` setting is -1 (MAVProxy would otherwise re-send
REQUEST_DATA_STREAM every 15 s, which resets the per-message rates the runtime asked for); the
previous value is restored afterwards.  See ``docs/mavproxy.md``.
"""

from __future__ import annotations

import shlex
from typing import Any

from MAVProxy.modules.lib import mp_module

from iterplan_compiler.mavproxy.link import unserialize_sends
from iterplan_compiler.mavproxy.mission import Mission, UsageError, parse_run

USAGE = "usage: iterplan <run CONTROLLER.py MAP.json [options]|status|stop|help>"


class IterplanModule(mp_module.MPModule):
    def __init__(self, mpstate: Any):
        super().__init__(mpstate, "iterplan", "fly iterplan controllers (iterc compile)")
        self.mission: Mission | None = None
        self._saved_streamrate: int | None = None
        self.add_command("iterplan", self.cmd_iterplan, "iterplan mission runtime",
                         ["<run|status|stop|help>", "run (FILENAME) (FILENAME)"])

    # -- output -------------------------------------------------------------------------------
    def _say(self, line: str) -> None:
        try:
            self.mpstate.console.writeln(f"iterplan: {line}")
        except Exception:  # noqa: BLE001 - a console going away must not end a mission
            print(f"iterplan: {line}", flush=True)

    # -- commands -----------------------------------------------------------------------------
    def cmd_iterplan(self, args: list[str]) -> None:
        if not args or args[0] in ("help", "-h", "--help"):
            self._say(USAGE)
            if args[:1] == ["help"]:
                try:
                    parse_run(["--help"])
                except UsageError as exc:
                    for line in str(exc).splitlines():
                        self._say(line)
            return
        cmd, rest = args[0], args[1:]
        if cmd == "run":
            self._run(rest)
        elif cmd == "status":
            if self.mission is None:
                self._say("no mission has been started")
            else:
                for line in self.mission.status():
                    self._say(line)
        elif cmd == "stop":
            m = self.mission
            if m is None or not m.running:
                self._say("no mission is running")
            elif m.stop():
                self._say(f"stopping: the mission ends and commands --on-end {m.args.on_end}")
            else:
                self._say("already stopping")
        else:
            self._say(USAGE)

    def _run(self, argv: list[str]) -> None:
        if self.mission is not None and self.mission.running:
            self._say("a mission is running: `iterplan stop` it first")
            return
        if len(argv) == 1 and " " in argv[0]:        # `iterplan run "a.py b.json --x"`
            argv = shlex.split(argv[0])
        try:
            args = parse_run(argv)
        except UsageError as exc:
            for line in str(exc).splitlines():
                self._say(line)
            return
        if self.master is None:
            self._say("no MAVLink link: add one with `link add` first")
            return
        self.mission = Mission(args, lambda: self.master, self._say, log_dir=self.logdir,
                               stop_event=self.mpstate.status.stop_event,
                               on_fly=self._quiet_streams, on_done=self._restore_streams)
        self._say(f"starting {args.controller} on {args.map}; outputs in {self.mission.out}")
        self.mission.start()

    # -- stream rates (see the module docstring) ----------------------------------------------
    def _quiet_streams(self) -> None:
        if self._saved_streamrate is None:
            self._saved_streamrate = self.settings.streamrate
        self.settings.streamrate = -1

    def _restore_streams(self) -> None:
        if self._saved_streamrate is not None:
            self.settings.streamrate = self._saved_streamrate
            self._saved_streamrate = None

    # -- MAVProxy hooks -----------------------------------------------------------------------
    def mavlink_packet(self, msg: Any) -> None:
        m = self.mission
        if m is not None and m.running:
            m.feed(msg)

    def unload(self) -> None:
        m = self.mission
        if m is not None and m.running:
            self._say("module unloaded during a mission: ending it (--on-end "
                      f"{m.args.on_end}); outputs follow in {m.out}")
            m.stop()
            m.thread.join(4.0)       # MAVProxy waits 5 s for unload(); the thread finishes
        if m is not None and not m.running:
            for mav in m.link.patched.values():
                unserialize_sends(mav)
        self.remove_command("iterplan")
        super().unload()


def init(mpstate: Any) -> IterplanModule:
    """MAVProxy's module entry point."""
    return IterplanModule(mpstate)
